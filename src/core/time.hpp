#pragma once
// Timestamps are int64 nanoseconds everywhere inside eds. ECD stores seconds with 9 decimals and DSEC
// stores microseconds with a large offset (~1.5e9 s as µs): both fit in int64 ns exactly (±292 years),
// whereas a double of 1.5e9 s resolves only ~0.24 µs.
#include <cmath>
#include <climits>
#include <cstdint>

namespace eds {

using TimeNs = std::int64_t;

constexpr TimeNs kNsPerSec = 1'000'000'000;

constexpr TimeNs kNsPerUs = 1'000;

// Whether a time in microseconds (as recordings store it) can be held in ns; readers refuse those
// that cannot (a corrupt field) rather than let the product overflow.
constexpr bool microsecondsFitNs(std::int64_t us) {
  return us >= INT64_MIN / kNsPerUs && us <= INT64_MAX / kNsPerUs;
}

inline double toSeconds(TimeNs t) { return static_cast<double>(t) * 1e-9; }
inline TimeNs fromSeconds(double s) { return static_cast<TimeNs>(std::llround(s * 1e9)); }

}  // namespace eds
