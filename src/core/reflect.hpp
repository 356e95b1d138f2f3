#pragma once
// Configuration structs list their fields once, next to their declaration, with
// EDS_FIELDS(Struct, field, ...), which defines a `visitFields(v, cfg)` overload calling
// v("field", cfg.field) for every field (nested configuration structs included, which have their own). Everything that walks a configuration (YAML loading,
// config_used.yaml, command-line overrides, tests) goes through these lists. `fieldCount<T>()` counts
// an aggregate's members, so that a test can tell a field that was added but not listed.
#include <array>
#include <cstddef>
#include <string_view>
#include <utility>

namespace eds {

namespace detail {
struct AnyField {
  template <class T>
  constexpr operator T() const;  // never defined: only used in unevaluated brace-initializations
};
}  // namespace detail

// The number of members of the aggregate T (the largest brace-initializer list it accepts).
template <class T, class... A>
constexpr std::size_t fieldCount() {
  if constexpr (requires { T{A{}..., detail::AnyField{}}; })
    return fieldCount<T, A..., detail::AnyField>();
  else
    return sizeof...(A);
}

// Enumerations used as configuration values name their values with an overload
//   constexpr std::array<std::pair<E, std::string_view>, N> enumNames(E)
// (the argument only selects the overload).
template <class E>
concept NamedEnum = requires(E e) { enumNames(e); };

template <NamedEnum E>
constexpr std::string_view enumName(E value) {
  for (const auto& [v, name] : enumNames(E{}))
    if (v == value) return name;
  return {};
}

}  // namespace eds

// EDS_FIELDS(Struct, a, b, ...) defines visitFields for Struct over its fields a, b, ... (at most 64).
#define EDS_FIELDS(Struct, ...)                    \
  template <class V>                               \
  void visitFields(V&& v, Struct& c) {             \
    EDS_FOR_EACH(EDS_VISIT_ONE_FIELD, __VA_ARGS__) \
  }
#define EDS_VISIT_ONE_FIELD(field) v(#field, c.field);
// A preprocessor loop: EDS_FOR_EACH(m, a, b, c) expands to m(a) m(b) m(c).
#define EDS_PARENS ()
#define EDS_EXPAND(...) EDS_EXPAND3(EDS_EXPAND3(EDS_EXPAND3(EDS_EXPAND3(__VA_ARGS__))))
#define EDS_EXPAND3(...) EDS_EXPAND2(EDS_EXPAND2(EDS_EXPAND2(EDS_EXPAND2(__VA_ARGS__))))
#define EDS_EXPAND2(...) EDS_EXPAND1(EDS_EXPAND1(EDS_EXPAND1(EDS_EXPAND1(__VA_ARGS__))))
#define EDS_EXPAND1(...) __VA_ARGS__
#define EDS_FOR_EACH(macro, ...) __VA_OPT__(EDS_EXPAND(EDS_FOR_EACH_STEP(macro, __VA_ARGS__)))
#define EDS_FOR_EACH_STEP(macro, a, ...) macro(a) __VA_OPT__(EDS_FOR_EACH_AGAIN EDS_PARENS(macro, __VA_ARGS__))
#define EDS_FOR_EACH_AGAIN() EDS_FOR_EACH_STEP
