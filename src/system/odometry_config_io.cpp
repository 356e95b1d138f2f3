#include "system/odometry_config_io.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <string>
#include <variant>
#include <vector>

#include "core/error.hpp"

namespace eds {

namespace {

using Field = std::variant<double*, int*, bool*>;

// The one list of parameters: both the reader and the writer walk it.
std::map<std::string, Field> fields(OdometryConfig& c) {
  std::map<std::string, Field> f;
  const auto sel = [&f](const std::string& p, PointSelectionConfig& s) {
    f[p + ".tile"] = &s.tile, f[p + ".fraction"] = &s.fraction, f[p + ".min_gradient"] = &s.min_gradient;
    f[p + ".border"] = &s.border, f[p + ".max_points"] = &s.max_points;
  };
  const auto fill = [&f](const std::string& p, DepthFillConfig& d) {
    f[p + ".max_distance_px"] = &d.max_distance_px, f[p + ".neighbours"] = &d.neighbours;
  };
  BootstrapConfig& b = c.bootstrap;
  sel("bootstrap.points", b.points);
  f["bootstrap.depth_prior_weight"] = &b.depth_prior_weight,
  f["bootstrap.min_parallax_px"] = &b.min_parallax_px;
  f["bootstrap.min_points"] = &b.min_points, f["bootstrap.min_frames"] = &b.min_frames;
  f["bootstrap.max_frames"] = &b.max_frames, f["bootstrap.max_parallax_step_px"] = &b.max_parallax_step_px;
  f["bootstrap.max_rmse"] = &b.max_rmse, f["bootstrap.min_intensity"] = &b.min_intensity;
  f["bootstrap.max_intensity"] = &b.max_intensity, f["bootstrap.geometric"] = &b.geometric;
  f["bootstrap.ba_levels"] = &b.ba_levels, f["bootstrap.ba.iterations"] = &b.ba.iterations;
  GeometricInitConfig& g = b.geometric_init;
  f["bootstrap.geometric_init.max_features"] = &g.max_features,
  f["bootstrap.geometric_init.quality"] = &g.quality;
  f["bootstrap.geometric_init.min_distance"] = &g.min_distance,
  f["bootstrap.geometric_init.min_flow_px"] = &g.min_flow_px;
  f["bootstrap.geometric_init.min_tracks"] = &g.min_tracks,
  f["bootstrap.geometric_init.ransac_px"] = &g.ransac_px;
  f["bootstrap.geometric_init.planar_ratio"] = &g.planar_ratio;
  f["bootstrap.geometric_init.max_reproj_px"] = &g.max_reproj_px;
  f["bootstrap.geometric_init.min_parallax_deg"] = &g.min_parallax_deg;
  FrameTrackerConfig& ft = c.frame_tracker;
  f["frame_tracker.levels"] = &ft.levels, f["frame_tracker.max_iterations"] = &ft.max_iterations;
  f["frame_tracker.huber"] = &ft.huber, f["frame_tracker.affine"] = &ft.affine,
  f["frame_tracker.max_rmse"] = &ft.max_rmse;
  f["frame_tracker.min_residuals"] = &ft.min_residuals, f["frame_tracker.convergence"] = &ft.convergence;
  f["frame_always_tries_cv"] = &c.frame_always_tries_cv;
  f["prior_levels"] = &c.prior_levels;
  MappingConfig& m = c.mapping;
  sel("mapping.points", m.points);
  fill("mapping.fill", m.fill);
  f["mapping.search.step_px"] = &m.search.step_px, f["mapping.search.max_rms"] = &m.search.max_rms;
  f["mapping.search.uniqueness"] = &m.search.uniqueness,
  f["mapping.search.min_line_px"] = &m.search.min_line_px;
  f["mapping.search.max_samples"] = &m.search.max_samples, f["mapping.epipolar_search"] = &m.epipolar_search;
  f["mapping.search_max_disagreement"] = &m.search_max_disagreement;
  f["mapping.min_intensity"] = &m.min_intensity, f["mapping.max_intensity"] = &m.max_intensity;
  BackendConfig& be = c.backend;
  f["backend.window"] = &be.window, f["backend.points_per_keyframe"] = &be.points_per_keyframe;
  f["backend.marginalize"] = &be.marginalize, f["backend.ba.iterations"] = &be.ba.iterations;
  f["backend.removal"] = &be.removal, f["backend.min_visible"] = &be.min_visible;
  f["backend.reference_inliers_only"] = &be.reference_inliers_only;
  f["backend.ba.huber"] = &be.ba.huber, f["backend.ba.grad_weight_c"] = &be.ba.grad_weight_c;
  f["backend.ba.outlier_energy"] = &be.ba.outlier_energy,
  f["backend.ba.lambda_initial"] = &be.ba.lambda_initial;
  f["policy.flow_t"] = &c.policy.flow_t, f["policy.flow_rt"] = &c.policy.flow_rt;
  f["policy.min_in_view"] = &c.policy.min_in_view, f["policy.max_log_alpha"] = &c.policy.max_log_alpha;
  f["policy.lookahead"] = &c.policy.lookahead,
  f["policy.lookahead_depth_ratio"] = &c.policy.lookahead_depth_ratio;
  f["threaded_backend"] = &c.threaded_backend, f["use_events"] = &c.use_events;
  f["wait_for_keyframe"] = &c.wait_for_keyframe;
  f["event_frame.num_events"] = &c.event_frame.num_events, f["event_frame.overlap"] = &c.event_frame.overlap;
  f["event_frame.sigma_frac"] = &c.event_frame.sigma_frac, f["event_frame.blur"] = &c.event_frame.blur;
  f["event_frame.reversal_compensation"] = &c.event_frame.reversal_compensation;
  f["event_frame.compensation_lookahead"] = &c.event_frame.compensation_lookahead;
  EventTrackerConfig& et = c.events.tracker;
  f["events.tracker.max_iterations"] = &et.max_iterations, f["events.tracker.levels"] = &et.levels;
  f["events.tracker.huber_initial"] = &et.huber_initial, f["events.tracker.adapt_huber"] = &et.adapt_huber;
  f["events.tracker.set_margin"] = &et.set_margin;
  f["events.tracker.border"] = &et.border, f["events.tracker.min_points"] = &et.min_points;
  f["events.tracker.min_correlation"] = &et.min_correlation,
  f["events.tracker.lambda_initial"] = &et.lambda_initial;
  sel("events.points", c.events.points);
  fill("events.fill", c.events.fill);
  f["events.depth_median_px"] = &c.events.depth_median_px;
  MotionPriorConfig& mp = c.events.motion_prior;
  f["events.motion_prior.enabled"] = &mp.enabled;
  f["events.motion_prior.sigma_translation"] = &mp.sigma_translation,
  f["events.motion_prior.accel"] = &mp.accel;
  f["events.motion_prior.sigma_rotation"] = &mp.sigma_rotation,
  f["events.motion_prior.ang_accel"] = &mp.ang_accel;
  f["events.motion_prior.max_gap_s"] = &mp.max_gap_s;
  f["bootstrap_from_events"] = &c.bootstrap_from_events;
  f["buffered_gate_translation"] = &c.buffered_gate_translation;
  f["buffered_gate_rotation_deg"] = &c.buffered_gate_rotation_deg;
  f["frame_rate"] = &c.frame_rate, f["start_s"] = &c.start_s, f["duration_s"] = &c.duration_s;
  return f;
}

// Leaves of a YAML map as dotted names.
void flatten(const YAML::Node& n, const std::string& prefix, std::map<std::string, YAML::Node>& out) {
  if (n.IsMap()) {
    for (const auto& kv : n)
      flatten(kv.second,
              prefix.empty() ? kv.first.as<std::string>() : prefix + "." + kv.first.as<std::string>(), out);
  } else {
    out[prefix] = n;
  }
}

}  // namespace

void loadOdometryConfig(const std::filesystem::path& file, OdometryConfig& cfg) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(file.string());
  } catch (const YAML::BadFile&) {
    throw InputError(file.string(), "cannot read the configuration file");
  } catch (const YAML::Exception& e) {
    throw InputError(file.string(), "line " + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  if (root.IsNull()) return;
  if (!root.IsMap()) throw InputError(file.string(), "expected a map of parameters");
  std::map<std::string, YAML::Node> leaves;
  flatten(root, "", leaves);
  auto f = fields(cfg);
  for (const auto& [key, node] : leaves) {
    const auto it = f.find(key);
    const std::string where = "line " + std::to_string(node.Mark().line + 1) + ": ";
    if (it == f.end()) throw InputError(file.string(), where + "unknown parameter '" + key + "'");
    try {
      std::visit([&node](auto* p) { *p = node.as<std::remove_pointer_t<decltype(p)>>(); }, it->second);
    } catch (const YAML::Exception&) {
      throw InputError(file.string(), where + "bad value for '" + key + "'");
    }
  }
}

void saveOdometryConfig(const std::filesystem::path& file, const OdometryConfig& cfg) {
  OdometryConfig copy = cfg;
  YAML::Node root(YAML::NodeType::Map);
  for (const auto& [key, field] : fields(copy)) {
    std::vector<std::string> parts;
    std::stringstream ss(key);
    for (std::string part; std::getline(ss, part, '.');) parts.push_back(part);
    // Down the dotted path, creating maps on the way (yaml-cpp nodes are handles into the tree).
    YAML::Node node = root;
    for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
      if (!node[parts[i]]) node[parts[i]] = YAML::Node(YAML::NodeType::Map);
      node.reset(node[parts[i]]);
    }
    std::visit([&](auto* p) { node[parts.back()] = *p; }, field);
  }
  std::ofstream out(file);
  if (!out) throw InputError(file.string(), "cannot open for writing");
  out << "# eds run: every parameter of this run (load with --config)\n" << root << "\n";
}

