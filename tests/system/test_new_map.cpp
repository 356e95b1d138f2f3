// A lost track that relocalization cannot recover: the camera is covered for a second (no events,
// black frames) while it turns 60 degrees, so that uncovered it sees another part of the room than
// any keyframe. A new map segment must start with a new bootstrap, the outputs mark it, and each
// segment, aligned on its own, must be accurate.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "eval/ate.hpp"
#include "io/trajectory_io.hpp"
#include "sim/motion.hpp"
#include "sim/presets.hpp"
#include "sim_frames.hpp"
#include "system/odometry.hpp"
#include "test_data.hpp"

namespace eds {
namespace {

// The hand-held motion with every pose from `t_turn_s` on turned by `deg` about the camera's vertical
// axis at that time (the simulator's smoothing makes the jump a fast turn, inside the covered second).
Trajectory turnedAt(const Trajectory& traj, double t_turn_s, double deg) {
  const TimeNs t_turn = traj.front().t + fromSeconds(t_turn_s);
  const auto pivot = std::lower_bound(traj.begin(), traj.end(), t_turn,
                                      [](const StampedPose& p, TimeNs t) { return p.t < t; });
  const SE3 T_w_pivot = pivot->T_w_c;
  const SE3 turn(Quat(Eigen::AngleAxisd(deg * std::numbers::pi / 180.0, Vec3::UnitY())), Vec3::Zero());
  const SE3 T_turn_w = T_w_pivot * turn * T_w_pivot.inverse();  // in the world, about the pivot camera
  Trajectory out = traj;
  for (StampedPose& p : out)
    if (p.t >= t_turn) p.T_w_c = T_turn_w * p.T_w_c;
  return out;
}

std::filesystem::path makeCoveredTurningRoom(const std::filesystem::path& traj_file) {
  const auto dir = test::tempDir("covered_turning_room");
  const Trajectory raw = sim::cutTrajectory(readTum(traj_file), 0.0, 8.0, traj_file.string());
  const sim::Motion motion{sim::smoothTrajectory(turnedAt(raw, 3.5, 60.0), 0.04)};
  sim::Scene scene = sim::makePreset("room", motion, 1);
  scene.loadTextures();
  sim::SimConfig sc = test::noisySimConfig(1);
  sc.exposure_s = 0.01;
  const auto at = [&](double s) { return motion.start() + fromSeconds(s); };
  sim::EventFaults faults;
  faults.gaps = {{at(3.0), at(4.0), 0.0}};
  test::writeSimSequence(dir, scene, motion, sc, {{at(3.0), at(4.0), 0.0}}, faults);
  return dir;
}

const std::filesystem::path& coveredTurningRoom(const std::filesystem::path& traj_file) {
  static const std::filesystem::path dir = makeCoveredTurningRoom(traj_file);
  return dir;
}

TEST(Recovery, ANewMapStartsWhenTheCameraIsUncoveredElsewhere) {
  EDS_REQUIRE_SHARED(traj, "trajectories/ecd_poster_6dof_groundtruth.txt");
  const Sequence seq(coveredTurningRoom(traj));
  OdometryConfig cfg;
  cfg.threaded_backend = false;  // deterministic
  const OdometryResult r = runOdometry(seq, cfg);
  ASSERT_EQ(r.segments.size(), 2u);
  ASSERT_EQ(r.losses.size(), 1u);
  const MapSegment& second = r.segments[1];
  const auto s = [&](TimeNs t) { return toSeconds(t - r.first_t); };
  std::printf(
      "[ covered room, turned 60 deg ] lost at %.3f s, relocalization tried on %d frames, new map "
      "from %.3f s, initialized at %.3f s\n",
      s(r.losses[0].t_lost), r.losses[0].attempts, s(second.t_start), s(second.t_init));
  EXPECT_NEAR(s(r.losses[0].t_lost), 3.0, 0.06);
  // Three frames fail to relocalize, then the bootstrap needs a few frames of parallax.
  EXPECT_LE(s(second.t_start), 4.2);
  ASSERT_GE(second.t_init, 0);
  EXPECT_LE(s(second.t_init), 4.6);
  EXPECT_EQ(r.losses[0].t_recovered, second.t_init);
  EXPECT_EQ(r.losses[0].recovery, "new map (segment 1)");

  // Each segment aligned on its own: the new one as accurate as a clean run, the whole run covered
  // but for the covered second and the new bootstrap.
  const std::vector<std::size_t> starts = indicesFrom(r.events_refined, segmentStartTimes(r));
  const eval::AteResult all = eval::evaluateAte(r.events_refined, seq.groundTruth(), {}, starts);
  ASSERT_EQ(all.segment_transforms.size(), 2u);
  const Trajectory after(r.events_refined.begin() + static_cast<std::ptrdiff_t>(starts[0]),
                         r.events_refined.end());
  const eval::AteResult a = eval::evaluateAte(after, seq.groundTruth(), {});
  std::printf(
      "  both segments: ATE %.3f cm, rot %.3f deg, coverage %.1f %%; the new one: ATE %.3f cm, rot "
      "%.3f deg (max %.3f)\n",
      all.trans.rmse * 100, all.rot.rmse, all.coverage * 100, a.trans.rmse * 100, a.rot.rmse, a.rot.max);
  EXPECT_LE(a.trans.rmse * 100, 0.3);
  EXPECT_LE(a.rot.max, 1.0);
  EXPECT_LE(all.trans.rmse * 100, 0.5);
  EXPECT_GE(all.coverage, 0.8);
  // One alignment over both segments (different world frames and scales) is far worse.
  const eval::AteResult one = eval::evaluateAte(r.events_refined, seq.groundTruth(), {});
  EXPECT_GT(one.trans.rmse, 3 * all.trans.rmse);
}

// What a live user hears through the push API (frames only): the new map is announced before any of
// its poses, and every keyframe announced is a real one, in order.
struct SegmentListener : OdometryListener {
  std::vector<MapSegment> segments;
  std::vector<int> keyframes;
  Trajectory frames;
  std::size_t frames_before_new_map = 0;
  void onNewMapSegment(const MapSegment& s) override {
    segments.push_back(s), frames_before_new_map = frames.size();
  }
  void onKeyframe(const KeyframeUpdate& k) override { keyframes.push_back(k.id); }
  void onFramePose(const StampedPose& p, int) override { frames.push_back(p); }
};

TEST(Recovery, TheListenerHearsOfTheNewMapBeforeItsPoses) {
  EDS_REQUIRE_SHARED(traj, "trajectories/ecd_poster_6dof_groundtruth.txt");
  const Sequence seq(coveredTurningRoom(traj));
  OdometryConfig cfg;
  cfg.threaded_backend = false;
  cfg.use_events = false;
  SegmentListener listener;
  Odometry odo(seq.camera(), cfg, &listener);
  for (std::size_t f = 0; f < seq.frames().size(); ++f) odo.addFrame(seq.frames()[f].t, seq.loadFrame(f));
  const OdometryResult& r = odo.finish();
  ASSERT_EQ(r.segments.size(), 2u);
  ASSERT_EQ(listener.segments.size(), 1u);
  EXPECT_EQ(listener.segments[0].id, 1);
  EXPECT_EQ(listener.segments[0].t_start, r.segments[1].t_start);
  ASSERT_GT(listener.frames_before_new_map, 0u);
  ASSERT_LT(listener.frames_before_new_map, listener.frames.size());
  EXPECT_LT(listener.frames[listener.frames_before_new_map - 1].t, r.segments[1].t_start);
  EXPECT_GE(listener.frames[listener.frames_before_new_map].t, r.segments[1].t_start);
  ASSERT_GE(listener.keyframes.size(), 4u);
  EXPECT_GE(listener.keyframes.front(), 0);
  for (std::size_t k = 1; k < listener.keyframes.size(); ++k)
    EXPECT_GT(listener.keyframes[k], listener.keyframes[k - 1]);
}

// The segment marks survive the trajectory file, and `eds eval` aligns each segment on its own.
TEST(Recovery, SegmentMarksRoundTripThroughTumFiles) {
  Trajectory traj;
  for (int i = 0; i < 9; ++i)
    traj.push_back(
        {fromSeconds(0.1 * i), SE3(Quat::Identity(), Vec3(std::cos(0.5 * i), std::sin(0.5 * i), 0.1 * i))});
  const std::vector<std::size_t> starts = indicesFrom(traj, {fromSeconds(0.3), fromSeconds(0.55)});
  ASSERT_EQ(starts, (std::vector<std::size_t>{3, 6}));
  const auto file = test::tempDir("segment_marks") / "traj.txt";
  writeTum(file, traj, starts);
  std::vector<std::size_t> read_starts;
  const Trajectory back = readTum(file, false, &read_starts);
  EXPECT_EQ(back.size(), traj.size());
  EXPECT_EQ(read_starts, starts);
  // Ground truth: the same path; the estimate's segments each in a frame and scale of their own.
  Trajectory est = traj;
  const double scales[] = {1.0, 3.0, 0.5};
  for (std::size_t i = 0; i < est.size(); ++i) {
    const std::size_t k = (i >= 3) + (i >= 6);
    const SE3 frame(Quat(Eigen::AngleAxisd(0.4 * k, Vec3::UnitZ())), Vec3(1.0 * k, 2.0 * k, 0));
    const SE3 p = frame * traj[i].T_w_c;
    est[i].T_w_c = SE3(p.so3(), p.translation() * scales[k] + Vec3(0, 0.002 * std::sin(3.0 * i), 0));
  }
  const eval::AteResult r = eval::evaluateAte(est, traj, {}, starts);
  EXPECT_EQ(r.segment_transforms.size(), 3u);
  EXPECT_EQ(r.pairs.size(), 9u);
  EXPECT_LT(r.trans.rmse, 0.01);
  EXPECT_GT(eval::evaluateAte(est, traj, {}).trans.rmse, 0.1);
  // The aligned estimate: each segment through its own transform.
  const Trajectory aligned = eval::alignedEstimate(est, r);
  for (std::size_t i = 0; i < aligned.size(); ++i)
    EXPECT_NEAR((aligned[i].T_w_c.translation() - traj[i].T_w_c.translation()).norm(), 0.0, 0.02) << i;
}

}  // namespace
}  // namespace eds
