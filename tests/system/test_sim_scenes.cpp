// The README's simulated scenes: the room and desk presets along the first 8 s of the real poster_6dof
// hand-held motion (smoothed, sigma = 50 ms), frames at 20 Hz, threshold noise 0.03 and background
// noise, as bench/odometry_table.sh builds them. eds run with the back-end in the tracking thread
// (deterministic); the refined trajectories, as eds run writes them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "accuracy.hpp"
#include "io/trajectory_io.hpp"
#include "sim/motion.hpp"
#include "sim/presets.hpp"
#include "sim_frames.hpp"
#include "system/odometry.hpp"
#include "test_data.hpp"

namespace eds {
namespace {

// The preset's sequence, simulated once per test program.
std::filesystem::path sceneSequence(const std::string& preset, const std::filesystem::path& traj_file) {
  static std::map<std::string, std::filesystem::path> done;
  if (auto it = done.find(preset); it != done.end()) return it->second;
  const auto dir = test::tempDir("scene_" + preset);
  const sim::Motion motion{
      sim::cutTrajectory(sim::smoothTrajectory(readTum(traj_file), 0.05), 0.0, 8.0, traj_file.string())};
  sim::Scene scene = sim::makePreset(preset, motion, 1);
  scene.loadTextures();
  test::writeSimSequence(dir, scene, motion, test::noisySimConfig(1));
  return done[preset] = dir;
}

// The preset (scene seed `seed`) along seconds [t_start, t_start + duration_s) of a real motion,
// smoothed as the low-frame-rate test set is (sigma = 40 ms, 10 ms exposure); `supersample` 2 renders as
// `eds simulate` does.
std::filesystem::path windowSequence(const std::string& preset, const std::filesystem::path& traj_file,
                                     double t_start, double duration_s, unsigned seed = 1,
                                     int supersample = 1) {
  using Key = std::tuple<std::string, std::string, double, double, unsigned, int>;
  static std::map<Key, std::filesystem::path> done;
  const Key key{preset, traj_file.stem().string(), t_start, duration_s, seed, supersample};
  if (auto it = done.find(key); it != done.end()) return it->second;
  const auto d = test::tempDir("scene_" + preset + "_" + traj_file.stem().string() + "_" +
                               std::to_string(static_cast<int>(t_start)) + "_" +
                               std::to_string(static_cast<int>(duration_s)) + "_" + std::to_string(seed) +
                               "_" + std::to_string(supersample));
  const sim::Motion motion{sim::cutTrajectory(sim::smoothTrajectory(readTum(traj_file), 0.04), t_start,
                                              duration_s, traj_file.string())};
  sim::Scene scene = sim::makePreset(preset, motion, seed);
  scene.loadTextures();
  sim::SimConfig sc = test::noisySimConfig(seed);
  sc.exposure_s = 0.01;
  sc.render.supersample = supersample;
  test::writeSimSequence(d, scene, motion, sc);
  return done[key] = d;
}

// The preset along the first seconds of the real shapes_rotation motion from 4 s (turns at 20-50 deg/s,
// up to 104 deg/s; translation 3-11 cm/s).
std::filesystem::path turningSequence(const std::string& preset, const std::filesystem::path& traj_file,
                                      double duration_s) {
  return windowSequence(preset, traj_file, 4.0, duration_s);
}

std::filesystem::path turningRoomSequence(const std::filesystem::path& traj_file, double duration_s) {
  return turningSequence("room", traj_file, duration_s);
}

enum class Mode { kEvents, kFrames };

void runScene(const std::string& preset, Mode mode, double frame_rate, test::Measured measured) {
  EDS_REQUIRE_SHARED(traj_file, "trajectories/ecd_poster_6dof_groundtruth.txt");
  const Sequence seq(sceneSequence(preset, traj_file));
  OdometryConfig cfg;
  cfg.use_events = mode == Mode::kEvents;
  cfg.frame_rate = frame_rate;
  cfg.threaded_backend = false;
  const OdometryResult r = runOdometry(seq, cfg);
  ASSERT_TRUE(r.initialized);
  EXPECT_TRUE(r.failures.empty()) << r.failures.size() << " failures, the first: " << r.failures[0].reason;
  const Trajectory& est = mode == Mode::kEvents ? r.events_refined : r.frames_refined;
  const eval::AteResult a = eval::evaluateAte(est, seq.groundTruth(), eval::EvalConfig{});
  test::expectAccuracy(preset + (mode == Mode::kEvents ? ", events + frames" : ", frames only") +
                           (frame_rate > 0 ? ", frames at " + test::hz(frame_rate) : ""),
                       a, measured);
  EXPECT_GE(a.coverage, 0.9);
}

TEST(SimScenes, RoomEventsAndFrames) { runScene("room", Mode::kEvents, 0, {0.114, 0.020}); }
TEST(SimScenes, RoomFramesOnly) { runScene("room", Mode::kFrames, 0, {0.155, 0.019}); }
TEST(SimScenes, DeskEventsAndFrames) { runScene("desk", Mode::kEvents, 0, {0.051, 0.044}); }
TEST(SimScenes, DeskFramesOnly) { runScene("desk", Mode::kFrames, 0, {0.061, 0.055}); }
TEST(SimScenes, DeskEventsAndFramesAt5Hz) { runScene("desk", Mode::kEvents, 5, {0.067, 0.053}); }

struct FirstSeconds {
  double init_after_s = -1;
  eval::AteResult ate;
  // Of the event poses between the bootstrap's last frame and the last frame, the share the pass that
  // tracks each sparse interval again moved in the refined trajectory.
  double merged_share = 0;
};

// One frame a second over the first 4 s of the preset's scene (synchronous back-end): the bootstrap has
// frames 1 s apart and the events carry the camera between them (the event frames since the first
// frame are tracked once the map exists). The event-rate poses of those 4 s.
FirstSeconds runFirstSecondsAtOneFramePerSecond(const std::string& preset,
                                                const std::filesystem::path& traj_file) {
  const Sequence seq(sceneSequence(preset, traj_file));
  OdometryConfig cfg;
  cfg.frame_rate = 1;
  cfg.duration_s = 4;
  cfg.threaded_backend = false;
  const OdometryResult r = runOdometry(seq, cfg);
  if (!r.initialized) return {};
  Trajectory gt = seq.groundTruth();
  std::erase_if(gt, [&](const StampedPose& p) { return p.t > r.first_t + fromSeconds(4.0); });
  const auto between = std::count_if(r.events.begin(), r.events.end(), [&](const StampedPose& p) {
    return p.t > r.init_t && p.t < r.frames.back().t;
  });
  FirstSeconds out{
      toSeconds(r.init_t - r.first_t), eval::evaluateAte(r.events_refined, gt, eval::EvalConfig{}),
      between > 0 ? static_cast<double>(r.events_retracked) / static_cast<double>(between) : 0.0};
  std::printf(
      "[ %s, 4 s, 1 frame/s ] initialized after %.2f s; ATE %.3f cm, rot %.3f deg, coverage %.1f %%; "
      "%zu of %td event poses merged\n",
      preset.c_str(), out.init_after_s, out.ate.trans.rmse * 100, out.ate.rot.rmse, out.ate.coverage * 100,
      r.events_retracked, between);
  return out;
}

// Goal: initialized within 2 s, ATE <= 2 cm, coverage of the 4 s >= 90 %. The rotation RMSE is the sim3
// alignment's on a short, slow start of the path (its mean equals its RMSE): not checked beyond the goal.
TEST(SimScenes, RoomAtOneFramePerSecond) {
  EDS_REQUIRE_SHARED(traj_file, "trajectories/ecd_poster_6dof_groundtruth.txt");
  const FirstSeconds r = runFirstSecondsAtOneFramePerSecond("room", traj_file);
  ASSERT_GE(r.init_after_s, 0) << "never initialized";
  // The essential matrix at 1 s has a median triangulation angle of 1.37 deg: enough for frames a second
  // apart (asking for the video rates' 1.5 deg it waited for the frame at 2 s).
  EXPECT_LE(r.init_after_s, 1.0 + 1e-6);
  // 1.2x rather than the usual 1.5x (the run is deterministic). Measured 0.754 cm (0.320 initialized
  // at 2 s).
  EXPECT_LE(r.ate.trans.rmse * 100, 1.2 * 0.754);
  EXPECT_GE(r.ate.coverage, 0.9);
}

// The desk: near objects before a far wall that most corners lie on. RANSAC's essential matrix at 1 s
// kept 30 of its 194 inliers in front of both cameras (never initialized over the 4 s); MAGSAC++ keeps
// them all. The event frames of that first second start from the nearer frame's pose (from the
// frames' interpolation, 2-3 cm off while the camera starts from rest, 74 % coverage). Same goal.
TEST(SimScenes, DeskAtOneFramePerSecond) {
  EDS_REQUIRE_SHARED(traj_file, "trajectories/ecd_poster_6dof_groundtruth.txt");
  const FirstSeconds r = runFirstSecondsAtOneFramePerSecond("desk", traj_file);
  ASSERT_GE(r.init_after_s, 0) << "never initialized";
  EXPECT_LE(r.init_after_s, 2.0 + 1e-6);
  EXPECT_LE(r.ate.trans.rmse * 100, 2.0);
  EXPECT_GE(r.ate.coverage, 0.9);
  // Both intervals after the bootstrap are tracked again from their start (measured 148 of 152 poses
  // merged; from 0.2 s into each interval, or the first interval left out, at most 80 %).
  EXPECT_GE(r.merged_share, 0.9);
}

struct FirstMotion {
  bool initialized = false;
  double init_after_s = 0;
  // The first two frames' motion against the truth: rotation error and the angle between the
  // translation directions (deg; NaN without two frames).
  double rot_deg = NAN, dir_deg = NAN;
};

// 3 s of the desk along the fast half of the poster motion (8-11 s, scene seed `seed`) at one frame a
// second, synchronous back-end; the start it makes.
FirstMotion fastDeskStart(const std::filesystem::path& traj_file, unsigned seed, bool from_features) {
  const Sequence seq(windowSequence("desk", traj_file, 8.0, 3.0, seed, 2));
  OdometryConfig cfg;
  cfg.frame_rate = 1;
  cfg.threaded_backend = false;
  cfg.bootstrap.geometric_init.from_features = from_features;
  const OdometryResult r = runOdometry(seq, cfg);
  FirstMotion m{r.initialized, toSeconds(r.init_t - r.first_t)};
  if (!r.initialized || r.frames_refined.size() < 2) return m;
  const Trajectory gt = seq.groundTruth();
  const auto truth = [&](TimeNs t) {  // the nearest sample of the 1 kHz truth
    return std::min_element(gt.begin(), gt.end(),
                            [&](const StampedPose& a, const StampedPose& b) {
                              return std::abs(a.t - t) < std::abs(b.t - t);
                            })
        ->T_w_c;
  };
  const SE3 T_1_0 = r.frames_refined[1].T_w_c.inverse() * r.frames_refined[0].T_w_c;
  const SE3 T_1_0_gt = truth(r.frames_refined[1].t).inverse() * truth(r.frames_refined[0].t);
  m.rot_deg = (T_1_0.so3().inverse() * T_1_0_gt.so3()).log().norm() * 180 / M_PI;
  const double cos_dir = T_1_0.translation().normalized().dot(T_1_0_gt.translation().normalized());
  m.dir_deg = std::acos(std::clamp(cos_dir, -1.0, 1.0)) * 180 / M_PI;
  return m;
}

// One frame a second along the fast half of the poster motion, at the desk (scene seed 4): 30 deg and
// 45 cm between the first two frames, objects 0.6-2 m away. The optical flow keeps a handful of corners
// and the events' pose too few more; the reference's ORB features matched to the frame's, used as the
// tracks, initialize at the first frame after the reference (without them: no initialization in these
// 3 s). Measured: 0.08 deg and 0.08 deg off, parallax 7.9 deg.
TEST(SimScenes, FastDeskAtOneFramePerSecondInitializesFromMatchedFeatures) {
  EDS_REQUIRE_SHARED(traj_file, "trajectories/ecd_poster_6dof_groundtruth.txt");
  EXPECT_FALSE(fastDeskStart(traj_file, 4, false).initialized);
  const FirstMotion m = fastDeskStart(traj_file, 4, true);
  ASSERT_TRUE(m.initialized);
  std::printf(
      "[ desk, poster 8-11 s, seed 4, 1 Hz ] initialized after %.2f s; first motion %.2f deg, direction "
      "%.2f deg off\n",
      m.init_after_s, m.rot_deg, m.dir_deg);
  EXPECT_LE(m.init_after_s, 1.0 + 1e-6);
  EXPECT_LE(m.rot_deg, 1.0);
  EXPECT_LE(m.dir_deg, 5.0);
}

// The same with scene seed 2: the matches' essential matrix at 1 s (124 of 163 inliers, most on the wall)
// takes most of the translation for rotation (median triangulation angle 2.85 deg) and initialized
// a map 30 deg and 108 deg off. Such a low angle from matches is refused; a later start must be right.
TEST(SimScenes, FastDeskAtOneFramePerSecondRefusesMatchesOfLittleParallax) {
  EDS_REQUIRE_SHARED(traj_file, "trajectories/ecd_poster_6dof_groundtruth.txt");
  const FirstMotion m = fastDeskStart(traj_file, 2, true);
  if (!m.initialized) return;
  EXPECT_LE(m.rot_deg, 1.0);
  EXPECT_LE(m.dir_deg, 5.0);
}

struct TurningRoomRun {
  double init_after_s = 0;
  eval::AteResult ate;
};

// The turning room at a low frame rate (synchronous back-end), its event-rate poses evaluated.
TurningRoomRun runTurningRoom(const std::filesystem::path& traj_file, double duration_s, double rate) {
  const Sequence seq(turningRoomSequence(traj_file, duration_s));
  OdometryConfig cfg;
  cfg.frame_rate = rate;
  cfg.threaded_backend = false;
  const OdometryResult r = runOdometry(seq, cfg);
  if (!r.initialized) return {-1, {}};
  TurningRoomRun out{toSeconds(r.init_t - r.first_t),
                     eval::evaluateAte(r.events_refined, seq.groundTruth(), eval::EvalConfig{})};
  std::printf("[ turning room, %.0f s, %s ] initialized after %.2f s; ATE %.3f cm, coverage %.1f %%\n",
              duration_s, test::hz(rate).c_str(), out.init_after_s, out.ate.trans.rmse * 100,
              out.ate.coverage * 100);
  return out;
}

// Two frames a second while the camera mostly turns: the translation gives 1-2.5 px of parallax per
// frame and the turn takes the bootstrap's reference out of view within a second or two, so asking for
// the 8 px of video rates it never initialized (over the whole 8 s of this motion). Goal: initialized
// within 2 s of the first frame, ATE <= 1 cm, coverage >= 90 %.
TEST(SimScenes, TurningRoomAtTwoFramesPerSecondInitializes) {
  EDS_REQUIRE_SHARED(traj_file, "trajectories/ecd_shapes_rotation_groundtruth.txt");
  const TurningRoomRun r = runTurningRoom(traj_file, 3.0, 2);
  ASSERT_GE(r.init_after_s, 0) << "never initialized";
  EXPECT_LE(r.init_after_s, 2.0 + 1e-6);
  EXPECT_LE(r.ate.trans.rmse * 100, 1.0);
  EXPECT_GE(r.ate.coverage, 0.9);
}

// Two frames a second along the fast half of the poster motion, in the room (scene seed 3): the corner
// tracks between the first two frames are too few for the geometric path, and the constant-depth fit of
// the second frame keeps about a third of the points, with a wrong translation. Taken, the run is lost
// (measured 26.1 cm, coverage 80.5 %); refused for its few inliers, the bootstrap restarts on that frame
// and the next pair initializes (0.288 cm, 99.5 %). Goal: ATE <= 1 cm, coverage >= 95 %.
TEST(SimScenes, RoomAtTwoFramesPerSecondRefusesAFirstFitWithFewInliers) {
  EDS_REQUIRE_SHARED(traj_file, "trajectories/ecd_poster_6dof_groundtruth.txt");
  const Sequence seq(windowSequence("room", traj_file, 8.0, 8.0, 3));
  OdometryConfig cfg;
  cfg.frame_rate = 2;
  cfg.threaded_backend = false;
  const OdometryResult r = runOdometry(seq, cfg);
  ASSERT_TRUE(r.initialized);
  const eval::AteResult a = eval::evaluateAte(r.events_refined, seq.groundTruth(), eval::EvalConfig{});
  std::printf(
      "[ room, poster 8-16 s, seed 3, 2 Hz ] initialized after %.2f s; ATE %.3f cm, coverage %.1f %%\n",
      toSeconds(r.init_t - r.first_t), a.trans.rmse * 100, a.coverage * 100);
  EXPECT_LE(a.trans.rmse * 100, 1.0);
  EXPECT_GE(a.coverage, 0.95);
}

// One frame a second while the camera turns back and forth. Frames this far apart may complete the
// bootstrap one frame after its reference (measured 1.0 s; asking for two frames it took frames up to
// 3 s, past the goal of 2 s). The event frames buffered meanwhile are tracked between frames a second
// apart, each from the previous one's pose (from the frames' interpolation, which the swing leaves far
// behind, 39 % of the 4 s had a pose). Goal: ATE <= 2 cm (0.311 measured); coverage (99.7 %) at least 80 %.
TEST(SimScenes, TurningRoomAtOneFramePerSecondTracksTheBootstrapsEvents) {
  EDS_REQUIRE_SHARED(traj_file, "trajectories/ecd_shapes_rotation_groundtruth.txt");
  const TurningRoomRun r = runTurningRoom(traj_file, 4.0, 1);
  ASSERT_GE(r.init_after_s, 0) << "never initialized";
  EXPECT_LE(r.init_after_s, 2.0 + 1e-6);
  EXPECT_LE(r.ate.trans.rmse * 100, 2.0);
  EXPECT_GE(r.ate.coverage, 0.8);
}

// The threaded back-end returns the keyframe that completes the bootstrap optimized, in a world moved
// from the frames' poses: the live events' start and motion prior must move with it. On this 7 s
// version of the turning room the keyframe moves by 1 cm and 1 deg; from the frames' poses the events
// lost the camera at once (event frames with no point in view, then no pose until the frame a second
// later: 64 % coverage of the first 4.5 s).
TEST(SimScenes, TurningRoomAtOneFramePerSecondThreadedStartsTheLiveEventsInTheMovedWorld) {
  EDS_REQUIRE_SHARED(traj_file, "trajectories/ecd_shapes_rotation_groundtruth.txt");
  const Sequence seq(turningRoomSequence(traj_file, 7.0));
  OdometryConfig cfg;
  cfg.frame_rate = 1;
  // The bootstrap waits for the second frame after its reference, as it did when this case was found:
  // done at the first one, the keyframe moves too little for the fault to show.
  cfg.bootstrap.min_frames_sparse = 2;
  // Nor does it refuse a sparse frame for keeping few inliers: with two frames asked for, the turn takes
  // most points out of view by the second, and the bootstrap would start too late for this case.
  cfg.bootstrap.min_inlier_fraction_sparse = 0;
  // Nor does it track its corners again from the events' pose: with them the corner tracks complete it
  // at the first frame.
  cfg.bootstrap.geometric_init.from_events = false;
  cfg.duration_s = 4.5;
  const OdometryResult r = runOdometry(seq, cfg);
  ASSERT_TRUE(r.initialized);
  Trajectory gt = seq.groundTruth();
  std::erase_if(gt, [&](const StampedPose& p) { return p.t > r.first_t + fromSeconds(cfg.duration_s); });
  const eval::AteResult a = eval::evaluateAte(r.events_refined, gt, eval::EvalConfig{});
  std::printf("[ turning room, 4.5 of 7 s, 1 Hz, threaded ] %zu losses; ATE %.3f cm, coverage %.1f %%\n",
              r.losses.size(), a.trans.rmse * 100, a.coverage * 100);
  // The start is what this case is about: no loss in its first two seconds. On some processors (an AMD
  // EPYC) the events lose the swing at 2.1 s until the frame at 3 s (78.6 % coverage), on others not;
  // the fault gave 64 %.
  for (const TrackLoss& loss : r.losses) EXPECT_GT(loss.t_lost - r.first_t, fromSeconds(2.0));
  EXPECT_LE(a.trans.rmse * 100, 2.0);
  EXPECT_GE(a.coverage, 0.75);
}

// A camera that starts covered: the room's frames of the first 0.6 s are dark (refused), and the
// bootstrap restarts (its first reference diverges after frames of almost no parallax) until its
// reference is the frame at 2.6 s. The event frames of the second before that reference are tracked
// backwards from it once the map exists (dropped, as they were, that second had no pose: the camera
// moves 15 cm in it; measured ATE 0.364 cm, coverage 99 %).
TEST(SimScenes, EventsBeforeTheBootstrapsReferenceAreTrackedBackwards) {
  EDS_REQUIRE_SHARED(traj_file, "trajectories/ecd_poster_6dof_groundtruth.txt");
  const auto dir = test::tempDir("scene_room_covered_start");
  const sim::Motion motion{
      sim::cutTrajectory(sim::smoothTrajectory(readTum(traj_file), 0.05), 0.0, 4.0, traj_file.string())};
  sim::Scene scene = sim::makePreset("room", motion, 1);
  scene.loadTextures();
  test::writeSimSequence(dir, scene, motion, test::noisySimConfig(1),
                         {{motion.start(), motion.start() + fromSeconds(0.6), 0.05}});
  const Sequence seq(dir);
  OdometryConfig cfg;
  cfg.threaded_backend = false;
  const OdometryResult r = runOdometry(seq, cfg);
  ASSERT_TRUE(r.initialized);
  ASSERT_FALSE(r.frames.empty());
  const TimeNs t_ref = r.frames.front().t;  // the bootstrap's reference frame
  ASSERT_GE(t_ref - r.first_t, fromSeconds(cfg.buffered_before_reference_s));
  Trajectory gt = seq.groundTruth();
  std::erase_if(gt, [&](const StampedPose& p) {
    return p.t < t_ref - fromSeconds(cfg.buffered_before_reference_s) || p.t >= t_ref;
  });
  const eval::AteResult a = eval::evaluateAte(r.events_refined, gt, eval::EvalConfig{});
  std::printf(
      "[ room, covered for 0.6 s ] reference at %.2f s; the second before it: ATE %.3f cm, "
      "coverage %.1f %%\n",
      toSeconds(t_ref - r.first_t), a.trans.rmse * 100, a.coverage * 100);
  EXPECT_GE(a.coverage, 0.9);
  EXPECT_LE(a.trans.rmse * 100, 0.5);
}

// The turning desk at one frame a second: the event tracker loses the camera in a fast swing near the
// end and the next frame relocalizes it. The event frames since the last pose are kept and, once
// relocalized, tracked backwards from that frame (measured: lost 7.67-8.00 s, 137 poses that cover the
// span; without them it had none).
TEST(SimScenes, TurningDeskAtOneFramePerSecondTracksTheTimeLostBackwards) {
  EDS_REQUIRE_SHARED(traj_file, "trajectories/ecd_shapes_rotation_groundtruth.txt");
  const Sequence seq(turningSequence("desk", traj_file, 8.0));
  OdometryConfig cfg;
  cfg.frame_rate = 1;
  cfg.threaded_backend = false;
  // The loss needs the start of corners tracked without the events: from the events' pose the bootstrap
  // starts geometrically and this desk is not lost (measured: 1.68 cm, 99.7 %).
  cfg.bootstrap.geometric_init.from_events = false;
  // Nor does the event tracker leave out the points that stay outliers: with them left out the loss
  // starts at 7.36 s and its backward poses cover too little of it for this case (89 % of the run).
  cfg.events.persistent_outliers.frames = 0;
  const OdometryResult r = runOdometry(seq, cfg);
  ASSERT_TRUE(r.initialized);
  ASSERT_EQ(r.losses.size(), 1u);
  const TrackLoss& loss = r.losses[0];
  ASSERT_GT(loss.t_recovered, loss.t_lost);
  const eval::AteResult a = eval::evaluateAte(r.events_refined, seq.groundTruth(), eval::EvalConfig{});
  // The poses of the time lost, with their errors in the whole run's alignment.
  std::vector<TimeNs> lost_t;
  double ss = 0;
  for (std::size_t k = 0; k < a.pairs.size(); ++k) {
    const TimeNs t = r.events_refined[a.pairs[k].est].t;
    if (t <= loss.t_lost || t >= loss.t_recovered) continue;
    lost_t.push_back(t);
    ss += a.trans_errors[k] * a.trans_errors[k];
  }
  ASSERT_FALSE(lost_t.empty()) << "no pose in the time lost";
  const double span_s = toSeconds(loss.t_recovered - loss.t_lost);
  const double covered_s = toSeconds(loss.t_recovered - lost_t.front());
  const double lost_rmse_cm = 100 * std::sqrt(ss / static_cast<double>(lost_t.size()));
  std::printf(
      "[ turning desk, 8 s, 1 Hz ] lost %.2f-%.2f s: %zu poses tracked backwards over %.2f s, ATE "
      "%.3f cm; whole run ATE %.3f cm, coverage %.1f %%\n",
      toSeconds(loss.t_lost - r.first_t), toSeconds(loss.t_recovered - r.first_t),
      loss.event_poses_backfilled, covered_s, lost_rmse_cm, a.trans.rmse * 100, a.coverage * 100);
  EXPECT_GE(loss.event_poses_backfilled, lost_t.size());
  EXPECT_GE(covered_s, 0.8 * span_s);
  EXPECT_LE(lost_rmse_cm, 1.0);
  EXPECT_LE(a.trans.rmse * 100, 1.0);
  EXPECT_GE(a.coverage, 0.9);
}

// A fast hand-held desk at one frame a second (scene seed 4): near 5.85 s the event tracker, on the 5 s
// keyframe while the camera turns 26 degrees and moves half a metre, slides into a wrong minimum that
// its correlation does not reveal, and the frame at 6 s aligned from there follows it. Aligned also
// from ORB features matched to the reference, that frame is found, and the event frames since the 5 s
// frame are tracked again backwards from it and merged with the forward ones (measured: ATE 0.163 cm,
// coverage 97.0 %; 0.777 cm since the event tracker leaves out points that stay outliers, whose gain
// over many scenes at one frame a second is an average this desk is not part of).
TEST(SimScenes, DeskAtOneFramePerSecondFindsAFrameTheEventsMissedFromFeatures) {
  EDS_REQUIRE_SHARED(traj_file, "trajectories/ecd_poster_6dof_groundtruth.txt");
  const Sequence seq(windowSequence("desk", traj_file, 0.0, 8.0, 4, 2));
  OdometryConfig cfg;
  cfg.frame_rate = 1;
  cfg.threaded_backend = false;
  const OdometryResult r = runOdometry(seq, cfg);
  ASSERT_TRUE(r.initialized);
  const eval::AteResult a = eval::evaluateAte(r.events_refined, seq.groundTruth(), eval::EvalConfig{});
  std::printf(
      "[ desk seed 4, 8 s, 1 Hz ] %zu frames from features, %zu event poses tracked again; ATE %.3f cm, "
      "coverage %.1f %%\n",
      r.feature_starts, r.events_retracked, a.trans.rmse * 100, a.coverage * 100);
  EXPECT_GE(r.feature_starts, 1u);
  EXPECT_GT(r.events_retracked, 0u);
  EXPECT_LE(a.trans.rmse * 100, 1.2);
  EXPECT_GE(a.coverage, 0.9);
}

}  // namespace
}  // namespace eds