void copyOdometryParameter(const OdometryConfig& from, OdometryConfig& to, const std::string& key) {
  OdometryConfig src = from;
  const auto f_from = fields(src);
  auto f_to = fields(to);
  const auto a = f_from.find(key);
  const auto b = f_to.find(key);
  if (a == f_from.end() || b == f_to.end()) throw std::invalid_argument("unknown parameter '" + key + "'");
  std::visit([&](auto* dst) { *dst = *std::get<decltype(dst)>(a->second); }, b->second);
}

OdometryConfig defaultOdometryConfig(int width, int height) {
  OdometryConfig c;
  if (width <= 0 || height <= 0)
    throw std::invalid_argument("defaultOdometryConfig: sensor size must be positive");
  constexpr double kSmall = 240.0 * 180.0, kLarge = 640.0 * 480.0;
  const double px = static_cast<double>(width) * height;
  if (px <= kSmall) return c;
  // 0 at 240x180, 1 from 640x480 on.
  const double f = std::min(1.0, (px - kSmall) / (kLarge - kSmall));
  c.event_frame.num_events = static_cast<int>(std::lround(20000 + f * (80000 - 20000)));
  c.event_frame.overlap = 0.5 + f * 0.1;
  c.events.points.fraction = 0.12 + f * (0.07 - 0.12);
  if (f >= 0.5) c.frame_tracker.levels += 1, c.bootstrap.tracker.levels += 1;
  c.backend.points_per_keyframe = static_cast<int>(std::lround(300 * (1 + f)));
  return c;
}

}  // namespace eds
