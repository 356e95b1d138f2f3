#pragma once
// The paper's sensitivity studies (Sec. 4.5, Figs. 6-7), reproduced: tracking-only (events against
// keyframes with the true depth) on simulated building-like scenes, one parameter varied over levels,
// several seeds per level.
//   depth noise:    Gaussian noise on the keyframes' depths, a fraction of the median scene depth.
//   contrast noise: the event camera's threshold drawn per crossing around mu_C with std-dev sigma_C.
// Poses are compared with the ground truth without alignment: tracking-only starts at the true pose
// with metric depth, so every error is the tracker's.
#include <cstdint>
#include <filesystem>
#include <functional>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

namespace eds::study {

enum class Kind { kDepthNoise, kContrastNoise };

struct StudyConfig {
  Kind kind = Kind::kDepthNoise;
  std::vector<double> levels;  // empty: the paper's (depth 1-50 % of the median; sigma_C 0.05-0.25)
  std::vector<std::uint64_t> seeds = {1, 2, 3};
  double duration_s = 2.0;            // of each simulated sequence
  double contrast_mean = 0.5;         // mu_C of the contrast study (the paper's)
  double depth_study_C = 0.2;         // threshold of the depth study's sequences, ...
  double depth_study_sigma_C = 0.03;  // ... with this much threshold noise
  std::filesystem::path work_dir;     // sequences are simulated here and removed after use
};

// One tracking-only run.
struct StudyRun {
  double level = 0;
  std::uint64_t seed = 0;
  std::vector<double> trans_cm, rot_deg;  // per pose matched with the ground truth
  double ate_cm = 0, rot_rmse_deg = 0, coverage = 0;
  std::size_t event_frames = 0, tracked = 0, failures = 0;
};

struct StudyResult {
  Kind kind = Kind::kDepthNoise;
  std::string title, level_label;   // "depth noise", "% of the median depth"
  double median_scene_depth_m = 0;  // of the first sequence's first frame
  std::vector<StudyRun> runs;       // level-major
  double wall_s = 0;
};

std::vector<double> defaultLevels(Kind kind);
// Runs every level on every seed; `progress` (if given) hears about each finished run.
StudyResult runStudy(const StudyConfig& cfg, const std::function<void(const StudyRun&)>& progress = {});
nlohmann::json toJson(const StudyResult& r);
// The level as the report writes it: "10 %" for depth noise, "0.15" for sigma_C.
std::string levelName(Kind kind, double level);

}  // namespace eds::study
