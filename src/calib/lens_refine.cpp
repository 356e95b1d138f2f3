#include "calib/lens_refine.hpp"

#include <ceres/ceres.h>
#include <ceres/product_manifold.h>

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <memory>
#include <stdexcept>

namespace eds {

void LensRefineConfig::validate() const {
  auto need = [](bool ok, const char* what) {
    if (!ok) throw std::invalid_argument(std::string("lens refinement: ") + what);
  };
  need(huber_px > 0, "huber_px must be positive");
  need(outlier_px > 0, "outlier_px must be positive");
  need(min_parallax_deg >= 0 && min_parallax_deg < 90, "min_parallax_deg must be in [0, 90)");
  need(min_observations >= 2, "min_observations must be >= 2");
  need(max_iterations > 0, "max_iterations must be positive");
  need(split_groups == 0 || (split_groups >= 2 && split_groups <= 16),
       "split_groups must be 0 or in [2, 16]");
}

namespace {

// Parameter blocks: a pose T_c_w as qx qy qz qw tx ty tz (one block: the Schur eliminator is much faster
// with two camera-side blocks per residual than with four), and the lens as k1 k2 p1 p2 k3 fx fy cx cy.
using PoseBlock = std::array<double, 7>;
using LensBlock = std::array<double, 9>;

// Raw-pixel reprojection error of a world point seen by a camera with pose T_c_w.
struct ReprojectionCost {
  explicit ReprojectionCost(const Vec2& obs) : obs_(obs) {}
  template <typename T>
  bool operator()(const T* pose, const T* p_w, const T* lens, T* r) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q_c_w(pose);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t_c_w(pose + 4), point(p_w);
    const Eigen::Matrix<T, 3, 1> p_c = q_c_w * point + t_c_w;
    if (p_c.z() <= T(1e-9)) return false;  // behind the camera: the step is rejected
    T xd, yd;
    distortRadTan(lens, p_c.x() / p_c.z(), p_c.y() / p_c.z(), &xd, &yd);
    r[0] = lens[5] * xd + lens[7] - T(obs_.x());
    r[1] = lens[6] * yd + lens[8] - T(obs_.y());
    return true;
  }
  Vec2 obs_;
};

// Fixes the scale gauge: the distance between the first posed camera (held constant) and the last.
struct BaselineCost {
  BaselineCost(const Vec3& c0, double d0) : c0_(c0), d0_(d0) {}
  template <typename T>
  bool operator()(const T* pose, T* r) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q_c_w(pose);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> t_c_w(pose + 4);
    const Eigen::Matrix<T, 3, 1> c = -(q_c_w.conjugate() * t_c_w);
    r[0] = T(100) * ((c - c0_.cast<T>()).norm() - T(d0_)) / T(d0_);
    return true;
  }
  Vec3 c0_;
  double d0_;
};

struct Observation {
  int frame;
  int point;
  Vec2 px;
  bool inlier = true;
};

// Least-squares intersection of the rays (origin c, unit direction d): the point closest to all.
Vec3 intersectRays(const std::vector<Vec3>& c, const std::vector<Vec3>& d) {
  Mat3 A = Mat3::Zero();
  Vec3 b = Vec3::Zero();
  for (std::size_t i = 0; i < c.size(); ++i) {
    const Mat3 P = Mat3::Identity() - d[i] * d[i].transpose();
    A += P;
    b += P * c[i];
  }
  return A.ldlt().solve(b);
}

// Covariance of the lens parameters (unit residual variance) from the solved problem, with the other
// parameters marginalized; the gauge is fixed by the first pose and the baseline term.
bool lensCovariance(ceres::Problem& problem, const double* lens, Eigen::Matrix<double, 9, 9>* cov) {
  if (problem.IsParameterBlockConstant(lens)) return false;
  ceres::Covariance::Options copts;
  copts.algorithm_type = ceres::SPARSE_QR;
  copts.num_threads = 2;
  ceres::Covariance covariance(copts);
  const std::vector<std::pair<const double*, const double*>> blocks{{lens, lens}};
  if (!covariance.Compute(blocks, &problem)) return false;
  Eigen::Matrix<double, 9, 9, Eigen::RowMajor> c;
  if (!covariance.GetCovarianceBlock(lens, lens, c.data())) return false;
  *cov = c;  // ambient: zero rows and columns where the lens is held
  return cov->allFinite();
}

// The image border's corners and edge midpoints, where a lens error shows most.
std::array<Vec2, 8> borderPixels(const CameraModel& cam) {
  const double w = cam.width - 1, h = cam.height - 1;
  return {Vec2(0, 0),     Vec2(w, 0),     Vec2(0, h),     Vec2(w, h),
          Vec2(w / 2, 0), Vec2(0, h / 2), Vec2(w, h / 2), Vec2(w / 2, h)};
}

