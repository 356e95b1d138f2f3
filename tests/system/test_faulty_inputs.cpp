// Faulty input on a hand-held desk scene (8 s). Frames the system cannot trust: dimmed to 5 % from 3 to
// 4 s (a hand over the lens) and blown out x4 from 5 to 5.5 s, the events unaffected; sharp (10 ms
// exposure) and motion-blurred (40 ms). The bad frames must stay out of tracking and the map, each
// listed as a failure with its cause, while the events carry the pose. Faulty events: a light flickering
// at 100 Hz over a patch, a burst of noise, two USB drops and hot pixels, the frames unaffected. Either
// way no rotation error above 1 degree (event-rate poses, as eds run writes them) and the ATE near the
// clean run's: with faulty events within 1.5x; with faulty frames within 1.3x outside the half second
// where no usable frame comes, and inside it bounded on its own.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <string>
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

struct Variant {
  double exposure_s;
  bool frame_faults;
  bool event_faults = false;
  bool covered = false;      // no events and black frames from 3 to 4 s
  bool frames_only = false;  // run without the events (the same sequence)
  bool threaded = false;     // the back-end in its own thread, as eds run has it by default
  bool deblur = false;       // the exposure given: keyframes deblurred with its events
  double t_start = 0.0;      // of the window in the hand-held motion
  bool dim_only = false;     // frame faults: the dimmed second only, from dim_from
  double dim_from = 3.0;
};

std::filesystem::path deskSequence(const std::filesystem::path& traj_file, Variant v) {
  const std::string name =
      "faulty_" + std::to_string(static_cast<int>(v.exposure_s * 1000)) + "ms" +
      (v.frame_faults ? "_frames" : "") + (v.event_faults ? "_events" : "") + (v.covered ? "_covered" : "") +
      (v.t_start > 0 ? "_from" + std::to_string(static_cast<int>(v.t_start)) : "") +
      (v.frame_faults && v.dim_only ? "_dim" + std::to_string(static_cast<int>(v.dim_from * 10)) : "");
  const auto dir = test::tempDir(name);
  const sim::Motion motion{sim::cutTrajectory(sim::smoothTrajectory(readTum(traj_file), 0.04), v.t_start, 8.0,
                                              traj_file.string())};
  sim::Scene scene = sim::makePreset("desk", motion, 1);
  scene.loadTextures();
  sim::SimConfig sc = test::noisySimConfig(1);
  sc.exposure_s = v.exposure_s;
  std::vector<sim::FrameGain> gains;
  const auto at = [&](double s) { return motion.start() + fromSeconds(s); };
  if (v.frame_faults) gains = {{at(v.dim_from), at(v.dim_from + 1.0), 0.05}};
  if (v.frame_faults && !v.dim_only) gains.push_back({at(5.0), at(5.5), 4.0});
  sim::EventFaults faults;
  if (v.event_faults) {
    faults.flicker = {{at(1.5), at(3.0), 100.0}};
    faults.bursts = {{at(3.5), at(3.8), 20.0}};
    faults.gaps = {{at(4.5), at(4.7), 0.0}, {at(5.5), at(5.55), 0.0}};
    sc.events.hot_pixel_fraction = 0.001;
    sc.events.hot_pixel_rate_hz = 1000;
  }
  if (v.covered) {
    gains = {{at(3.0), at(4.0), 0.0}};
    faults.gaps = {{at(3.0), at(4.0), 0.0}};
  }
  test::writeSimSequence(dir, scene, motion, sc, gains, faults);
  return dir;
}

