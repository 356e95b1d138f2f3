// An event frame that cannot be tracked is reported as a failure, and tracking goes on from the next
// keyframe instead of aborting.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <random>

#include "sim/presets.hpp"
#include "sim/writer.hpp"
#include "system/track_only.hpp"
#include "test_data.hpp"

namespace eds {
namespace {

// A simulated room sequence whose events of 0.5-0.6 s are replaced, with probability `fraction`, by
// uniform noise that no prediction can explain.
std::filesystem::path noisySequence(const std::string& name, double fraction) {
  const auto dir = test::tempDir(name);
  const sim::Motion motion(sim::handheldMotion(1.2, 4));
  sim::Scene scene = sim::makePreset("room", motion, 4);
  scene.loadTextures();
  CameraModel cam;
  cam.width = 240, cam.height = 180;
  cam.fx = cam.fy = 200;
  cam.cx = 119.5, cam.cy = 89.5;
  sim::SimConfig cfg;
  cfg.fps = 20;
  {
    sim::EcdWriter writer(dir, false, true);
    sim::Simulator(scene, cam, motion, cfg).run(motion.start(), motion.end(), writer);
    writer.finish();
  }
  sim::writeEcdCalib(dir / "calib.txt", cam);
  sim::writeGroundTruth(dir / "groundtruth.txt", motion, motion.start(), motion.end(),
                        sim::kGroundTruthRateHz);
  {
    std::ifstream in(dir / "events.txt");
    std::ofstream out(dir / "events_noisy.txt");
    std::mt19937 rng(1);
    std::uniform_int_distribution<int> ux(0, 239), uy(0, 179), up(0, 1);
    std::uniform_real_distribution<double> u(0, 1);
    std::string line;
    while (std::getline(in, line)) {
      const double t = std::stod(line);
      if (t >= 0.5 && t < 0.6 && u(rng) < fraction)
        out << line.substr(0, line.find(' ')) << ' ' << ux(rng) << ' ' << uy(rng) << ' ' << up(rng) << '\n';
      else
        out << line << '\n';
    }
  }
  std::filesystem::rename(dir / "events_noisy.txt", dir / "events.txt");
  return dir;
}

TEST(TrackOnly, UntrackableEventsAreReportedAndTrackingResumes) {
  const auto dir = noisySequence("track_fail", 1.0);
  const Sequence seq(dir);
  TrackOnlyConfig tc;
  const TrackOnlyResult r = runTrackOnly(seq, tc);
  ASSERT_FALSE(r.failures.empty());
  for (const auto& f : r.failures) {
    EXPECT_GE(toSeconds(f.t), 0.45) << f.reason;
    EXPECT_LE(toSeconds(f.t), 0.65) << f.reason;
  }
  EXPECT_GT(toSeconds(r.trajectory.back().t), 1.1) << "tracking did not go on after the failures";
  EXPECT_GE(r.keyframes, 2u);
  writeTrackSummary(dir / "summary.json", r, tc);
  std::ifstream js(dir / "summary.json");
  const std::string text((std::istreambuf_iterator<char>(js)), {});
  EXPECT_NE(text.find("\"failures\""), std::string::npos);
  EXPECT_NE(text.find(r.failures.front().reason.substr(0, 20)), std::string::npos);
}

// Four events in five replaced by noise: the correlation sinks but stays above the absolute floor (0.2),
// so only the relative lost-track checks report it (half the events is not enough for any).
TEST(TrackOnly, ASuddenDropIsALostTrack) {
  const auto dir = noisySequence("track_drop", 0.8);
  const Sequence seq(dir);
  TrackOnlyConfig off;
  off.events.lost_track.min_correlation_ratio = 0;
  off.events.lost_track.max_cost_ratio = 0;
  const TrackOnlyResult r_off = runTrackOnly(seq, off);
  const TrackOnlyResult r_on = runTrackOnly(seq, TrackOnlyConfig{});
  std::printf("[ sudden drop ] failures: %zu with the check off, %zu on\n", r_off.failures.size(),
              r_on.failures.size());
  EXPECT_TRUE(r_off.failures.empty());
  ASSERT_FALSE(r_on.failures.empty());
  for (const auto& f : r_on.failures) {
    EXPECT_GE(toSeconds(f.t), 0.45) << f.reason;
    EXPECT_LE(toSeconds(f.t), 0.65) << f.reason;
    EXPECT_NE(f.reason.find("recent median"), std::string::npos) << f.reason;
  }
  EXPECT_GT(toSeconds(r_on.trajectory.back().t), 1.1) << "tracking did not go on after the failures";
  // Each check alone catches it.
  TrackOnlyConfig cost_only;
  cost_only.events.lost_track.min_correlation_ratio = 0;
  const TrackOnlyResult r_cost = runTrackOnly(seq, cost_only);
  ASSERT_FALSE(r_cost.failures.empty());
  EXPECT_EQ(r_cost.failures.front().reason.rfind("cost ", 0), 0u) << r_cost.failures.front().reason;
  TrackOnlyConfig corr_only;
  corr_only.events.lost_track.max_cost_ratio = 0;
  const TrackOnlyResult r_corr = runTrackOnly(seq, corr_only);
  ASSERT_FALSE(r_corr.failures.empty());
  EXPECT_EQ(r_corr.failures.front().reason.rfind("correlation ", 0), 0u) << r_corr.failures.front().reason;
}

}  // namespace
}  // namespace eds
