// The plausibility gate of the event frames buffered during the bootstrap: frames 1 s apart, the
// camera moving 10 cm and turning 16 deg about y between them.
#include <gtest/gtest.h>

#include <cmath>

#include "system/buffered_gate.hpp"

namespace eds {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kMarginT = 0.002, kMarginR = 0.2 * kDeg;

SE3 pose(double x, double yaw_deg) { return SE3::exp((Vec6() << x, 0, 0, 0, yaw_deg * kDeg, 0).finished()); }

Trajectory frames() { return {{0, pose(0, 0)}, {fromSeconds(1.0), pose(0.1, 16)}}; }

bool accepts(TimeNs t, const StampedPose& last, const SE3& T) {
  return BufferedEventGate(frames(), t, last, kMarginT, kMarginR).accepts(T);
}

TEST(BufferedEventGate, TheInterpolationPasses) {
  const Trajectory f = frames();
  const TimeNs t = fromSeconds(0.5);
  const BufferedEventGate gate(f, t, f[0], kMarginT, kMarginR);
  EXPECT_TRUE(gate.accepts(gate.interpolated()));
  ASSERT_NE(gate.before(), nullptr);
  EXPECT_EQ(gate.before()->t, 0);
  EXPECT_EQ(gate.after()->t, fromSeconds(1.0));
  // Half the motion between the frames (8 deg) from the interpolation, plus the margin, and no more.
  EXPECT_TRUE(accepts(t, f[0], gate.interpolated() * pose(0, 7.9)));
  EXPECT_TRUE(accepts(t, f[0], gate.interpolated() * pose(0.045, 0)));
}

// At 0.3 s the camera has swung 13 deg the other way: 17.8 deg from the interpolation, but within
// kMaxSpeedup (4) times the mean speed (16 deg/s) over the 0.3 s from the nearer frame.
TEST(BufferedEventGate, ASwingWithinTheSpeedBoundOfTheNearerFramePasses) {
  const Trajectory f = frames();
  EXPECT_TRUE(accepts(fromSeconds(0.3), f[0], pose(0.01, -13)));
  // At 0.1 s the same swing is beyond that bound (6.4 deg) and beyond half the motion.
  EXPECT_FALSE(accepts(fromSeconds(0.1), f[0], pose(0.01, -13)));
  // Near the second frame the bound is measured from that frame.
  EXPECT_TRUE(accepts(fromSeconds(0.8), f[0], pose(0.1, 16 + 12)));
  EXPECT_FALSE(accepts(fromSeconds(0.8), f[0], pose(0.1, 16 + 14)));
}

// However close to the frames, a pose may not jump from the last accepted one: 20 ms after it, 4 x
// 16 deg/s allows 1.28 deg (plus the margin).
TEST(BufferedEventGate, AJumpFromTheLastAcceptedPoseFails) {
  const StampedPose last{fromSeconds(0.5), pose(0.05, 8)};
  const TimeNs t = fromSeconds(0.52);
  EXPECT_TRUE(accepts(t, last, pose(0.05, 8 + 1.3)));
  EXPECT_FALSE(accepts(t, last, pose(0.05, 8 + 1.6)));
  EXPECT_FALSE(accepts(t, last, pose(0.05 + 0.011, 8)));  // 4 x 0.1 m/s x 0.02 s = 8 mm, plus 2
  // An older last pose is replaced by the frame before t.
  const StampedPose older{fromSeconds(-1.0), pose(0, 0)};
  EXPECT_EQ(BufferedEventGate(frames(), t, older, kMarginT, kMarginR).last().t, 0);
}

// After the last frame there is no motion to scale the bounds by: only the margins around its pose.
TEST(BufferedEventGate, AfterTheLastFrameOnlyTheFirstBoundHolds) {
  const Trajectory f = frames();
  const TimeNs t = fromSeconds(1.2);
  const BufferedEventGate gate(f, t, f[1], kMarginT, kMarginR);
  EXPECT_EQ(gate.before(), nullptr);
  EXPECT_TRUE(gate.accepts(f[1].T_w_c * pose(0, 0.15)));
  EXPECT_FALSE(gate.accepts(f[1].T_w_c * pose(0, 0.25)));
  EXPECT_FALSE(gate.accepts(f[1].T_w_c * pose(0.003, 0)));
}

}  // namespace
}  // namespace eds