eval::AteResult runDesk(Variant v, OdometryResult& r, bool recovery = true, bool feature_start = true) {
  const Sequence seq(deskSequence(test::sharedDataDir() / "trajectories/ecd_poster_6dof_groundtruth.txt", v));
  OdometryConfig cfg;
  cfg.threaded_backend = v.threaded;  // off: deterministic
  cfg.recovery.enabled = recovery;
  if (!feature_start) cfg.feature_start.min_interval_s = 0;
  cfg.use_events = !v.frames_only;
  if (v.deblur) cfg.deblur.exposure_s = v.exposure_s;
  r = runOdometry(seq, cfg);
  EXPECT_TRUE(r.initialized);
  const Trajectory& est = v.frames_only ? r.frames_refined : r.events_refined;
  const eval::AteResult a = eval::evaluateAte(est, seq.groundTruth(), eval::EvalConfig{});
  char dim[64] = "";
  if (v.frame_faults)
    std::snprintf(dim, sizeof dim, ", dimmed %.0f-%.0f s%s", v.dim_from, v.dim_from + 1,
                  v.dim_only ? "" : ", x4 5-5.5 s");
  std::printf(
      "[ desk from %.0f s, %.0f ms exposure%s%s%s%s%s ] ATE %.3f cm, rot %.3f deg (max %.3f), "
      "coverage %.1f %%, %zu frames not used, %zu events of flickering pixels dropped, %zu failures\n",
      v.t_start, v.exposure_s * 1000, v.frames_only ? ", frames only" : "",
      v.threaded ? ", threaded back-end" : "", v.deblur ? ", keyframes deblurred" : "", dim,
      v.event_faults ? ", flicker, noise burst, USB drops, hot pixels"
      : v.covered    ? ", covered 3-4 s"
                     : "",
      a.trans.rmse * 100, a.rot.rmse, a.rot.max, a.coverage * 100, r.frames_rejected,
      r.events_flicker_dropped, r.failures.size());
  const auto worst =
      std::max_element(a.rot_errors_deg.begin(), a.rot_errors_deg.end()) - a.rot_errors_deg.begin();
  if (!a.pairs.empty())
    std::printf("  largest rotation error at %.3f s\n",
                toSeconds(est[a.pairs[static_cast<std::size_t>(worst)].est].t - r.first_t));
  return a;
}

// The same scene without the faults, run here rather than quoted, so that the bounds follow the clean
// run as it improves.
test::Measured cleanRun(Variant v) {
  OdometryResult r;
  v.frame_faults = v.event_faults = v.covered = false;
  const eval::AteResult a = runDesk(v, r);
  return {a.trans.rmse * 100, a.rot_oriented.rmse};
}

// Within `ratio` times the clean run's ATE; with frame faults (the issue of frames the events must carry
// through) also no rotation error above 1 degree, with event faults the rotation RMSE within 1.5x.
void expectWithinCleanBounds(const eval::AteResult& a, test::Measured clean, bool max_rotation,
                             double ratio) {
  EXPECT_LE(a.trans.rmse * 100, ratio * clean.ate_cm);
  if (max_rotation)
    EXPECT_LE(a.rot.max, 1.0);
  else
    EXPECT_LE(a.rot_oriented.rmse, 1.5 * clean.rot_deg);
  EXPECT_GE(a.coverage, 0.9);
}

// One run with frame faults: what must hold on every run, the accuracy bounds aside.
eval::AteResult expectFaultsHandled(Variant v, OdometryResult& r) {
  const eval::AteResult a = runDesk(v, r);
  EXPECT_GE(a.coverage, 0.9);
  EXPECT_EQ(r.exposure_estimated, !v.deblur);
  EXPECT_NEAR(r.exposure_s, v.exposure_s, 0.006);
  EXPECT_EQ(r.deblurred, v.deblur || v.exposure_s >= OdometryConfig{}.deblur.min_exposure_s);
  // The 20 dimmed and 10 blown-out frames, and nothing else (but a few event frames the lost-track
  // check flags), each failure naming its cause.
  EXPECT_EQ(r.frames_rejected, 30u);
  std::map<std::string, int> causes;
  std::size_t lost_event_frames = 0;
  for (const OdometryFailure& f : r.failures) {
    const double s = toSeconds(f.t - r.first_t);
    if (f.reason.starts_with("event frame: ")) {
      ++lost_event_frames;
      continue;
    }
    const bool dim = s >= 2.99 && s < 4.0, bright = s >= 4.99 && s < 5.5;
    EXPECT_TRUE(dim || bright) << "failure at " << s << " s: " << f.reason;
    causes[f.reason.substr(0, f.reason.find(" ("))] += 1;
  }
  // The dimmed frames still hold the scene: aligned from the events' pose, each gives a pose (never a
  // keyframe). The blown-out ones keep too few pixels to be trusted.
  EXPECT_EQ((causes["frame kept out of the map: low contrast or blurred"] +
             causes["frame kept out of the map: too dark"]),
            20);
  EXPECT_EQ(causes["frame not used: overexposed"], 10);
  EXPECT_EQ(r.frames_tracked_only, 20u);
  for (const StampedPose& kf : r.keyframes) {
    const double s = toSeconds(kf.t - r.first_t);
    EXPECT_FALSE((s >= 2.99 && s < 4.0) || (s >= 4.99 && s < 5.5)) << "keyframe at " << s << " s";
  }
  EXPECT_LE(lost_event_frames, r.events_tracked / 100);
  return a;
}

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// Translation RMSE (cm) of the event-rate poses between the last usable frame before the blown-out ones
// (4.95 s) and the first after (5.5 s), where no frame anchors them, and of all the others.
struct BlindSplit {
  double inside_cm = 0, outside_cm = 0;
};

