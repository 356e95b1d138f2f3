// Smoothing of event-rate poses: white jitter in position and orientation shrinks, a motion that is a
// parabola in the window is kept exactly, a curved one is followed closely, and gaps longer than the
// window are not bridged.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "system/trajectory_smoothing.hpp"

namespace eds {
namespace {

// Poses every 4 ms (an event-frame rate) along x(t) = 0.1 sin(2 pi f t), with Gaussian jitter.
Trajectory sine(double f_hz, double jitter, double seconds, std::uint64_t seed, Trajectory* truth) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0, jitter);
  Trajectory noisy;
  for (TimeNs t = 0; t <= fromSeconds(seconds); t += 4'000'000) {
    const double x = 0.1 * std::sin(2 * M_PI * f_hz * toSeconds(t));
    const SO3 R = SO3::exp(Vec3(0.01 * toSeconds(t), 0, 0));
    truth->push_back({t, SE3(R, Vec3(x, 0.02, 1.0))});
    noisy.push_back({t, SE3(R, Vec3(x + n(rng), 0.02 + n(rng), 1.0 + n(rng)))});
  }
  return noisy;
}

double rms(const Trajectory& a, const Trajectory& b) {
  double s = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    s += (a[i].T_w_c.translation() - b[i].T_w_c.translation()).squaredNorm();
  return std::sqrt(s / static_cast<double>(a.size()));
}

TEST(TrajectorySmoothing, JitterShrinksAndTheMotionIsKept) {
  Trajectory truth;
  const Trajectory noisy = sine(2.0, 0.002, 2.0, 3, &truth);  // 2 mm jitter on a 2 Hz, 10 cm motion
  const Trajectory smooth = smoothPoses(noisy, 0.06);         // 31 poses per window
  ASSERT_EQ(smooth.size(), noisy.size());
  const double before = rms(noisy, truth), after = rms(smooth, truth);
  EXPECT_NEAR(before, 0.002 * std::sqrt(3.0), 0.0003);
  EXPECT_LT(after, 0.45 * before) << before << " -> " << after;  // ~1.5/sqrt(31) of the noise
  for (std::size_t i = 0; i < noisy.size(); ++i) {
    EXPECT_EQ(smooth[i].t, noisy[i].t);
    EXPECT_TRUE(smooth[i].T_w_c.so3().matrix().isApprox(noisy[i].T_w_c.so3().matrix(), 1e-15));
  }
  // Without jitter the fit follows even this vigorous motion (1.6 g peaks) to a fraction of a millimetre;
  // a moving average of the same window would be off by x'' h^2 / 6, up to 9 mm.
  Trajectory exact;
  sine(2.0, 0.0, 2.0, 3, &exact);
  EXPECT_LT(rms(smoothPoses(exact, 0.06), exact), 0.0005);
  EXPECT_GT(rms(smoothPoses(exact, 0.06), exact), 1e-6);  // it does change a curved motion
}

// Orientations: a 2 Hz, 5 degree swing about a tilted axis, every 4 ms, with 0.1 degree white jitter
// about random axes (an event frame's own rotation error).
TEST(TrajectorySmoothing, OrientationJitterShrinksAndTheSwingIsKept) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n(0, 0.1 * M_PI / 180 / std::sqrt(3.0));
  const Vec3 axis = Vec3(1, 2, 0.5).normalized();
  Trajectory truth, noisy;
  for (TimeNs t = 0; t <= fromSeconds(2.0); t += 4'000'000) {
    const double angle = 5 * M_PI / 180 * std::sin(2 * M_PI * 2 * toSeconds(t));
    const SE3 T(SO3::exp(angle * axis), Vec3(0, 0, 1));
    truth.push_back({t, T});
    noisy.push_back({t, SE3(T.so3() * SO3::exp(Vec3(n(rng), n(rng), n(rng))), T.translation())});
  }
  const auto rms_deg = [&](const Trajectory& a) {
    double s = 0;
    for (std::size_t i = 0; i < a.size(); ++i)
      s += (truth[i].T_w_c.so3().inverse() * a[i].T_w_c.so3()).log().squaredNorm();
    return std::sqrt(s / static_cast<double>(a.size())) * 180 / M_PI;
  };
  const double before = rms_deg(noisy), after = rms_deg(smoothPoses(noisy, 0.06));
  EXPECT_NEAR(before, 0.1, 0.01);
  EXPECT_LT(after, 0.45 * before) << before << " -> " << after;
  EXPECT_LT(rms_deg(smoothPoses(truth, 0.06)), 0.02);  // the swing itself, 5 deg at 2 Hz, is followed
}