// Lens parameter i in the LensBlock order: k1 k2 p1 p2 k3 fx fy cx cy.
double& lensParameter(CameraModel& c, int i) {
  if (i < 5) return c.k[static_cast<std::size_t>(i)];
  return i == 5 ? c.fx : i == 6 ? c.fy : i == 7 ? c.cx : c.cy;
}

// Standard deviation (px, worst direction) of where the lens maps rays through the image border, from the
// covariance of its parameters: one number for how well the data determine the lens.
double borderSigmaPx(const CameraModel& cam, const Eigen::Matrix<double, 9, 9>& cov) {
  double worst = 0;
  for (const Vec2& px : borderPixels(cam)) {
    const Vec3 ray = cam.unproject(px);
    Eigen::Matrix<double, 2, 9> J;
    for (int i = 0; i < 9; ++i) {
      // Numeric derivative of the projection of a fixed ray with respect to each lens parameter.
      CameraModel a = cam, b = cam;
      const double step = i < 5 ? 1e-6 : 1e-4;
      lensParameter(a, i) += step;
      lensParameter(b, i) -= step;
      J.col(i) = (a.project(ray) - b.project(ray)) / (2 * step);
    }
    const Eigen::Matrix2d S = J * cov * J.transpose();
    worst = std::max(
        worst, std::sqrt(std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(S).eigenvalues()(1))));
  }
  return worst;
}

}  // namespace

double lensBorderDifferencePx(const CameraModel& a, const CameraModel& b) {
  double worst = 0;
  for (const Vec2& px : borderPixels(a)) {
    const Vec3 ray = a.unproject(px);
    worst = std::max(worst, (a.project(ray) - b.project(ray)).norm());
  }
  return worst;
}

namespace {

// The bundle adjustment of refineLens: poses, points and the lens, stored where Ceres can point at
// them for the whole solve.
class LensProblem {
 public:
  LensProblem(const CameraModel& camera, const std::vector<std::optional<SE3>>& T_w_c, const LensRefineConfig& cfg,
              int first, int last)
      : camera_(camera), T_w_c_(T_w_c), cfg_(cfg), first_(first), last_(last), pose_(T_w_c.size()) {
    baseline_ = (T_w_c[last]->translation() - T_w_c[first]->translation()).norm();
    CameraModel start = camera;
    if (camera.distortion != Distortion::kRadTan) start.k = {};  // undistorted: radtan with zeros
    for (int i = 0; i < 9; ++i) lens_[static_cast<std::size_t>(i)] = lensParameter(start, i);
    for (std::size_t i = 0; i < T_w_c.size(); ++i) {
      if (!T_w_c[i]) continue;
      const SE3 T_c_w = T_w_c[i]->inverse();
      const Quat& q = T_c_w.quaternion();
      pose_[i] = {q.x(), q.y(), q.z(), q.w(), T_c_w.translation().x(), T_c_w.translation().y(),
                  T_c_w.translation().z()};
    }
  }

  // Triangulates each track from its posed observations with the given lens; returns how many made it.
  std::size_t triangulate(const std::vector<FeatureTrack>& tracks) {
    const double min_cos = std::cos(cfg_.min_parallax_deg * M_PI / 180.0);
    std::vector<Vec3> origins, dirs;
    for (const FeatureTrack& tr : tracks) {
      origins.clear();
      dirs.clear();
      std::vector<Observation> mine;
      for (std::size_t j = 0; j < tr.frames.size(); ++j) {
        const int f = tr.frames[j];
        if (f < 0 || f >= static_cast<int>(T_w_c_.size()) || !T_w_c_[f]) continue;
        const SE3& T = *T_w_c_[f];
        origins.push_back(T.translation());
        dirs.push_back((T.so3() * camera_.unproject(tr.px[j])).normalized());
        mine.push_back({f, static_cast<int>(points_.size()), tr.px[j]});
      }
      if (static_cast<int>(mine.size()) < cfg_.min_observations) continue;
      if (dirs.front().dot(dirs.back()) > min_cos) continue;  // too little parallax for a depth
      const Vec3 X = intersectRays(origins, dirs);
      bool in_front = X.allFinite();
      for (const Observation& o : mine) in_front = in_front && (T_w_c_[o.frame]->inverse() * X).z() > 0;
      if (!in_front) continue;
      points_.push_back(X);
      obs_.insert(obs_.end(), mine.begin(), mine.end());
    }
    return points_.size();
  }

