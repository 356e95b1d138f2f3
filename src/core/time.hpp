#pragma once
// Timestamps are int64 nanoseconds everywhere inside eds. ECD stores seconds with 9 decimals and DSEC
// stores microseconds with a large offset (~1.5e9 s as µs): both fit in int64 ns exactly (±292 years),
// whereas a double of 1.5e9 s resolves only ~0.24 µs.
#include <cmath>
#include <cstdint>

namespace eds {

using TimeNs = std::int64_t;

constexpr TimeNs kNsPerSec = 1'000'000'000;

inline double toSeconds(TimeNs t) { return static_cast<double>(t) * 1e-9; }
inline TimeNs fromSeconds(double s) { return static_cast<TimeNs>(std::llround(s * 1e9)); }

}  // namespace eds