TEST(TrajectorySmoothing, LinesStayExactAndGapsAreNotBridged) {
  Trajectory line;  // a parabola, in fact: constant acceleration along y
  for (TimeNs t = 0; t < 500'000'000; t += 5'000'000) {
    const double s = toSeconds(t);
    line.push_back({t, SE3(SO3(), Vec3(0.3 * s, -0.1 * s + 2.0 * s * s, 2.0))});
  }
  const Trajectory s = smoothPoses(line, 0.05);
  for (std::size_t i = 0; i < line.size(); ++i)
    EXPECT_LT((s[i].T_w_c.translation() - line[i].T_w_c.translation()).norm(), 1e-10);
  // Two poses alone, 1 s from the rest: no neighbour within the window, left as they are.
  Trajectory gap = line;
  gap.push_back({1'500'000'000, SE3(SO3(), Vec3(5, 5, 5))});
  gap.push_back({1'504'000'000, SE3(SO3(), Vec3(-5, 5, 5))});
  const Trajectory g = smoothPoses(gap, 0.05);
  EXPECT_EQ(g.back().T_w_c.translation(), Vec3(-5, 5, 5));
  EXPECT_EQ(smoothPoses(gap, 0.0)[3].T_w_c.translation(), gap[3].T_w_c.translation());
  std::swap(gap[0], gap[1]);
  EXPECT_THROW(smoothPoses(gap, 0.05), std::invalid_argument);
}

// Event poses off the truth by a slowly varying offset (position and rotation), frames exact every
// 50 ms: anchored, the offset is gone but for what its curvature leaves between two frames; a new map
// segment between two frames, or frames too far apart, leave the poses as they were.
TEST(AnchorToFrames, RemovesASlowOffsetBetweenExactFrames) {
  Trajectory truth, events, frames;
  for (TimeNs t = 0; t <= fromSeconds(2.0); t += 4'000'000) {
    const double s = toSeconds(t);
    const SE3 T(SO3::exp(Vec3(0.2 * s, 0.1, 0)), Vec3(0.3 * s, 0.02, 1.0));
    truth.push_back({t, T});
    const SE3 drift(SO3::exp(Vec3(0, 0.004 * std::sin(3 * s), 0)), Vec3(0.003 * std::sin(2 * s), 0.002, 0));
    events.push_back({t, SE3(drift.so3() * T.so3(), T.translation() + drift.translation())});
    if (t % 50'000'000 == 0) frames.push_back({t, T});
  }
  const Trajectory anchored = anchorToFrames(events, frames, fromSeconds(0.5));
  EXPECT_GT(rms(events, truth), 0.002);
  EXPECT_LT(rms(anchored, truth), 1e-5);
  double worst_deg = 0;
  for (std::size_t i = 0; i < truth.size(); ++i)
    worst_deg = std::max(
        worst_deg, (truth[i].T_w_c.so3().inverse() * anchored[i].T_w_c.so3()).log().norm() * 180 / M_PI);
  EXPECT_LT(worst_deg, 0.01);
  // A break at 1.01 s: the poses between the frames at 1.0 and 1.05 s keep their offset.
  const Trajectory broken = anchorToFrames(events, frames, fromSeconds(0.5), {fromSeconds(1.01)});
  for (std::size_t i = 0; i < events.size(); ++i) {
    const bool inside = events[i].t > fromSeconds(1.0) && events[i].t < fromSeconds(1.05);
    const double d = (broken[i].T_w_c.translation() - events[i].T_w_c.translation()).norm();
    if (inside) EXPECT_EQ(d, 0.0) << i;
  }
  EXPECT_GT(rms(broken, truth), 1e-5);
  // Frames farther apart than the limit are no anchors for the poses between them.
  const Trajectory apart = anchorToFrames(events, frames, fromSeconds(0.04));
  for (std::size_t i = 0; i < events.size(); ++i)
    if (events[i].t % 50'000'000 != 0)
      EXPECT_EQ((apart[i].T_w_c.translation() - events[i].T_w_c.translation()).norm(), 0.0) << i;
}

}  // namespace
}  // namespace eds