  double residual(const Observation& o) const {
    const ReprojectionCost cost(o.px);
    double r[2];
    if (!cost(pose_[o.frame].data(), points_[o.point].data(), lens_.data(), r)) return 1e9;
    return std::hypot(r[0], r[1]);
  }

  double rms() const {
    double s = 0;
    std::size_t n = 0;
    for (const Observation& o : obs_) {
      if (!o.inlier) continue;
      const double e = residual(o);
      s += e * e;
      ++n;
    }
    return n ? std::sqrt(s / n) : 0.0;
  }

  // Drops the observations the lens cannot explain, and the tracks left too short.
  void rejectOutliers(LensRefineResult& res) {
    for (Observation& o : obs_) o.inlier = residual(o) <= cfg_.outlier_px;
    std::vector<int> count(points_.size(), 0);
    for (const Observation& o : obs_) count[o.point] += o.inlier;
    for (Observation& o : obs_) o.inlier = o.inlier && count[o.point] >= cfg_.min_observations;
    for (int c : count) res.tracks_used += c >= cfg_.min_observations;
  }

  // group >= 0: only the tracks of that group (point index modulo cfg.split_groups), no covariance.
  bool solve(bool lens_free, int group);

  CameraModel lensCamera() const {
    CameraModel c = camera_;
    c.distortion = Distortion::kRadTan;
    for (int i = 0; i < 9; ++i) lensParameter(c, i) = lens_[static_cast<std::size_t>(i)];
    return c;
  }

  // Repeatability: the lens from each of the disjoint groups of tracks, from the full solution, against
  // `full`. Errors along a track are correlated (each position is tracked from the last), which the
  // covariance (independent errors) does not see; whole tracks per group, this spread does.
  double splitSigmaPx(const CameraModel& full) {
    const auto pose0 = pose_;
    const auto points0 = points_;
    const auto lens0 = lens_;
    double sum2 = 0;
    for (int g = 0; g < cfg_.split_groups; ++g) {
      solve(true, g);
      const double d = lensBorderDifferencePx(full, lensCamera());
      sum2 += d * d;
      pose_ = pose0, points_ = points0, lens_ = lens0;
    }
    // Each group holds 1/K of the tracks: the full set's spread is the groups' over sqrt(K).
    const double K = cfg_.split_groups;
    return std::sqrt(sum2 / (K * (K - 1)));
  }

  std::vector<std::optional<SE3>> poses() const {
    std::vector<std::optional<SE3>> out(T_w_c_.size());
    for (std::size_t i = 0; i < T_w_c_.size(); ++i) {
      if (!T_w_c_[i]) continue;
      const Quat q(pose_[i][3], pose_[i][0], pose_[i][1], pose_[i][2]);
      out[i] = SE3(q.normalized(), Vec3(pose_[i][4], pose_[i][5], pose_[i][6])).inverse();
    }
    return out;
  }

  std::size_t observations() const {
    std::size_t n = 0;
    for (const Observation& o : obs_) n += o.inlier;
    return n;
  }

  // The covariance of the lens after the full solve (zero where held); ok false if there is none.
  Eigen::Matrix<double, 9, 9> lens_cov = Eigen::Matrix<double, 9, 9>::Zero();
  bool cov_ok = false;

