#pragma once
// Configuration structs list their fields once, next to their declaration, in a `visitFields(v, cfg)`
// overload that calls v("name", cfg.field) for every field (nested configuration structs included,
// which have their own overload). Everything that walks a configuration (YAML loading,
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
