#include "study/sensitivity.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "eval/ate.hpp"
#include "io/sequence.hpp"
#include "sim/motion.hpp"
#include "sim/presets.hpp"
#include "sim/simulator.hpp"
#include "sim/writer.hpp"
#include "system/track_only.hpp"

namespace eds::study {

namespace {

// A building-like sequence (sim preset `building`, the built-in hand-held motion) with depth maps.
void simulateBuilding(const std::filesystem::path& dir, std::uint64_t seed, double duration_s, double C,
                      double sigma_C) {
  const sim::Motion motion(sim::handheldMotion(duration_s, seed));
  sim::Scene scene = sim::makePreset("building", motion, seed);
  scene.loadTextures();
  const CameraModel cam = sim::defaultCamera(240, 180);
  sim::SimConfig cfg;
  cfg.events.C_pos = cfg.events.C_neg = C;
  cfg.events.sigma_C = sigma_C;
  cfg.events.noise_rate_hz = 0.1;
  cfg.events.seed = seed;
  cfg.fps = 20;
  sim::EcdWriter writer(dir, /*gzip=*/false, /*write_depth=*/true);
  sim::writeEcdCalib(dir / "calib.txt", cam);
  sim::writeGroundTruth(dir / "groundtruth.txt", motion, motion.start(), motion.end(), sim::kGroundTruthRateHz);
  sim::Simulator(scene, cam, motion, cfg).run(motion.start(), motion.end(), writer);
  writer.finish();
}

double medianDepth(const Sequence& seq) {
  const std::optional<cv::Mat> depth = seq.loadDepth(0);
  if (!depth) return 0;
  std::vector<float> v;
  for (int r = 0; r < depth->rows; ++r)
    for (int c = 0; c < depth->cols; ++c)
      if (const float d = depth->at<float>(r, c); d > 0) v.push_back(d);
  if (v.empty()) return 0;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

StudyRun trackOnce(const Sequence& seq, double level, std::uint64_t seed, Kind kind) {
  TrackOnlyConfig cfg;
  cfg.seed = seed;
  if (kind == Kind::kDepthNoise) cfg.depth_noise = level;
  const TrackOnlyResult tr = runTrackOnly(seq, cfg);
  StudyRun run{level, seed, {}, {}, 0, 0, 0, tr.event_frames, tr.tracked, tr.failures.size()};
  eval::EvalConfig ec;
  ec.alignment = eval::Alignment::kNone;
  try {
    const eval::AteResult ate = eval::evaluateAte(tr.trajectory, seq.groundTruth(), ec);
    for (double e : ate.trans_errors) run.trans_cm.push_back(100 * e);
    run.rot_deg = ate.rot_errors_deg;
    run.ate_cm = 100 * ate.trans.rmse, run.rot_rmse_deg = ate.rot.rmse, run.coverage = ate.coverage;
  } catch (const std::invalid_argument&) {
    // nothing tracked: no pose to compare, coverage 0
  }
  return run;
}

}  // namespace

std::vector<double> defaultLevels(Kind kind) {
  if (kind == Kind::kDepthNoise) return {0.01, 0.05, 0.10, 0.20, 0.30, 0.50};
  return {0.05, 0.10, 0.15, 0.20, 0.25, 0.30};
}

std::string levelName(Kind kind, double level) {
  char b[32];
  if (kind == Kind::kDepthNoise)
    std::snprintf(b, sizeof b, "%g %%", 100 * level);
  else
    std::snprintf(b, sizeof b, "%.2f", level);
  return b;
}

StudyResult runStudy(const StudyConfig& cfg, const std::function<void(const StudyRun&)>& progress) {
  const auto t0 = std::chrono::steady_clock::now();
  StudyResult res;
  res.kind = cfg.kind;
  const bool depth = cfg.kind == Kind::kDepthNoise;
  res.title = depth ? "depth noise" : "contrast-threshold noise";
  res.level_label = depth ? "depth noise (std-dev, % of the median scene depth)" : "sigma_C (mu_C = 0.5)";
  const std::vector<double> levels = cfg.levels.empty() ? defaultLevels(cfg.kind) : cfg.levels;
  if (cfg.seeds.empty()) throw std::invalid_argument("a study needs at least one seed");
  std::vector<StudyRun> runs;
  const auto simulateAndTrack = [&](std::uint64_t seed, double C, double sigma_C,
                                    const std::vector<double>& at) {
    const std::filesystem::path dir = cfg.work_dir / ("seq_" + std::to_string(seed));
    std::filesystem::remove_all(dir);
    simulateBuilding(dir, seed, cfg.duration_s, C, sigma_C);
    const Sequence seq(dir);
    if (res.median_scene_depth_m == 0) res.median_scene_depth_m = medianDepth(seq);
    for (double level : at) {
      runs.push_back(trackOnce(seq, level, seed, cfg.kind));
      if (progress) progress(runs.back());
    }
    std::filesystem::remove_all(dir);
  };
  for (std::uint64_t seed : cfg.seeds) {
    if (depth)
      simulateAndTrack(seed, cfg.depth_study_C, cfg.depth_study_sigma_C, levels);  // one sequence, all levels
    else
      for (double sigma : levels) simulateAndTrack(seed, cfg.contrast_mean, sigma, {sigma});
  }
  for (double level : levels)  // level-major
    for (const StudyRun& r : runs)
      if (r.level == level) res.runs.push_back(r);
  res.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

nlohmann::json toJson(const StudyResult& r) {
  nlohmann::json runs = nlohmann::json::array();
  for (const StudyRun& s : r.runs)
    runs.push_back({{"level", s.level},
                    {"seed", s.seed},
                    {"ate_cm", s.ate_cm},
                    {"rot_rmse_deg", s.rot_rmse_deg},
                    {"coverage", s.coverage},
                    {"event_frames", s.event_frames},
                    {"tracked", s.tracked},
                    {"failures", s.failures},
                    {"trans_cm", s.trans_cm},
                    {"rot_deg", s.rot_deg}});
  return {{"study", r.title},
          {"level", r.level_label},
          {"median_scene_depth_m", r.median_scene_depth_m},
          {"wall_s", r.wall_s},
          {"runs", runs}};
}

}  // namespace eds::study
