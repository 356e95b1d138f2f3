// The event front-end's reference hand-over: a frame that became a keyframe is tracked against at once
// (provisional reference) while a threaded back-end maps it, and the keyframe the back-end publishes
// later, in a world its optimization moved, takes over without moving the estimate relative to it.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "sim_frames.hpp"
#include "support/sim_event_frame_case.hpp"
#include "system/event_frontend.hpp"

namespace eds {
namespace {

// A textured keyframe at time t (intensity in [0.2, 0.8]) with points on a 3 px grid at inverse depth 0.5.
Keyframe texturedKeyframe(int id, TimeNs t, const SE3& T_w_kf) {
  cv::Mat noise(180, 240, CV_32F);
  cv::RNG rng(static_cast<std::uint64_t>(id) + 1);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 1.0);
  cv::GaussianBlur(noise, noise, cv::Size(0, 0), 2.0);
  cv::normalize(noise, noise, 0.2, 0.8, cv::NORM_MINMAX);
  Keyframe kf;
  kf.id = id, kf.t = t, kf.T_w_kf = T_w_kf, kf.image = noise;
  for (int v = 6; v < 174; v += 3)
    for (int u = 6; u < 234; u += 3) {
      KeyframePoint p;
      p.u = static_cast<float>(u), p.v = static_cast<float>(v), p.inv_depth = 0.5;
      kf.points.push_back(p);
    }
  return kf;
}

double distance(const SE3& a, const SE3& b) { return (a.inverse() * b).log().norm(); }

TEST(EventFrontend, ProvisionalReferenceThenThePublishedKeyframeInAMovedWorld) {
  EventFrontend front(test::simCamera(), EventFrontendConfig{});
  const SE3 T_w_kf0 = SE3::exp((Vec6() << 0.1, 0, 0, 0, 0.02, 0).finished());
  front.setReference(texturedKeyframe(3, fromSeconds(1.0), T_w_kf0), T_w_kf0);
  ASSERT_TRUE(front.hasReference());
  // A frame at 1.2 s, tracked 5 cm and 2 degrees from the keyframe, becomes a keyframe.
  const TimeNs t1 = fromSeconds(1.2);
  const SE3 T_w_f1 = T_w_kf0 * SE3::exp((Vec6() << 0.05, 0.01, 0, 0.035, 0, 0).finished());
  front.correct(t1, T_w_f1);
  const Keyframe f1 = texturedKeyframe(4, t1, T_w_f1);
  front.setProvisionalReference(4, t1, f1.image, T_w_f1, f1.points);
  // Tracked against the frame, composed with it under the id the back-end will give it.
  EXPECT_LT(front.T_ef_kf().log().norm(), 1e-12);
  EXPECT_EQ(front.referenceId(), 4);
  EXPECT_LT(distance(front.T_w_kf(), T_w_f1), 1e-12);
  EXPECT_EQ(front.reference().t, t1);
  // The camera moves on relative to the frame; an older keyframe published meanwhile is not taken.
  const SE3 T_f1_ef = SE3::exp((Vec6() << 0.01, 0, 0.005, 0, 0.01, 0).finished());
  front.restartFrom(T_w_f1 * T_f1_ef);
  front.setReference(texturedKeyframe(2, fromSeconds(0.8), T_w_kf0), T_w_kf0);
  EXPECT_EQ(front.reference().t, t1);
  EXPECT_EQ(front.referenceId(), 4);
  // The frame's keyframe comes back from the bundle adjustment 3 cm and 1 degree away (the world
  // estimate moved): the estimate keeps its pose relative to it.
  const SE3 T_w_kf1 = SE3::exp((Vec6() << 0.03, -0.01, 0.02, 0, 0, 0.017).finished()) * T_w_f1;
  front.setReference(texturedKeyframe(4, t1, T_w_kf1), T_w_kf1);
  EXPECT_EQ(front.referenceId(), 4);
  EXPECT_LT(distance(front.T_w_kf(), T_w_kf1), 1e-12);
  EXPECT_LT(distance(front.T_ef_kf(), T_f1_ef.inverse()), 1e-9);
}

// A front-end on a keyframe at the origin, corrected by a frame at 50 ms.
struct CorrectedOnce {
  EventFrontend front{test::simCamera(), EventFrontendConfig{}};
  const TimeNs t1 = fromSeconds(0.05);
  const SE3 T_w_f1 = SE3::exp((Vec6() << 0.02, 0, 0.01, 0, 0.01, 0).finished());
  CorrectedOnce() {
    front.setReference(texturedKeyframe(0, 0, SE3()), SE3());
    front.correct(t1, T_w_f1);
  }
};

// Published after later frames corrected the estimate (the frames do not wait for the back-end): the
// estimate still keeps its pose relative to the keyframe it was tracked against.
TEST(EventFrontend, ProvisionalReferencePublishedAfterLaterFrames) {
  CorrectedOnce s;
  const Keyframe f1 = texturedKeyframe(1, s.t1, s.T_w_f1);
  s.front.setProvisionalReference(1, s.t1, f1.image, s.T_w_f1, f1.points);
  for (int k = 2; k <= 3; ++k)
    s.front.correct(fromSeconds(0.05 * k),
                    s.T_w_f1 * SE3::exp((Vec6() << 0.01 * k, 0, 0, 0, 0, 0).finished()));
  const SE3 T_f1_ef = SE3::exp((Vec6() << 0.035, 0, 0.002, 0, 0.004, 0).finished());
  s.front.restartFrom(s.T_w_f1 * T_f1_ef);
  const SE3 T_w_kf1 = SE3::exp((Vec6() << -0.02, 0.01, 0.03, 0.01, 0, 0).finished()) * s.T_w_f1;
  s.front.setReference(texturedKeyframe(1, s.t1, T_w_kf1), T_w_kf1);
  EXPECT_EQ(s.front.referenceId(), 1);
  EXPECT_LT(distance(s.front.T_w_kf(), T_w_kf1), 1e-12);
  EXPECT_LT(distance(s.front.T_ef_kf(), T_f1_ef.inverse()), 1e-9);
}

// A keyframe published in the world the frames were tracked in (a synchronous back-end returns the
// keyframe's pose as the frame's) moves nothing.
TEST(EventFrontend, KeyframeAtTheCorrectedFramesPoseKeepsTheEstimate) {
  CorrectedOnce s;
  const SE3 T_f1_ef = SE3::exp((Vec6() << 0.004, 0, 0, 0, 0, 0.002).finished());
  s.front.restartFrom(s.T_w_f1 * T_f1_ef);
  s.front.setReference(texturedKeyframe(1, s.t1, s.T_w_f1), s.T_w_f1);
  EXPECT_EQ(s.front.referenceId(), 1);
  EXPECT_LT(distance(s.front.T_ef_kf(), T_f1_ef.inverse()), 1e-9);
}

// Without a provisional reference (one with too few points is refused), a keyframe made from the last
// corrected frame that comes back in a moved world still keeps the estimate's pose relative to it.
TEST(EventFrontend, CorrectedFramesKeyframeInAMovedWorldWithoutProvisionalReference) {
  CorrectedOnce s;
  const SE3 T_f1_ef = SE3::exp((Vec6() << 0.01, 0.004, 0, 0, 0.003, 0).finished());
  s.front.restartFrom(s.T_w_f1 * T_f1_ef);
  const SE3 T_w_kf1 = SE3::exp((Vec6() << 0.02, -0.01, 0.01, 0, 0.01, 0).finished()) * s.T_w_f1;
  s.front.setReference(texturedKeyframe(1, s.t1, T_w_kf1), T_w_kf1);
  EXPECT_EQ(s.front.referenceId(), 1);
  EXPECT_LT(distance(s.front.T_ef_kf(), T_f1_ef.inverse()), 1e-9);
}

// The first event frame between two frames a second apart starts from the nearer frame's pose: the
// camera 30 ms after frame a has moved 1 degree and 2 mm from it, while the interpolation towards frame
// b (2 m and 90 degrees on) is 6 cm and 2.7 degrees off, outside the tracker's basin.
TEST(EventFrontend, BetweenFramesFarApartStartsFromTheNearerFrame) {
  SimEventFrameCaseConfig cc;
  cc.event_frame_delay_s = 0.03;
  const SimEventFrameCase c = makeSimEventFrameCase(cc);
  EventFrontend front(c.cam, EventFrontendConfig{});
  front.setReference(c.kf, SE3());
  const TimeNs t_a = c.kf.t, t_b = c.kf.t + fromSeconds(1.0);
  front.correct(t_a, SE3());
  const SE3 T_w_b = SE3::exp((Vec6() << 2.0, 0, 0.5, 0, M_PI / 2, 0).finished());
  std::string failure;
  const std::optional<SE3> T_w_ef = front.trackBetween(c.ef, t_a, SE3(), t_b, T_w_b, &failure);
  ASSERT_TRUE(T_w_ef) << failure;
  const SE3 err = T_w_ef->inverse() * c.T_ef_kf_true.inverse();
  std::printf("[ event front-end ] error %.3f deg, %.2f mm\n", err.so3().log().norm() * 180 / M_PI,
              err.translation().norm() * 1e3);
  EXPECT_LT(err.so3().log().norm() * 180 / M_PI, 0.15);
  EXPECT_LT(err.translation().norm(), 0.003);
}

// The event frame moved by dt in time.
EventFrame shifted(EventFrame ef, TimeNs dt) {
  ef.t += dt, ef.t_first += dt, ef.t_last += dt;
  return ef;
}

// The tracker's points per second are bounded while frames come at video rate: a reference set after
// event frames 2 ms apart (500 a second) gets points_per_second / 500 of its points, after event frames
// 20 ms apart points_per_second / 50; with the budget off, or frames 0.5 s apart, all of them.
TEST(EventFrontend, AReferenceAfterFastEventFramesIsThinnedToThePointBudget) {
  const SimEventFrameCase c = makeSimEventFrameCase({});
  const auto pointsAfter = [&](double spacing_s, double budget, double frame_gap_s = 0.05) {
    EventFrontendConfig cfg;
    cfg.point_budget.points_per_second = budget;
    EventFrontend front(c.cam, cfg);
    front.setReference(c.kf, SE3());
    // Two frames, then the event frames (all 1 s later than the case's own times: they must be >= 0).
    const TimeNs t_frame = c.kf.t + fromSeconds(1.0);
    front.correct(t_frame - fromSeconds(frame_gap_s), SE3());
    front.correct(t_frame, SE3());
    const int before = front.numPoints();
    for (int k = 0; k < 20; ++k) front.track(shifted(c.ef, fromSeconds(1.0 + spacing_s * k)), nullptr);
    EXPECT_EQ(front.numPoints(), before) << "thinned before the next reference";
    front.setReference(c.kf, SE3());
    const int thinned = front.numPoints();
    // No usable frame for 0.15 s (the refused one at 0.1 s does not count): the points come back.
    front.correct(t_frame + fromSeconds(0.1), SE3(), false);
    front.track(shifted(c.ef, t_frame + fromSeconds(0.15) - c.ef.t), nullptr);
    EXPECT_EQ(front.numPoints(), before) << "a thinned reference kept past the frames";
    return std::pair{before, thinned};
  };
  const auto [all, fast] = pointsAfter(0.002, 3e5);
  ASSERT_GT(all, 1500);
  EXPECT_EQ(fast, 600);
  EXPECT_EQ(pointsAfter(0.020, 3e5).second, std::min(all, 6000));
  EXPECT_EQ(pointsAfter(0.002, 0).second, all);
  EXPECT_EQ(pointsAfter(0.002, 3e5, 0.5).second, all);
  EventFrontendConfig bad;
  bad.point_budget.points_per_second = -1;
  EXPECT_THROW(EventFrontend(c.cam, bad), std::invalid_argument);
  bad.point_budget = {.points_per_second = 3e5, .max_frame_gap_s = 0};
  EXPECT_THROW(EventFrontend(c.cam, bad), std::invalid_argument);
}

// An event frame after others passed over (load shedding) starts from a prediction several steps
// long: solved coarse-to-fine it comes back from a start 4.7 cm and 0.6 degrees off (about 9 px at the
// plane's 1 m), where the finest level alone, enough for the step after a single event frame, ends
// 5 cm away.
TEST(EventFrontend, AfterEventFramesPassedOverTheSolveGoesCoarseToFine) {
  const SimEventFrameCase c = makeSimEventFrameCase({});
  const SE3 T_w_ef_true = c.T_ef_kf_true.inverse();
  const SE3 offset = SE3::exp((Vec6() << 0.041, -0.022, 0, 0, 0, 0.011).finished());
  const auto errorAfter = [&](std::size_t passed) {
    EventFrontend front(c.cam, EventFrontendConfig{});
    front.setReference(c.kf, SE3());
    front.correct(c.ef.t - fromSeconds(0.01), T_w_ef_true * offset);
    EventFrame ef = c.ef;
    ef.passed_before = passed;
    const std::optional<SE3> T_w_ef = front.track(ef, nullptr);
    const double err = T_w_ef ? (T_w_ef->inverse() * T_w_ef_true).translation().norm() : 1.0;
    std::printf("[ event front-end, %zu passed over ] position error %.2f mm\n", passed, err * 1e3);
    return err;
  };
  // From three passed over on (every 4th event frame built), as measured on the rotation room.
  EXPECT_LT(errorAfter(7), 0.002);
  EXPECT_LT(errorAfter(3), 0.002);
  EXPECT_GT(errorAfter(2), 0.005);
  EXPECT_GT(errorAfter(0), 0.005);
}

}  // namespace
}  // namespace eds
