// The README's simulated scenes: the room and desk presets along the first 8 s of the real poster_6dof
// hand-held motion (smoothed, sigma = 50 ms), frames at 20 Hz, threshold noise 0.03 and background
// noise, as bench/odometry_table.sh builds them. eds run with the back-end in the tracking thread
// (deterministic); the refined trajectories, as eds run writes them.
#include <gtest/gtest.h>

#include <map>
#include <string>

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

TEST(SimScenes, RoomEventsAndFrames) { runScene("room", Mode::kEvents, 0, {0.133, 0.070}); }
TEST(SimScenes, RoomFramesOnly) { runScene("room", Mode::kFrames, 0, {0.155, 0.062}); }
TEST(SimScenes, DeskEventsAndFrames) { runScene("desk", Mode::kEvents, 0, {0.074, 0.070}); }
TEST(SimScenes, DeskFramesOnly) { runScene("desk", Mode::kFrames, 0, {0.061, 0.061}); }
TEST(SimScenes, DeskEventsAndFramesAt5Hz) { runScene("desk", Mode::kEvents, 5, {0.092, 0.086}); }

}  // namespace
}  // namespace eds
