#include "eval/ate.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <numbers>
#include <stdexcept>
#include <utility>

#include "core/error.hpp"
#include "io/output_file.hpp"

namespace eds::eval {
namespace {

// Angle of a rotation matrix in radians via its quaternion; atan2 keeps precision near 0 and pi.
double rotationAngle(const Mat3& R) {
  const Quat q(R);
  return 2.0 * std::atan2(q.vec().norm(), std::abs(q.w()));
}

// RMS distance of the matched ground-truth positions from their principal axis: the square root of
// the two smaller eigenvalues of their covariance.
double offAxisSpread(const Trajectory& gt, const std::vector<MatchedPair>& pairs) {
  if (pairs.empty()) return 0.0;
  Vec3 mu = Vec3::Zero();
  for (const MatchedPair& p : pairs) mu += gt[p.gt].T_w_c.translation();
  mu /= static_cast<double>(pairs.size());
  Mat3 C = Mat3::Zero();
  for (const MatchedPair& p : pairs) {
    const Vec3 d = gt[p.gt].T_w_c.translation() - mu;
    C += d * d.transpose();
  }
  C /= static_cast<double>(pairs.size());
  const Vec3 lambda = Eigen::SelfAdjointEigenSolver<Mat3>(C, Eigen::EigenvaluesOnly).eigenvalues();
  return std::sqrt(std::max(0.0, lambda[0] + lambda[1]));  // ascending: the two smaller
}

}  // namespace

bool rotationFreeAboutPath(const AteResult& r) {
  // An se3 alignment on one pose takes its rotation from that pose's orientation.
  if ((r.alignment != Alignment::kSim3 && r.alignment != Alignment::kSe3) || r.align_frames == 1)
    return false;
  return r.trans.rmse > 0.1 * r.path_off_axis_m;
}

nlohmann::json toJson(const ErrorStats& s) {
  return {{"rmse", s.rmse}, {"mean", s.mean}, {"median", s.median},          {"std", s.std},
          {"min", s.min},   {"max", s.max},   {"num_samples", s.num_samples}};
}

ErrorStats computeStats(const std::vector<double>& values) {
  ErrorStats s;
  s.num_samples = values.size();
  if (values.empty()) return s;
  const double n = static_cast<double>(values.size());
  double sum = 0.0, sum_sq = 0.0;
  for (const double v : values) {
    sum += v;
    sum_sq += v * v;
  }
  s.mean = sum / n;
  s.rmse = std::sqrt(sum_sq / n);
  // Two-pass variance: the one-pass formula cancels badly when the spread is small.
  double var = 0.0;
  for (const double v : values) var += (v - s.mean) * (v - s.mean);
  s.std = std::sqrt(var / n);
  std::vector<double> sorted = values;
  std::sort(sorted.begin(), sorted.end());
  const std::size_t m = sorted.size() / 2;
  s.median = sorted.size() % 2 == 1 ? sorted[m] : 0.5 * (sorted[m - 1] + sorted[m]);
  s.min = sorted.front();
  s.max = sorted.back();
  return s;
}

double computeCoverage(const Trajectory& est, const Trajectory& gt, const std::vector<MatchedPair>& pairs,
                       const std::optional<TimeWindow>& window, TimeNs max_gap) {
  if (gt.empty()) return 0.0;
  const auto [gt_min, gt_max] = std::minmax_element(
      gt.begin(), gt.end(), [](const StampedPose& a, const StampedPose& b) { return a.t < b.t; });
  TimeNs span_start = gt_min->t, span_end = gt_max->t;
  if (window) {
    span_start = std::max(span_start, window->start);
    span_end = std::min(span_end, window->end);
  }
  if (span_end <= span_start) return 0.0;

  std::vector<TimeNs> stamps;
  stamps.reserve(pairs.size());
  for (const MatchedPair& p : pairs) stamps.push_back(est[p.est].t);
  std::sort(stamps.begin(), stamps.end());
  TimeNs covered = 0;
  for (std::size_t i = 1; i < stamps.size(); ++i) {
    if (stamps[i] - stamps[i - 1] > max_gap) continue;
    // Matched estimates may lie up to max_dt outside the span; that time is not gt time.
    const TimeNs a = std::max(stamps[i - 1], span_start);
    const TimeNs b = std::min(stamps[i], span_end);
    if (b > a) covered += b - a;
  }
  return std::clamp(static_cast<double>(covered) / static_cast<double>(span_end - span_start), 0.0, 1.0);
}

AteResult evaluateAte(const Trajectory& est, const Trajectory& gt, const EvalConfig& cfg,
                      const std::vector<std::size_t>& segment_starts) {
  std::vector<MatchedPair> pairs = associate(est, gt, cfg.max_dt);
  if (cfg.window) pairs = filterByGtWindow(pairs, gt, *cfg.window);
  return evaluateAtePairs(est, gt, std::move(pairs), cfg, segment_starts);
}

namespace {

// Aligns the pairs of one segment and appends their errors; false when the segment cannot be aligned
// (too few or degenerate poses) and `may_skip`, else the alignment's exception propagates.
bool alignSegment(const Trajectory& est, const Trajectory& gt, const std::vector<MatchedPair>& pairs,
                  const EvalConfig& cfg, bool may_skip, AteResult& r, Sim3& transform) {
  const std::size_t n = pairs.size();
  std::vector<Vec3> p_gt(n), p_est(n);
  std::vector<Quat> q_gt(n), q_est(n);
  for (std::size_t i = 0; i < n; ++i) {
    const SE3& G = gt[pairs[i].gt].T_w_c;
    const SE3& E = est[pairs[i].est].T_w_c;
    p_gt[i] = G.translation();
    q_gt[i] = G.quaternion();
    p_est[i] = E.translation();
    q_est[i] = E.quaternion();
  }
  try {
    transform = alignTrajectory(p_gt, q_gt, p_est, q_est, cfg.alignment, cfg.align_frames);
  } catch (const std::invalid_argument&) {
    if (may_skip) return false;
    throw;
  }
  for (std::size_t i = 0; i < n; ++i) {
    r.trans_errors.push_back((p_gt[i] - transform.apply(p_est[i])).norm());
    const Mat3 E = (transform.R * q_est[i].toRotationMatrix()) * q_gt[i].toRotationMatrix().transpose();
    r.rot_errors_deg.push_back(rotationAngle(E) * 180.0 / std::numbers::pi);
    r.pairs.push_back(pairs[i]);
  }
  // The rotation R minimizing Σ ‖R_gt − R R_est‖²: the polar factor of Σ R_gt R_estᵀ.
  Mat3 M = Mat3::Zero();
  for (std::size_t i = 0; i < n; ++i)
    M += q_gt[i].toRotationMatrix() * q_est[i].toRotationMatrix().transpose();
  const Eigen::JacobiSVD<Mat3> svd(M, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3 D = Mat3::Identity();
  D(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  const Mat3 R_o = svd.matrixU() * D * svd.matrixV().transpose();
  for (std::size_t i = 0; i < n; ++i) {
    const Mat3 E = (R_o * q_est[i].toRotationMatrix()) * q_gt[i].toRotationMatrix().transpose();
    r.rot_oriented_errors_deg.push_back(rotationAngle(E) * 180.0 / std::numbers::pi);
  }
  return true;
}

}  // namespace

AteResult evaluateAtePairs(const Trajectory& est, const Trajectory& gt, std::vector<MatchedPair> pairs,
                           const EvalConfig& cfg, const std::vector<std::size_t>& segment_starts) {
  AteResult r;
  r.alignment = cfg.alignment;
  r.align_frames = cfg.align_frames;
  r.segment_starts = segment_starts;
  if (pairs.empty()) throw std::invalid_argument("no estimated pose matches the ground truth");
  // Pairs are sorted by estimate index, so each segment's pairs are contiguous.
  r.segment_transforms.assign(segment_starts.size() + 1, Sim3{});
  bool first = true;
  for (std::size_t k = 0, i = 0; k < r.segment_transforms.size(); ++k) {
    const std::size_t end = k < segment_starts.size() ? segment_starts[k] : est.size();
    std::vector<MatchedPair> seg;
    for (; i < pairs.size() && pairs[i].est < end; ++i) seg.push_back(pairs[i]);
    if (seg.empty()) continue;
    if (alignSegment(est, gt, seg, cfg, !segment_starts.empty(), r, r.segment_transforms[k]) && first) {
      r.transform = r.segment_transforms[k], first = false;
      // The spread of the poses the alignment was fitted to.
      const std::size_t used =
          cfg.align_frames == -1 ? seg.size() : std::min<std::size_t>(seg.size(), cfg.align_frames);
      r.path_off_axis_m = offAxisSpread(gt, std::vector<MatchedPair>(seg.begin(), seg.begin() + used));
    }
  }
  if (r.pairs.empty())
    throw std::invalid_argument("no map segment of the estimate has enough matched poses to align");
  r.trans = computeStats(r.trans_errors);
  r.rot = computeStats(r.rot_errors_deg);
  r.rot_oriented = computeStats(r.rot_oriented_errors_deg);
  r.coverage = computeCoverage(est, gt, r.pairs, cfg.window, cfg.max_coverage_gap);
  return r;
}

Trajectory alignedEstimate(const Trajectory& est, const AteResult& r) {
  if (r.segment_transforms.size() <= 1) return applySim3(est, r.transform);
  Trajectory out;
  for (std::size_t k = 0; k < r.segment_transforms.size(); ++k) {
    const std::size_t a = k == 0 ? 0 : r.segment_starts[k - 1];
    const std::size_t b = k < r.segment_starts.size() ? r.segment_starts[k] : est.size();
    const Trajectory part = applySim3(Trajectory(est.begin() + a, est.begin() + b), r.segment_transforms[k]);
    out.insert(out.end(), part.begin(), part.end());
  }
  return out;
}

EvalInputs readEvalInputs(const std::filesystem::path& gt_file, const std::filesystem::path& est_file) {
  EvalInputs in{gt_file, est_file, readTum(gt_file, true), {}, {}};
  in.est = readTum(est_file, true, &in.est_segment_starts);
  if (in.gt.empty()) throw InputError(gt_file.string(), "ground-truth trajectory is empty");
  if (in.est.empty()) throw InputError(est_file.string(), "estimated trajectory is empty");
  return in;
}

AteResult evaluateAte(const EvalInputs& in, const EvalConfig& cfg) {
  const std::string gt_name = in.gt_file.string(), est_name = in.est_file.string();
  std::vector<MatchedPair> pairs = associate(in.est, in.gt, cfg.max_dt);
  char max_dt_ms[32];
  std::snprintf(max_dt_ms, sizeof(max_dt_ms), "%g", static_cast<double>(cfg.max_dt) * 1e-6);
  if (pairs.empty())
    throw InputError(
        est_name, "no pose is within " + std::string(max_dt_ms) + " ms of a pose of ground truth " + gt_name);
  const std::size_t num_matched = pairs.size();
  if (cfg.window) pairs = filterByGtWindow(pairs, in.gt, *cfg.window);
  if (pairs.empty())
    throw InputError(est_name, "none of the " + std::to_string(num_matched) +
                                   " poses matched with ground truth " + gt_name +
                                   " lies inside the time window");
  try {
    return evaluateAtePairs(in.est, in.gt, std::move(pairs), cfg, in.est_segment_starts);
  } catch (const std::invalid_argument& e) {
    throw InputError(est_name, std::string(e.what()) + " (ground truth " + gt_name + ")");
  }
}

AteResult evaluateAteFiles(const std::filesystem::path& gt_file, const std::filesystem::path& est_file,
                           const EvalConfig& cfg) {
  return evaluateAte(readEvalInputs(gt_file, est_file), cfg);
}

nlohmann::json toJson(const AteResult& r) {
  nlohmann::json j;
  j["trans"] = toJson(r.trans);
  j["rot"] = toJson(r.rot);
  j["rot_oriented"] = toJson(r.rot_oriented);
  j["matched_pairs"] = r.pairs.size();
  j["coverage"] = r.coverage;
  j["alignment"] = toString(r.alignment);
  j["align_frames"] = r.align_frames;
  j["scale"] = r.transform.s;
  j["segments"] = r.segment_transforms.size();
  j["path_off_axis_m"] = r.path_off_axis_m;
  j["alignment_rotation_free"] = rotationFreeAboutPath(r);
  return j;
}

void writeJson(const std::filesystem::path& file, const AteResult& r) { writeJson(file, toJson(r)); }

void writeJson(const std::filesystem::path& file, const nlohmann::json& j) {
  writeTextFile(file, j.dump(2) + "\n");
}

}  // namespace eds::eval