BlindSplit splitAtBlindStretch(const eval::AteResult& a, const Trajectory& est, TimeNs first_t) {
  double sum[2] = {0, 0};
  int n[2] = {0, 0};
  for (std::size_t i = 0; i < a.pairs.size(); ++i) {
    const double s = toSeconds(est[a.pairs[i].est].t - first_t);
    const int k = s > 4.951 && s < 5.499;
    sum[k] += a.trans_errors[i] * a.trans_errors[i];
    ++n[k];
  }
  return {100 * std::sqrt(sum[1] / std::max(n[1], 1)), 100 * std::sqrt(sum[0] / std::max(n[0], 1))};
}

// The frames' exposure, unless given, is estimated from the first frames with motion and their events:
// within 6 ms of the simulated one (the estimate runs 3-4 ms long on these noisy sensors). The threaded
// back-end's results vary from run to run, so its figures are the medians of `runs` runs.
// Outside the blind half second the faulty frames must cost little (kept out of the map): within `ratio`
// times the clean run's ATE. Inside it the events carry the pose alone: within `blind_cm`.
void expectCarriedThrough(Variant v, double ratio, double blind_cm, int runs = 1) {
  EDS_REQUIRE_SHARED(traj, "trajectories/ecd_poster_6dof_groundtruth.txt");
  std::vector<double> inside_cm, outside_cm, rot_max_deg, clean_cm;
  for (int i = 0; i < runs; ++i) {
    OdometryResult r;
    const eval::AteResult a = expectFaultsHandled(v, r);
    const BlindSplit split = splitAtBlindStretch(a, r.events_refined, r.first_t);
    inside_cm.push_back(split.inside_cm);
    outside_cm.push_back(split.outside_cm);
    rot_max_deg.push_back(a.rot.max);
    clean_cm.push_back(cleanRun(v).ate_cm);
    std::printf("  blind 4.95-5.5 s %.4f cm, elsewhere %.4f cm (%.2fx the clean run)\n", split.inside_cm,
                split.outside_cm, split.outside_cm / clean_cm.back());
  }
  EXPECT_LE(median(outside_cm), ratio * median(clean_cm));
  EXPECT_LE(median(inside_cm), blind_cm);
  EXPECT_LE(median(rot_max_deg), 1.0);
}

// Over the blown-out half second no frame anchors the event-rate poses, and there the events alone
// are 3-4x less accurate than the anchored poses elsewhere: a whole-run ratio against the clean run
// measured mostly those 59 poses (docs/experiments.md). Sharp: elsewhere 0.033 against 0.028 cm
// (1.17x), blind 0.090 cm. Blurred: against a blurred keyframe the events stray more there (0.117 cm,
// elsewhere 1.09x; 0.134 cm built for the compiler's default); with the keyframes deblurred with the
// events of their exposure (estimated, 44 ms, or given) 0.101 cm, elsewhere 1.07x (0.143 cm).
TEST(BadFrames, DimmedAndOverexposedFramesSharp) { expectCarriedThrough({0.01, true}, 1.3, 0.14); }
TEST(BadFrames, DimmedAndOverexposedFramesMotionBlur) { expectCarriedThrough({0.04, true}, 1.3, 0.21); }
TEST(BadFrames, DimmedAndOverexposedFramesMotionBlurKeyframesDeblurred) {
  expectCarriedThrough({.exposure_s = 0.04, .frame_faults = true, .deblur = true}, 1.3, 0.21);
}
// The default threaded back-end: a refused frame after a keyframe waits for it to be mapped, as a usable
// one does, so that the events carry the pose against the mapped keyframe. Single runs spread (blind
// 0.061-0.121 cm, elsewhere 1.02-1.26x), hence the medians of three. On two busy cores 4
// runs in 110 keyframed at other frames and lost the pose in the blown-out half second (2.3 cm, 7-8
// degrees; docs/experiments.md), so the test runs alone (CMake).
TEST(BadFrames, DimmedAndOverexposedFramesSharpThreadedBackend) {
  expectCarriedThrough({.exposure_s = 0.01, .frame_faults = true, .threaded = true}, 1.3, 0.14, 3);
}

// Without events the dimmed frames, aligned for a pose only, carry the track through their second: the
// only loss is the half second of blown-out frames (0.029 cm over 93 %; before, a loss over both gaps
// and 80 %).
TEST(BadFrames, DimmedFramesBridgedWithoutEvents) {
  EDS_REQUIRE_SHARED(traj, "trajectories/ecd_poster_6dof_groundtruth.txt");
  OdometryResult r, clean;
  const eval::AteResult a = runDesk({0.01, true, false, false, true}, r);
  const eval::AteResult c = runDesk({0.01, false, false, false, true}, clean);
  EXPECT_EQ(r.frames_tracked_only, 20u);
  EXPECT_LE(a.trans.rmse, 1.5 * c.trans.rmse);
  EXPECT_LE(a.rot.max, 1.0);
  EXPECT_GE(a.coverage, 0.9);
  ASSERT_EQ(r.losses.size(), 1u);
  EXPECT_NEAR(toSeconds(r.losses[0].t_lost - r.first_t), 4.95, 0.01);
}

