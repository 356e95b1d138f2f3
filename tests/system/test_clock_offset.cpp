// The events' clock offset from the frames', told by the two trajectories of one run.
#include <gtest/gtest.h>

#include <cmath>

#include "system/clock_offset.hpp"

namespace eds {
namespace {

// A camera turning back and forth (about 60 deg/s at most) and moving, at time t in seconds.
SE3 poseAtSeconds(double t) {
  const Vec3 w(0.3 * std::sin(2.0 * t), 0.5 * std::sin(3.1 * t + 1.0), 0.2 * std::cos(1.7 * t));
  return SE3(SO3::exp(w), Vec3(0.1 * t, 0.05 * std::sin(t), 0.0));
}

// Frames at 20 Hz; event poses every 7 ms whose stamps are `offset_ms` late (the pose of instant t
// stamped t + offset), with a little noise on the rotation.
void trajectories(double offset_ms, Trajectory& frames, Trajectory& events) {
  for (int k = 0; k <= 100; ++k) frames.push_back({fromSeconds(0.05 * k), poseAtSeconds(0.05 * k)});
  for (int k = 0; k <= 700; ++k) {
    const double t = 0.007 * k;
    const SO3 noise = SO3::exp(Vec3(1e-4 * std::sin(37.0 * k), 1e-4 * std::cos(53.0 * k), 0.0));
    const SE3 T = poseAtSeconds(t);
    events.push_back({fromSeconds(t + offset_ms * 1e-3), SE3(T.so3() * noise, T.translation())});
  }
}

TEST(ClockOffset, FindsEventsFiveMillisecondsLate) {
  Trajectory frames, events;
  trajectories(5.0, frames, events);
  const ClockOffsetEstimate e = estimateEventClockOffset(frames, events);
  ASSERT_TRUE(e.valid);
  EXPECT_NEAR(e.offset_ms, 5.0, 0.2);
  EXPECT_TRUE(e.suggestsOffset());
  EXPECT_LT(e.rms_deg_at_best, 0.2 * e.rms_deg_at_zero);
}

TEST(ClockOffset, FindsEventsThreeMillisecondsEarly) {
  Trajectory frames, events;
  trajectories(-3.0, frames, events);
  const ClockOffsetEstimate e = estimateEventClockOffset(frames, events);
  EXPECT_NEAR(e.offset_ms, -3.0, 0.2);
  EXPECT_TRUE(e.suggestsOffset());
}

TEST(ClockOffset, NoOffsetSuggestsNone) {
  Trajectory frames, events;
  trajectories(0.0, frames, events);
  const ClockOffsetEstimate e = estimateEventClockOffset(frames, events);
  ASSERT_TRUE(e.valid);
  EXPECT_LT(std::abs(e.offset_ms), 0.2);
  EXPECT_FALSE(e.suggestsOffset());
}

TEST(ClockOffset, TooShortIsNoEstimate) {
  Trajectory frames, events;
  trajectories(5.0, frames, events);
  frames.resize(5);
  EXPECT_FALSE(estimateEventClockOffset(frames, events).valid);
}

}  // namespace
}  // namespace eds
