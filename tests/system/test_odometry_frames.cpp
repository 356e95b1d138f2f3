// eds run --frames-only end to end: the ESIM plane, a simulated room (map against the true planes) and
// real frames with distortion (ECD slider_depth).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "accuracy.hpp"
#include "core/error.hpp"
#include "eval/ate.hpp"
#include "io/ply.hpp"
#include "sim/motion.hpp"
#include "sim/presets.hpp"
#include "sim_frames.hpp"
#include "system/odometry.hpp"
#include "system/run_stats.hpp"
#include "test_data.hpp"

namespace eds {
namespace {

OdometryConfig framesOnly() {
  OdometryConfig cfg;
  cfg.use_events = false;
  return cfg;
}

eval::AteResult evaluateTrajectory(const Trajectory& traj, const Trajectory& gt, double until_s = 0) {
  eval::EvalConfig ec;
  ec.alignment = eval::Alignment::kSim3;
  if (until_s > 0) ec.window = eval::TimeWindow{0, fromSeconds(until_s)};
  return eval::evaluateAte(traj, gt, ec);
}

eval::AteResult evaluate(const OdometryResult& r, const Trajectory& gt, double until_s = 0) {
  return evaluateTrajectory(r.frames, gt, until_s);
}

// The whole ESIM sequence, poses as tracked and refined (what eds run writes).
TEST(FramesOnly, EsimPlane) {
  EDS_REQUIRE_SHARED(dir, "esim_poster6dof_planar");
  const Sequence seq(dir);
  OdometryConfig cfg = framesOnly();
  cfg.threaded_backend = false;  // deterministic
  const OdometryResult r = runOdometry(seq, cfg);
  ASSERT_TRUE(r.initialized);
  EXPECT_TRUE(r.failures.empty());
  const eval::AteResult a = evaluate(r, seq.groundTruth());
  const eval::AteResult ar = evaluateTrajectory(r.frames_refined, seq.groundTruth());
  std::printf("[ frames-only esim ] init %.2f s, %zu keyframes\n", toSeconds(r.init_t - r.first_t),
              r.keyframes.size());
  test::expectAccuracy("ESIM, frames only, as tracked", a, {0.096, 0.061});
  test::expectAccuracy("ESIM, frames only, refined", ar, {0.063, 0.036});
  EXPECT_GE(ar.coverage, 0.95);
}

// Rotation from the first to the last pose of the estimate against the ground truth's (degrees).
double rotationDriftDeg(const Trajectory& est, const Trajectory& gt) {
  const SE3 est_rel = est.front().T_w_c.inverse() * est.back().T_w_c;
  const SE3 gt_rel = poseAt(gt, est.front().t).inverse() * poseAt(gt, est.back().t);
  return (est_rel.so3() * gt_rel.so3().inverse()).angle() * 180.0 / M_PI;
}

// Real frames with distortion, back-end in the tracking thread (deterministic). Rotation drift over the
// slide: measured 1.47 deg with DSO's removal rule (the release preset and the compiler's default
// alike), 1.71 when the x86-64-v3 build still fused multiply-adds (this figure moves with rounding); the
// bound takes the larger. The slide is where the window's choice of the keyframe to drop shows (DSO's
// rule keeps a long baseline; dropping the oldest drifted 4.3 deg).
TEST(FramesOnly, SliderDepthRealFramesWithDistortion) {
  EDS_REQUIRE_SHARED(dir, "ecd_slider_depth");
  const Sequence seq(dir);
  const Trajectory gt = seq.groundTruth();
  OdometryConfig cfg = framesOnly();
  cfg.threaded_backend = false;
  const OdometryResult r = runOdometry(seq, cfg);
  ASSERT_TRUE(r.initialized);
  const eval::AteResult a = evaluateTrajectory(r.frames_refined, gt);
  const double drift = rotationDriftDeg(r.frames_refined, gt);
  OdometryConfig oldest = cfg;
  oldest.backend.removal = WindowRemoval::kOldest;
  const double drift_oldest = rotationDriftDeg(runOdometry(seq, oldest).frames_refined, gt);
  std::printf(
      "[ frames-only slider_depth ] init %.2f s, %zu keyframes, ATE %.3f cm, rot %.3f deg, coverage %.1f "
      "%%, rotation drift %.2f deg (dropping the oldest keyframe: %.2f deg)\n",
      toSeconds(r.init_t - r.first_t), r.keyframes.size(), a.trans.rmse * 100, a.rot.rmse, a.coverage * 100,
      drift, drift_oldest);
  test::expectAccuracy("ECD slider_depth, frames only, refined", a, {0.394, 0.568});
  EXPECT_GE(a.coverage, 0.9);
  EXPECT_LE(drift, 1.5 * 1.71);
  EXPECT_GE(drift_oldest, 3.0);
}

// Distance from p to the rectangle of a plane.
double distanceToPlane(const sim::Plane& pl, const Vec3& p) {
  const Vec3 d = p - pl.center;
  const double a = std::clamp(d.dot(pl.u), -pl.size_u / 2, pl.size_u / 2);
  const double b = std::clamp(d.dot(pl.v), -pl.size_v / 2, pl.size_v / 2);
  return (d - a * pl.u - b * pl.v).norm();
}

// The room preset along the first 8 s of the real poster_6dof motion (smoothed,
// σ = 50 ms), frames at 20 Hz.
TEST(FramesOnly, RoomMapLiesOnTheTruePlanes) {
  EDS_REQUIRE_SHARED(traj_file, "trajectories/ecd_poster_6dof_groundtruth.txt");
  const auto dir = test::tempDir("frames_room");
  const sim::Motion motion{
      sim::cutTrajectory(sim::smoothTrajectory(readTum(traj_file), 0.05), 0.0, 8.0, traj_file.string())};
  sim::Scene scene = sim::makePreset("room", motion, 3);
  scene.loadTextures();
  sim::SimConfig sc;
  sc.fps = 20;
  sc.render_hz = 20;                        // frames only: no need to render between them
  sc.events.C_pos = sc.events.C_neg = 5.0;  // (almost) no events
  test::writeSimSequence(dir, scene, motion, sc);
  std::filesystem::remove(dir / "events.txt");  // a frames-only sequence
  const Sequence seq(dir);
  OdometryConfig cfg = framesOnly();
  cfg.threaded_backend = false;  // deterministic
  const OdometryResult r = runOdometry(seq, cfg);
  ASSERT_TRUE(r.initialized);
  const Trajectory gt = seq.groundTruth();
  const eval::AteResult a = evaluate(r, gt);
  std::vector<double> dist, range;
  Vec3 centre = Vec3::Zero();
  for (const StampedPose& p : gt) centre += p.T_w_c.translation() / static_cast<double>(gt.size());
  for (const MapPoint& m : r.map) {
    const Vec3 p = a.transform.apply(m.p_w);
    double best = 1e9;
    for (const sim::Plane& pl : scene.planes) best = std::min(best, distanceToPlane(pl, p));
    dist.push_back(best);
    range.push_back((p - centre).norm());
  }
  ASSERT_FALSE(dist.empty());
  std::nth_element(dist.begin(), dist.begin() + dist.size() / 2, dist.end());
  std::nth_element(range.begin(), range.begin() + range.size() / 2, range.end());
  const double med = dist[dist.size() / 2], depth = range[range.size() / 2];
  std::printf(
      "[ frames-only room 8 s ] ATE %.3f cm, coverage %.1f %%, %zu map points, median distance to the "
      "planes %.2f cm = %.2f %% of the median depth %.2f m\n",
      a.trans.rmse * 100, a.coverage * 100, r.map.size(), med * 100, med / depth * 100, depth);
  EXPECT_GE(r.map.size(), 5000u);
  EXPECT_LE(med, 0.02 * depth);
  EXPECT_GE(a.coverage, 0.9);
  test::expectAccuracy("room 8 s, frames only, no events, as tracked", a, {0.255, 0.065});
  // The refined trajectory (each pose through its keyframe's final pose): the back-end's later
  // refinement of the keyframes shows mostly in the rotation (here 0.065 -> 0.043 deg with the
  // orientations aligned).
  ASSERT_EQ(r.frames_refined.size(), r.frames.size());
  const eval::AteResult ar = evaluateTrajectory(r.frames_refined, gt);
  std::printf("[ frames-only room 8 s ] refined: ATE %.3f cm, rot %.3f deg (as tracked: %.3f deg)\n",
              ar.trans.rmse * 100, ar.rot_oriented.rmse, a.rot_oriented.rmse);
  EXPECT_LT(ar.rot_oriented.rmse, 0.9 * a.rot_oriented.rmse);
  test::expectAccuracy("room 8 s, frames only, no events, refined", ar, {0.174, 0.043});
  // What eds run writes: the map as PLY, read back; the refined trajectory as the main file.
  writeOdometryOutputs(dir / "out", r, cfg);
  EXPECT_EQ(readPly(dir / "out" / "map.ply").xyz.size(), r.map.size());
  const Trajectory written = readTum(dir / "out" / "trajectory_frames.txt");
  const Trajectory live = readTum(dir / "out" / "trajectory_frames_live.txt");
  ASSERT_EQ(written.size(), r.frames.size());
  ASSERT_EQ(live.size(), r.frames.size());
  const std::size_t mid = written.size() / 2;
  EXPECT_LT((written[mid].T_w_c.translation() - r.frames_refined[mid].T_w_c.translation()).norm(), 1e-6);
  EXPECT_LT((live[mid].T_w_c.translation() - r.frames[mid].T_w_c.translation()).norm(), 1e-6);
  std::filesystem::remove_all(dir);
}

TEST(FramesOnly, FrameRateSelectionAndBadArguments) {
  std::vector<FrameRef> frames;
  for (int i = 0; i < 100; ++i) frames.push_back({fromSeconds(0.04 * i), "f.png"});  // 25 Hz, 4 s
  EXPECT_EQ(selectFrames(frames, 0, 0, 0).size(), 100u);
  const auto five = selectFrames(frames, 0, 0, 5.0);
  ASSERT_EQ(five.size(), 21u);  // 0, 0.2, ..., 4.0 s (the last is nearest 3.96 s)
  EXPECT_EQ(five[1], 5u);       // 0.2 s
  EXPECT_EQ(selectFrames(frames, 1.0, 1.0, 0).size(), 26u);  // [1, 2] s inclusive
  EXPECT_TRUE(selectFrames(frames, 10.0, 0, 0).empty());
  EDS_REQUIRE_SHARED(dir, "ecd_slider_depth");
  const Sequence seq(dir);
  OdometryConfig cfg = framesOnly();
  cfg.frame_rate = -1;
  EXPECT_THROW(runOdometry(seq, cfg), std::invalid_argument);
  cfg = framesOnly();
  cfg.start_s = 100;
  EXPECT_THROW(runOdometry(seq, cfg), InputError);
  cfg = framesOnly();
  cfg.backend.window = 1;
  EXPECT_THROW(runOdometry(seq, cfg), std::invalid_argument);
}

TEST(FramesOnly, ProgressGoesForwardToTheEnd) {
  EDS_REQUIRE_SHARED(dir, "ecd_slider_depth");
  const Sequence seq(dir);
  OdometryConfig cfg = framesOnly();
  cfg.duration_s = 1.0;
  std::vector<std::pair<double, double>> calls;
  runOdometry(seq, cfg, [&](double done, double total) { calls.emplace_back(done, total); });
  ASSERT_GE(calls.size(), 5u);  // every 0.1 s of the sequence's 1 s, and the end
  for (std::size_t i = 1; i < calls.size(); ++i) {
    EXPECT_GE(calls[i].first, calls[i - 1].first);
    EXPECT_EQ(calls[i].second, calls[0].second);
  }
  EXPECT_NEAR(calls[0].second, 1.0, 0.05);  // the frames' span within the requested second
  EXPECT_EQ(calls.back().first, calls.back().second);
}

}  // namespace
}  // namespace eds