// The same at the motion's fast part (55-59 cm/s, about 2 % of the scene's depth from frame to frame):
// a dimmed frame's alignment must start from the constant-velocity prediction, since from the last pose
// it would land too far from its start to be kept, and the map would then take the dark frames.
TEST(BadFrames, DimmedFramesBridgedWithoutEventsAtSpeed) {
  EDS_REQUIRE_SHARED(traj, "trajectories/ecd_poster_6dof_groundtruth.txt");
  Variant v{0.01, true};
  v.frames_only = true, v.t_start = 8.0, v.dim_only = true, v.dim_from = 4.0;
  OdometryResult r, clean;
  const eval::AteResult a = runDesk(v, r);
  v.frame_faults = false;
  const eval::AteResult c = runDesk(v, clean);
  EXPECT_EQ(r.frames_tracked_only, 20u);
  EXPECT_TRUE(r.losses.empty());
  EXPECT_LE(a.trans.rmse, 1.5 * c.trans.rmse);
  EXPECT_LE(a.rot.max, 1.0);
  EXPECT_GE(a.coverage, 0.95);
}

// The flickering pixels' events are dropped before the event frames.
TEST(FaultyEvents, FlickerNoiseBurstUsbDropsAndHotPixels) {
  EDS_REQUIRE_SHARED(traj, "trajectories/ecd_poster_6dof_groundtruth.txt");
  OdometryResult r;
  const eval::AteResult a = runDesk({0.01, false, true}, r);
  expectWithinCleanBounds(a, cleanRun({0.01, false}), false, 1.5);
  EXPECT_GT(r.events_flicker_dropped, 1'000'000u);
  // The lost-track check flags event frames of the noise burst and the one that spans a USB drop's
  // start; nothing else fails.
  const auto inFault = [&](double s) {
    for (const auto& [a, b] : {std::pair{3.5, 3.8}, {4.5, 4.7}, {5.5, 5.55}})
      if (s >= a - 0.05 && s <= b + 0.05) return true;
    return false;
  };
  for (const OdometryFailure& f : r.failures) {
    const double s = toSeconds(f.t - r.first_t);
    EXPECT_TRUE(f.reason.starts_with("event frame: ") && inFault(s))
        << "failure at " << s << " s: " << f.reason;
  }
}

// The camera covered for a second (no events, black frames) while it moves on: the first frame after
// is relocalized (features against the newest keyframe, then the direct alignment) and the track goes
// on in the same map. Without the recovery that frame, a second after the last, is still aligned from
// its features as well; without either it follows a wrong alignment for the rest of the run.
TEST(Recovery, ACoveredCameraIsRelocalizedWhenUncovered) {
  EDS_REQUIRE_SHARED(traj, "trajectories/ecd_poster_6dof_groundtruth.txt");
  OdometryResult r;
  const eval::AteResult a = runDesk({0.01, false, false, true}, r);
  ASSERT_EQ(r.losses.size(), 1u);
  const TrackLoss& loss = r.losses.front();
  std::printf("  lost at %.3f s (%s), recovered at %.3f s after %d frames: %s\n",
              toSeconds(loss.t_lost - r.first_t), loss.cause.c_str(), toSeconds(loss.t_recovered - r.first_t),
              loss.attempts, loss.recovery.c_str());
  EXPECT_NEAR(toSeconds(loss.t_lost - r.first_t), 3.0, 0.06);
  EXPECT_NEAR(toSeconds(loss.t_recovered - r.first_t), 4.0, 0.11);  // the first or second frame after
  EXPECT_LE(a.trans.rmse * 100, 0.3);
  EXPECT_LE(a.rot.max, 1.0);
  EXPECT_GE(a.coverage, 0.8);  // the covered second has no pose
  OdometryResult no_recovery;
  const eval::AteResult b = runDesk({0.01, false, false, true}, no_recovery, false);
  EXPECT_GE(no_recovery.feature_starts, 1u);
  EXPECT_LE(b.trans.rmse * 100, 0.3);
  OdometryResult without;
  const eval::AteResult c = runDesk({0.01, false, false, true}, without, false, false);
  EXPECT_GT(c.trans.rmse * 100, 5.0);
}

}  // namespace
}  // namespace eds