 private:
  const CameraModel& camera_;
  const std::vector<std::optional<SE3>>& T_w_c_;
  const LensRefineConfig& cfg_;
  int first_, last_;
  double baseline_ = 0;
  LensBlock lens_{};
  std::vector<PoseBlock> pose_;
  std::vector<Vec3> points_;
  std::vector<Observation> obs_;
};

bool LensProblem::solve(bool lens_free, int group) {
  ceres::Solver::Options opts;
  // A few hundred frames at most: the reduced camera system is small enough to be dense; the sparse
  // and the iterative Schur solvers were slower here (the lens block couples every frame).
  opts.linear_solver_type = ceres::DENSE_SCHUR;
  opts.max_num_iterations = cfg_.max_iterations;
  opts.num_threads = 2;
  opts.logging_type = ceres::SILENT;
  ceres::Problem::Options popts;
  popts.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  popts.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(popts);
  ceres::ProductManifold<ceres::EigenQuaternionManifold, ceres::EuclideanManifold<3>> pose_manifold;
  ceres::HuberLoss huber(cfg_.huber_px);
  std::vector<int> used(T_w_c_.size(), 0);
  for (const Observation& o : obs_) {
    if (!o.inlier || (group >= 0 && o.point % cfg_.split_groups != group)) continue;
    auto* cost = new ceres::AutoDiffCostFunction<ReprojectionCost, 2, 7, 3, 9>(new ReprojectionCost(o.px));
    problem.AddResidualBlock(cost, &huber, pose_[o.frame].data(), points_[o.point].data(), lens_.data());
    if (!used[o.frame]) problem.SetManifold(pose_[o.frame].data(), &pose_manifold);
    used[o.frame] = 1;
  }
  if (used[first_]) problem.SetParameterBlockConstant(pose_[first_].data());
  if (used[last_]) {
    const Vec3 c0 = T_w_c_[first_]->translation();
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<BaselineCost, 1, 7>(new BaselineCost(c0, baseline_)),
                             nullptr, pose_[last_].data());
  }
  // Which lens parameters (LensBlock order) move; the others are held as they are.
  const std::array<bool, 9> moves{cfg_.refine_radial,     cfg_.refine_radial,     cfg_.refine_tangential,
                                  cfg_.refine_tangential, cfg_.refine_k3,         cfg_.refine_projection,
                                  cfg_.refine_projection, cfg_.refine_projection, cfg_.refine_projection};
  std::vector<int> held;
  for (int i = 0; i < 9; ++i)
    if (!lens_free || !moves[static_cast<std::size_t>(i)]) held.push_back(i);
  std::unique_ptr<ceres::SubsetManifold> subset;
  if (held.size() == lens_.size()) {
    problem.SetParameterBlockConstant(lens_.data());
  } else if (!held.empty()) {
    subset = std::make_unique<ceres::SubsetManifold>(static_cast<int>(lens_.size()), held);
    problem.SetManifold(lens_.data(), subset.get());
  }
  ceres::Solver::Summary summary;
  ceres::Solve(opts, &problem, &summary);
  if (lens_free && group < 0) cov_ok = lensCovariance(problem, lens_.data(), &lens_cov);
  return summary.IsSolutionUsable() && summary.termination_type == ceres::CONVERGENCE;
}

}  // namespace

LensRefineResult refineLens(const CameraModel& camera, const std::vector<FeatureTrack>& tracks,
                            const std::vector<std::optional<SE3>>& T_w_c, const LensRefineConfig& cfg) {
  cfg.validate();
  if (camera.distortion != Distortion::kRadTan && camera.distortion != Distortion::kNone)
    throw std::invalid_argument("lens refinement: only the radtan model is supported (camera is " +
                                std::string(toString(camera.distortion)) + ")");
  int first = -1, last = -1;
  for (int i = 0; i < static_cast<int>(T_w_c.size()); ++i) {
    if (!T_w_c[i]) continue;
    if (first < 0) first = i;
    last = i;
  }
  if (first < 0 || first == last)
    throw std::invalid_argument("lens refinement: needs at least two posed frames");
  if (!((T_w_c[last]->translation() - T_w_c[first]->translation()).norm() > 0))
    throw std::invalid_argument("lens refinement: the first and last poses coincide");
  LensProblem lp(camera, T_w_c, cfg, first, last);
  constexpr std::size_t kMinTracks = 20;
  if (const std::size_t n = lp.triangulate(tracks); n < kMinTracks)
    throw std::invalid_argument("lens refinement: only " + std::to_string(n) +
                                " tracks are long enough with enough parallax (need " + std::to_string(kMinTracks) +
                                ")");
  LensRefineResult res;
  // 1. Poses and points with the given lens; drop what it cannot explain, and solve again without the
  // outliers: the fair baseline for the refined lens.
  lp.solve(false, -1);
  lp.rejectOutliers(res);
  lp.solve(false, -1);
  res.rms_fixed_px = lp.rms();
  // 2. Everything, lens included.
  res.converged = lp.solve(true, -1);
  res.rms_refined_px = lp.rms();
  res.observations = lp.observations();
  res.camera = lp.lensCamera();
  if (lp.cov_ok) {
    // Scale to the residuals' variance: the covariance above assumes 1 px.
    const double r2 = res.rms_refined_px * res.rms_refined_px;
    res.lens_sigma_cov_px = borderSigmaPx(res.camera, lp.lens_cov * r2);
    res.lens_sigma_px = res.lens_sigma_cov_px;
    for (int i = 0; i < 5; ++i) res.k_sigma[i] = std::sqrt(std::max(0.0, lp.lens_cov(i, i))) * res.rms_refined_px;
  }
  if (cfg.split_groups > 1) {
    res.lens_sigma_split_px = lp.splitSigmaPx(res.camera);
    res.lens_sigma_px = std::isfinite(res.lens_sigma_cov_px) ? std::max(res.lens_sigma_cov_px, res.lens_sigma_split_px)
                                                             : res.lens_sigma_split_px;
  }
  res.T_w_c = lp.poses();
  return res;
}

}  // namespace eds
