// Frames the system cannot trust: a hand-held desk scene whose frames are dimmed to 5 % from 3 to 4 s (a
// hand over the lens) and blown out x4 from 5 to 5.5 s, the events unaffected; sharp (10 ms exposure)
// and motion-blurred (40 ms). The bad frames must stay out of tracking and the map, each listed as a
// failure with its cause, while the events carry the pose: ATE within 1.5x the clean run's and no
// rotation error above 1 degree (event-rate poses, as eds run writes them).
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

struct Variant {
  double exposure_s;
  bool faults;
};

std::filesystem::path deskSequence(const std::filesystem::path& traj_file, Variant v) {
  const std::string name = "bad_frames_" + std::to_string(static_cast<int>(v.exposure_s * 1000)) +
                           (v.faults ? "ms_faults" : "ms_clean");
  const auto dir = test::tempDir(name);
  const sim::Motion motion{
      sim::cutTrajectory(sim::smoothTrajectory(readTum(traj_file), 0.04), 0.0, 8.0, traj_file.string())};
  sim::Scene scene = sim::makePreset("desk", motion, 1);
  scene.loadTextures();
  sim::SimConfig sc = test::noisySimConfig(1);
  sc.exposure_s = v.exposure_s;
  std::vector<sim::FrameGain> gains;
  const TimeNs t0 = motion.start();
  if (v.faults)
    gains = {{t0 + fromSeconds(3.0), t0 + fromSeconds(4.0), 0.05},
             {t0 + fromSeconds(5.0), t0 + fromSeconds(5.5), 4.0}};
  test::writeSimSequence(dir, scene, motion, sc, gains);
  return dir;
}

eval::AteResult runDesk(Variant v, OdometryResult& r) {
  const Sequence seq(deskSequence(test::sharedDataDir() / "trajectories/ecd_poster_6dof_groundtruth.txt", v));
  OdometryConfig cfg;
  cfg.threaded_backend = false;  // deterministic
  r = runOdometry(seq, cfg);
  EXPECT_TRUE(r.initialized);
  const eval::AteResult a = eval::evaluateAte(r.events_refined, seq.groundTruth(), eval::EvalConfig{});
  std::printf(
      "[ desk, %.0f ms exposure%s ] ATE %.3f cm, rot %.3f deg (max %.3f), coverage %.1f %%, %zu frames "
      "not used, %zu failures\n",
      v.exposure_s * 1000, v.faults ? ", dimmed 3-4 s, x4 5-5.5 s" : "", a.trans.rmse * 100, a.rot.rmse,
      a.rot.max, a.coverage * 100, r.frames_rejected, r.failures.size());
  return a;
}

// `clean`: the same scene's figures without the faults, measured with these settings (docs/experiments.md).
void expectCarriedThrough(Variant v, test::Measured clean) {
  EDS_REQUIRE_SHARED(traj, "trajectories/ecd_poster_6dof_groundtruth.txt");
  OdometryResult r;
  const eval::AteResult a = runDesk(v, r);
  EXPECT_LE(a.trans.rmse * 100, 1.5 * clean.ate_cm);
  EXPECT_LE(a.rot.max, 1.0);
  EXPECT_GE(a.coverage, 0.9);
  // The 20 dimmed and 10 blown-out frames, and nothing else, each failure naming its cause.
  EXPECT_EQ(r.frames_rejected, 30u);
  std::map<std::string, int> causes;
  for (const OdometryFailure& f : r.failures) {
    const double s = toSeconds(f.t - r.first_t);
    const bool dim = s >= 2.99 && s < 4.0, bright = s >= 4.99 && s < 5.5;
    EXPECT_TRUE(dim || bright) << "failure at " << s << " s: " << f.reason;
    causes[f.reason.substr(0, f.reason.find(" ("))] += 1;
  }
  EXPECT_EQ((causes["frame not used: low contrast or blurred"] + causes["frame not used: too dark"]), 20);
  EXPECT_EQ(causes["frame not used: overexposed"], 10);
}

TEST(BadFrames, DimmedAndOverexposedFramesSharp) { expectCarriedThrough({0.01, true}, {0.122, 0.094}); }
TEST(BadFrames, DimmedAndOverexposedFramesMotionBlur) { expectCarriedThrough({0.04, true}, {0.150, 0.126}); }

}  // namespace
}  // namespace eds
