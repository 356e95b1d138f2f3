// The event tracker on events from the simulator (not from the EGM being tested): a keyframe with true
// depth of a scene ~1 m away, an event frame a few ms later; started 1 deg and 1 cm off, the tracker
// must recover the true relative pose.
#include <gtest/gtest.h>

#include <algorithm>
#include <stdexcept>
#include <vector>

#include "frontend/event_tracker.hpp"
#include "support/sim_event_frame_case.hpp"

namespace eds {
namespace {

// The test's case: keyframe at t = 0, event frame of 30,000 events around 40 ms, C = 0.15.
SimEventFrameCase makeOneEventFrame() { return makeSimEventFrameCase({}); }

TEST(EventTrackerOnSim, RecoversThePoseFromOneDegreeAndOneCentimetreOff) {
  SimEventFrameCase o = makeOneEventFrame();
  ASSERT_GT(o.kf.points.size(), 1000u);
  // 1 degree about a tilted axis and 1 cm off.
  const SE3 offset(SO3::exp(Vec3(0.6, -0.8, 0.0).normalized() * (M_PI / 180.0)), Vec3(0.006, -0.008, 0.0));
  const SimCaseSolution s = trackSimCase(o, offset);
  const TrackResult& res = s.first;
  const double rot_deg = s.rot_err_deg, trans_mm = s.trans_err_mm;
  std::printf("[ tracker on sim ] events %.1f..%.1f ms (%zu total), ", toSeconds(o.ef.t_first) * 1e3,
              toSeconds(o.ef.t_last) * 1e3, o.total_events);
  std::printf("%zu points, correlation %.3f, error %.4f deg, %.3f mm (motion %.2f deg, %.1f mm)\n",
              o.kf.points.size(), s.second.correlation, rot_deg, trans_mm,
              o.T_ef_kf_true.so3().angle() * 180 / M_PI, o.T_ef_kf_true.translation().norm() * 1000);
  EXPECT_TRUE(res.ok) << res.failure;
  EXPECT_LE(rot_deg, 1.5 * 0.0356);
  // Measured 0.82 mm / 0.036 deg at this instant; without the event frame's reversal compensation
  // 2.7 mm (a DVS pixel loses one event at each turn of its brightness, event_frame.hpp). The error
  // varies with the instant: the next test holds the median over 11 instants.
  EXPECT_LT(trans_mm, 1.0);
}

// A warm start (the situation of nearly every event frame: a prediction a fraction of a pixel off, the
// finest level alone) ends once a step gains little, well before the iteration limit; and a solve
// started at its own solution stops at the first step.
TEST(EventTrackerOnSim, AWarmStartConvergesInAFewIterations) {
  const SimEventFrameCase o = makeOneEventFrame();
  EventTracker tracker(o.cam, {});
  tracker.setKeyframe(o.kf);
  SE3 T = SE3(SO3::exp(Vec3(0.6, -0.8, 0.0).normalized() * (0.05 * M_PI / 180.0)), Vec3(0.0003, -0.0004, 0)) *
          o.T_ef_kf_true;
  Vec6 nu = Vec6::Zero();
  const TrackResult warm = tracker.track(o.ef, T, nu, 1);
  const TrackResult again = tracker.track(o.ef, T, nu, 1);
  const double trans_mm = (T.inverse().translation() - o.T_ef_kf_true.inverse().translation()).norm() * 1e3;
  std::printf("[ tracker on sim ] warm start: %d iterations, then %d; error %.3f mm\n", warm.iterations,
              again.iterations, trans_mm);
  ASSERT_TRUE(warm.ok) << warm.failure;
  EXPECT_LE(warm.iterations, EventTrackerConfig{}.max_iterations / 2);
  EXPECT_LE(again.iterations, 2);
  EXPECT_LT(trans_mm, 1.0);
}

// One event frame's pose at C = 0.15 at 11 instants 50 ms apart (bench_tracker_sim_study's table):
// measured median 1.234 mm / 0.0618 deg (1.07 mm from an idealized sensor without hysteresis).
TEST(EventTrackerOnSim, MedianErrorOverElevenInstantsAtCoarseThresholds) {
  const SE3 offset(SO3::exp(Vec3(0.6, -0.8, 0.0).normalized() * (M_PI / 180.0)), Vec3(0.006, -0.008, 0.0));
  std::vector<double> trans_mm, rot_deg;
  for (int k = 0; k <= 10; ++k) {
    SimEventFrameCaseConfig cfg;
    cfg.keyframe_time_s = 0.05 * k;
    const SimCaseSolution s = trackSimCase(makeSimEventFrameCase(cfg), offset);
    EXPECT_TRUE(s.first.ok) << s.first.failure;
    trans_mm.push_back(s.trans_err_mm), rot_deg.push_back(s.rot_err_deg);
  }
  const auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  const double t_med = median(trans_mm), r_med = median(rot_deg);
  std::printf("[ tracker on sim ] C = 0.15, 11 instants: median %.3f mm, %.4f deg\n", t_med, r_med);
  EXPECT_LE(t_med, 1.5 * 1.234);
  EXPECT_LE(r_med, 1.5 * 0.0618);
}

TEST(EventTrackerOnSim, RecoversThePoseToUnderAMillimetreAtEveryInstantWithFineThresholds) {
  // C = 0.05 and event frames of about the same span (90,000 events), at four instants of the motion:
  // measured 0.545 / 0.233 / 0.211 / 0.225 mm and 0.027 / 0.013 / 0.013 / 0.013 deg.
  const SE3 offset(SO3::exp(Vec3(0.6, -0.8, 0.0).normalized() * (M_PI / 180.0)), Vec3(0.006, -0.008, 0.0));
  for (const double t_kf : {0.0, 0.15, 0.3, 0.45}) {
    SimEventFrameCaseConfig cfg;
    cfg.keyframe_time_s = t_kf;
    cfg.contrast = 0.05;
    cfg.num_events = 90000;
    const SimEventFrameCase o = makeSimEventFrameCase(cfg);
    const SimCaseSolution s = trackSimCase(o, offset);
    std::printf("[ tracker on sim ] C = 0.05, keyframe at %.2f s: error %.4f deg, %.3f mm\n", t_kf,
                s.rot_err_deg, s.trans_err_mm);
    EXPECT_TRUE(s.first.ok) << s.first.failure;
    // 1.5x the worst instant's figure.
    EXPECT_LE(s.rot_err_deg, 1.5 * 0.027) << "keyframe at " << t_kf << " s";
    EXPECT_LE(s.trans_err_mm, 1.5 * 0.545) << "keyframe at " << t_kf << " s";
  }
}

// At high event-frame rates the front-end gives the tracker an evenly thinned subset of the keyframe's
// points; the subset has exactly the size asked for, and a third of the points still recovers the pose
// of the first test, less precisely (measured 1.86 mm / 0.095 deg against 0.82 mm / 0.036 deg with all:
// one event frame's error; where the rate thins the points, three times as many event frames share it).
TEST(EventTrackerOnSim, AThirdOfThePointsEvenlyThinnedStillRecoversThePose) {
  const SimEventFrameCase o = makeOneEventFrame();
  const int all = static_cast<int>(o.kf.points.size()), third = all / 3;
  EventTracker tracker(o.cam, {});
  // Spread as the whole set: the share in the image's top half (an event frame 90 rows high) is the same.
  tracker.setKeyframe(o.kf, 0);
  const double top_all = tracker.pointsInView(SE3(), o.cam.width, o.cam.height / 2) / double(all);
  tracker.setKeyframe(o.kf, third);
  EXPECT_EQ(tracker.numPoints(), static_cast<std::size_t>(third));
  EXPECT_NEAR(tracker.pointsInView(SE3(), o.cam.width, o.cam.height / 2) / double(third), top_all, 0.02);
  tracker.setKeyframe(o.kf, 0);
  EXPECT_EQ(tracker.numPoints(), static_cast<std::size_t>(all));
  tracker.setKeyframe(o.kf, 10 * all);
  EXPECT_EQ(tracker.numPoints(), static_cast<std::size_t>(all));
  EXPECT_THROW(tracker.setKeyframe(o.kf, -1), std::invalid_argument);
  const SE3 offset(SO3::exp(Vec3(0.6, -0.8, 0.0).normalized() * (M_PI / 180.0)), Vec3(0.006, -0.008, 0.0));
  const SimCaseSolution s = trackSimCase(o, offset, third);
  std::printf("[ tracker on sim ] %d of %d points: error %.4f deg, %.3f mm\n", third, all, s.rot_err_deg,
              s.trans_err_mm);
  EXPECT_TRUE(s.first.ok) << s.first.failure;
  EXPECT_LE(s.first.points_in_view, third);
  EXPECT_LE(s.rot_err_deg, 1.5 * 0.095);
  EXPECT_LE(s.trans_err_mm, 1.5 * 1.86);
}

double translationErrorMm(const SE3& T, const SE3& T_true) {
  return (T.inverse().translation() - T_true.inverse().translation()).norm() * 1000.0;
}

// A nearer object hides part of the keyframe's view: the events in the left third of the event frame
// come from elsewhere (the frame's own content 120 px to the right). Tracked again and again, as
// consecutive event frames are, the points that land there disagree every time; the persistent-outlier
// rule leaves most of them out and few others, and the pose is then better than with them weighed down
// by the Huber loss alone.
TEST(EventTrackerOnSim, PointsHiddenByANearerObjectAreLeftOutAndFewOthers) {
  SimEventFrameCase o = makeOneEventFrame();
  const EventFrame clean = {o.ef.t, o.ef.t_first, o.ef.t_last, o.ef.delta.clone(), 0};
  constexpr int kHiddenCols = 80, kShift = 120;
  for (int y = 0; y < o.ef.delta.rows; ++y)
    for (int x = 0; x < kHiddenCols; ++x) o.ef.delta.at<float>(y, x) = o.ef.delta.at<float>(y, x + kShift);
  const auto solve = [&](int frames, EventTracker& tracker) {
    tracker.setKeyframe(o.kf);
    tracker.setPersistentOutliers(frames, 2.0);
    SE3 T = o.T_ef_kf_true;
    Vec6 nu = Vec6::Zero();
    for (int k = 0; k < 8; ++k) EXPECT_TRUE(tracker.track(o.ef, T, nu).ok) << "track " << k;
    return T;
  };
  EventTracker with(o.cam, {}), without(o.cam, {});
  const SE3 T_with = solve(3, with), T_without = solve(0, without);
  ASSERT_EQ(with.numPoints(), o.kf.points.size());
  int hidden = 0, hidden_out = 0, clear = 0, clear_out = 0;
  for (std::size_t i = 0; i < o.kf.points.size(); ++i) {
    const KeyframePoint& p = o.kf.points[i];
    const double x = o.cam.project(o.T_ef_kf_true * (o.cam.pinholeRay(p.u, p.v) / p.inv_depth)).x();
    const bool out = with.isPersistentOutlier(i);
    if (x < kHiddenCols - 4) hidden++, hidden_out += out;
    if (x > kHiddenCols + 4) clear++, clear_out += out;
  }
  const double err_with = translationErrorMm(T_with, o.T_ef_kf_true);
  const double err_without = translationErrorMm(T_without, o.T_ef_kf_true);
  std::printf(
      "[ tracker on sim ] hidden third: %d of %d hidden points left out, %d of %d others; error "
      "%.3f mm (%.3f mm without the rule)\n",
      hidden_out, hidden, clear_out, clear, err_with, err_without);
  // Measured: 1060 of 1635 hidden, 122 of ~3300 others; 11.6 mm against 15.2 mm (a third of the view
  // wrong pulls the pose before the rule catches up: the first three tracks weigh every point).
  EXPECT_EQ(without.numPersistentOutliers(), 0);
  EXPECT_GE(hidden_out, hidden / 2);
  EXPECT_LE(clear_out, clear / 20);
  EXPECT_LT(err_with, 0.85 * err_without);
  // Hidden in every other event frame only: the hidden points are outliers every other time, never
  // three times in a row. Measured 263 left out (the pose, pulled by the hidden third, also puts some
  // points off on the clean frames); counted without the rows, 1504.
  EventTracker alternating(o.cam, {});
  alternating.setKeyframe(o.kf);
  alternating.setPersistentOutliers(3, 2.0);
  SE3 T = o.T_ef_kf_true;
  Vec6 nu = Vec6::Zero();
  for (int k = 0; k < 8; ++k) EXPECT_TRUE(alternating.track(k % 2 ? o.ef : clean, T, nu).ok);
  EXPECT_LE(alternating.numPersistentOutliers(), hidden / 4);
  with.setPersistentOutliers(0, 2.0);  // off: every point back
  EXPECT_EQ(with.numPersistentOutliers(), 0);
  EXPECT_THROW(with.setPersistentOutliers(-1, 2.0), std::invalid_argument);
  EXPECT_THROW(with.setPersistentOutliers(3, 0.0), std::invalid_argument);
}

TEST(EventTrackerOnSim, APosePriorWeighsAsItsSigmaSays) {
  // A prior with a huge sigma leaves the events' answer; a tiny one is obeyed; one on translation
  // alone (what the frames' constant-velocity prediction gives between frames) pins the position and
  // leaves the rotation to the events, which must take it well away from the prior's 0.3 degrees
  // (not to zero: with the position held 3 mm off, the rotation that moves the image the same way
  // absorbs part of it, ~0.1 degree at 1 m).
  SimEventFrameCase o = makeOneEventFrame();
  ASSERT_GT(o.kf.points.size(), 1000u);
  const SE3 start =
      SE3(SO3::exp(Vec3(0.6, -0.8, 0.0).normalized() * (M_PI / 180.0)), Vec3(0.006, -0.008, 0.0)) *
      o.T_ef_kf_true;
  // The prior sits 3 mm and 0.3 degrees off the truth.
  PosePrior prior;
  prior.T_ef_kf = SE3(SO3::exp(Vec3(0, 0, 0.3 * M_PI / 180)), Vec3(0.003, 0, 0)) * o.T_ef_kf_true;
  auto solve = [&](const PosePrior* p) {
    EventTracker tracker(o.cam, {});
    tracker.setKeyframe(o.kf);
    SE3 T = start;
    Vec6 nu = Vec6::Zero();
    for (int k = 0; k < 2; ++k) EXPECT_TRUE(tracker.track(o.ef, T, nu, 0, p).ok);
    return T;
  };
  const SE3 T_free = solve(nullptr);
  prior.sigma.setConstant(1e3);
  const SE3 T_loose = solve(&prior);
  prior.sigma.setConstant(1e-7);
  const SE3 T_tight = solve(&prior);
  prior.sigma << 2e-4, 2e-4, 2e-4, 0.1, 0.1, 0.1;  // 0.2 mm at 1 m; 6 degrees
  const SE3 T_trans = solve(&prior);
  auto dist = [](const SE3& a, const SE3& b) { return (a * b.inverse()).log().norm(); };
  EXPECT_LT(dist(T_loose, T_free), 1e-6);
  EXPECT_LT(dist(T_tight, prior.T_ef_kf), 1e-5);
  EXPECT_LT(translationErrorMm(T_trans, prior.T_ef_kf), 0.75);  // a quarter of the 3 mm the events pull
  const double rot_trans = (T_trans * o.T_ef_kf_true.inverse()).so3().angle() * 180 / M_PI;
  std::printf("[ tracker on sim ] translation held 3 mm off: rotation error %.4f deg (prior's: 0.3)\n",
              rot_trans);
  EXPECT_LT(rot_trans, 0.15);
}

}  // namespace
}  // namespace eds
