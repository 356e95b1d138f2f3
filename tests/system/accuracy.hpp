#pragma once
// The bound every accuracy figure of the README is held to: at most 1.5x the value measured when the
// figure was written (measured + 0.02 cm where that is larger, for the tiniest translations), for
// translation and rotation alike, so that a doubled error or a rotation regression fails.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <string>

#include "eval/ate.hpp"
#include "system/odometry.hpp"

namespace eds::test {

// The rotation figure is the RMSE with the orientations aligned (the best constant rotation,
// `rot_oriented`), not the one through the sim3 alignment: that alignment's rotation is fitted to the
// positions, so on these paths (centimetres of travel against sub-millimetre errors, or a straight slide)
// it turns with the position errors and with the rounding of the build, and a bound on it holds noise.
struct Measured {
  double ate_cm = 0;   // translation RMSE, cm
  double rot_deg = 0;  // rotation RMSE with the orientations aligned, degrees
};

inline double translationBoundCm(double measured_cm) {
  return std::max(1.5 * measured_cm, measured_cm + 0.02);
}

inline std::string hz(double rate) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g Hz", rate);
  return buf;
}

// Prints the result next to the measured figure and checks both bounds.
inline void expectAccuracy(const std::string& what, const eval::AteResult& a, Measured m) {
  std::printf(
      "[ %s ] ATE %.3f cm (measured %.3f), rot %.3f deg with the orientations aligned (measured %.3f; "
      "through the position alignment %.3f), coverage %.1f %%\n",
      what.c_str(), a.trans.rmse * 100, m.ate_cm, a.rot_oriented.rmse, m.rot_deg, a.rot.rmse,
      a.coverage * 100);
  EXPECT_LE(a.trans.rmse * 100, translationBoundCm(m.ate_cm)) << what;
  EXPECT_LE(a.rot_oriented.rmse, 1.5 * m.rot_deg) << what;
}

// A sound run fails nowhere but at a few event frames the lost-track check flags (a fast turn):
// at most 1 % of those tracked.
inline void expectOnlyAFewLostEventFrames(const OdometryResult& r) {
  for (const auto& f : r.failures) EXPECT_EQ(f.reason.rfind("event frame: ", 0), 0u) << f.reason;
  EXPECT_LE(r.failures.size(), r.events_tracked / 100) << "event frames tracked: " << r.events_tracked;
}

}  // namespace eds::test
