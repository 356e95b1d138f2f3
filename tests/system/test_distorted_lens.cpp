// The distorted event path end to end: scenes simulated through the ECD DAVIS240C's radtan lens (the
// slider's calib.txt, as `eds simulate --calib`) and through a pinhole with the same intrinsics. With
// the lens, events land between the undistorted pixel centres (the event frame's bilinear votes) and
// frames go through the remap table; tracking-only and eds run must stay close to the pinhole case.
// Tracking-only runs on the ESIM poster scene (3 s), where it is accurate with true depth; eds run on
// the desk preset along 8 s of the real poster_6dof motion, long enough for a well-posed alignment.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <utility>

#include "accuracy.hpp"
#include "eval/ate.hpp"
#include "io/sequence.hpp"
#include "io/trajectory_io.hpp"
#include "sim/motion.hpp"
#include "sim/presets.hpp"
#include "sim/scene.hpp"
#include "sim/simulator.hpp"
#include "sim/writer.hpp"
#include "system/odometry.hpp"
#include "system/track_only.hpp"
#include "test_data.hpp"

namespace eds {
namespace {

// Frames at 20 Hz, threshold noise 0.03, 2x2 anti-aliasing as `eds simulate`; depth maps for tracking-only.
void simulateThrough(const CameraModel& cam, const sim::Scene& scene, const sim::Motion& motion,
                     double noise_rate_hz, const std::filesystem::path& out) {
  sim::SimConfig sc;
  sc.fps = 20;
  sc.render.supersample = 2;
  sc.events.sigma_C = 0.03;
  sc.events.noise_rate_hz = noise_rate_hz;
  sc.events.seed = 3;
  sim::EcdWriter writer(out, false, true);
  sim::writeEcdCalib(out / "calib.txt", cam);
  sim::writeGroundTruth(out / "groundtruth.txt", motion, motion.start(), motion.end(),
                        sim::kGroundTruthRateHz);
  sim::Simulator(scene, cam, motion, sc).run(motion.start(), motion.end(), writer);
  writer.finish();
}

struct Pair {
  std::filesystem::path pinhole, radtan;
};

// The slider's lens and the pinhole with its intrinsics.
std::pair<CameraModel, CameraModel> lenses(const std::filesystem::path& calib) {
  CameraModel radtan = readEcdCalib(calib);
  radtan.width = 240, radtan.height = 180;
  CameraModel pinhole = radtan;
  pinhole.distortion = Distortion::kNone;
  pinhole.k = {};
  return {pinhole, radtan};
}

Pair simulatePair(const std::string& name, const sim::Scene& scene, const sim::Motion& motion,
                  double noise_rate_hz, const std::filesystem::path& calib) {
  const auto [pinhole, radtan] = lenses(calib);
  Pair p{test::tempDir(name + "_pinhole"), test::tempDir(name + "_radtan")};
  simulateThrough(pinhole, scene, motion, noise_rate_hz, p.pinhole);
  simulateThrough(radtan, scene, motion, noise_rate_hz, p.radtan);
  return p;
}

std::filesystem::path sliderCalib() { return test::sharedDataDir() / "ecd_slider_depth" / "calib.txt"; }

// The ESIM poster scene for 3 s, simulated once per test program.
const Pair& esimPair() {
  static const Pair pair = [] {
    const auto esim = test::sharedDataDir() / "esim_poster6dof_planar";
    const sim::Motion motion(sim::cutTrajectory(readTum(esim / "groundtruth.txt"), 0.0, 3.0, esim));
    sim::Scene scene = sim::readEsimSceneTxt(esim / "scene.txt", test::sharedDataDir() / "textures");
    scene.loadTextures();
    return simulatePair("lens_esim", scene, motion, 0.0, sliderCalib());
  }();
  return pair;
}

// The desk preset along 8 s of the poster_6dof motion (smoothed, sigma = 50 ms), background noise.
const Pair& deskPair() {
  static const Pair pair = [] {
    const auto poster = test::sharedDataDir() / "trajectories" / "ecd_poster_6dof_groundtruth.txt";
    const sim::Motion motion(
        sim::cutTrajectory(sim::smoothTrajectory(readTum(poster), 0.05), 0.0, 8.0, poster.string()));
    sim::Scene scene = sim::makePreset("desk", motion, 1);
    scene.loadTextures();
    return simulatePair("lens_desk", scene, motion, 0.1, sliderCalib());
  }();
  return pair;
}

eval::AteResult trackOnly(const std::filesystem::path& dir) {
  const Sequence seq(dir);
  const TrackOnlyResult r = runTrackOnly(seq, TrackOnlyConfig{});
  EXPECT_EQ(r.tracked, r.event_frames) << dir;
  // The first keyframe sits at its true pose, so the estimate is aligned on that pose alone: an
  // alignment over all positions cannot fix the rotation about the nearly straight first second.
  eval::EvalConfig ec;
  ec.alignment = eval::Alignment::kSe3;
  ec.align_frames = 1;
  return eval::evaluateAte(r.trajectory, seq.groundTruth(), ec);
}

eval::AteResult odometry(const std::filesystem::path& dir) {
  const Sequence seq(dir);
  OdometryConfig cfg;
  cfg.threaded_backend = false;  // deterministic
  const OdometryResult r = runOdometry(seq, cfg);
  EXPECT_TRUE(r.initialized) << dir;
  test::expectOnlyAFewLostEventFrames(r);
  return eval::evaluateAte(r.events_refined, seq.groundTruth(), eval::EvalConfig{});
}

// Each lens against its measured figure, and the lens no more than 1.5x the pinhole's error.
void expectClose(const char* what, const eval::AteResult& pin, const eval::AteResult& rad,
                 test::Measured pin_measured, test::Measured rad_measured) {
  test::expectAccuracy(std::string(what) + ", pinhole", pin, pin_measured);
  test::expectAccuracy(std::string(what) + ", radtan", rad, rad_measured);
  EXPECT_LE(rad.trans.rmse * 100, test::translationBoundCm(pin.trans.rmse * 100));
  EXPECT_LE(rad.rot_oriented.rmse, 1.5 * pin.rot_oriented.rmse);
  EXPECT_GE(rad.coverage, 0.95);
}

TEST(DistortedLens, TrackingOnlyMatchesThePinholeCase) {
  EDS_REQUIRE_SHARED(esim, "esim_poster6dof_planar");
  EDS_REQUIRE_SHARED(textures, "textures");
  EDS_REQUIRE_SHARED(calib, "ecd_slider_depth/calib.txt");
  const Pair& p = esimPair();
  expectClose("ESIM scene 3 s, tracking-only with true depth", trackOnly(p.pinhole), trackOnly(p.radtan),
              {0.466, 0.254}, {0.517, 0.275});
}

TEST(DistortedLens, EventsAndFramesMatchThePinholeCase) {
  EDS_REQUIRE_SHARED(poster, "trajectories/ecd_poster_6dof_groundtruth.txt");
  EDS_REQUIRE_SHARED(calib, "ecd_slider_depth/calib.txt");
  const Pair& p = deskPair();
  expectClose("desk 8 s, eds run", odometry(p.pinhole), odometry(p.radtan), {0.061, 0.046}, {0.063, 0.047});
}

}  // namespace
}  // namespace eds
