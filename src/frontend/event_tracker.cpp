#include "frontend/event_tracker.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "core/image_sampling.hpp"
#include "core/robust.hpp"
#include "core/weighted_gram.hpp"

namespace eds {

void EventTrackerConfig::validate() const {
  if (max_iterations < 1) throw std::invalid_argument("event tracker: max_iterations must be >= 1");
  if (!(huber_initial > 0)) throw std::invalid_argument("event tracker: huber_initial must be > 0");
  if (min_points < 6) throw std::invalid_argument("event tracker: min_points must be >= 6");
  if (!(converged_step_px >= 0)) throw std::invalid_argument("event tracker: converged_step_px must be >= 0");
}

EventTracker::EventTracker(const CameraModel& pinhole, EventTrackerConfig cfg)
    : cam_(pinhole), cfg_(cfg), huber_(cfg.huber_initial), data_var_(std::pow(cfg.huber_initial / 1.345, 2)) {
  cfg_.validate();
  if (cam_.distortion != Distortion::kNone)
    throw std::invalid_argument("event tracker: works on the undistorted pinhole camera");
}

void EventTracker::setKeyframe(const Keyframe& kf) {
  p_kf_.clear();
  a_.clear();
  px_kf_.clear();
  g_rho_.clear();
  for (const KeyframePoint& p : kf.points) {
    if (!(p.inv_depth > 0) || !std::isfinite(p.inv_depth)) continue;
    p_kf_.push_back(cam_.pinholeRay(p.u, p.v) * (1.0 / p.inv_depth));
    a_.push_back(egmRow(cam_, p.u, p.v, p.gx, p.gy, p.inv_depth));
    px_kf_.emplace_back(p.u, p.v);
    g_rho_.emplace_back(p.gx, p.gy, p.inv_depth);
  }
  if (p_kf_.empty())
    throw std::invalid_argument("event tracker: keyframe " + std::to_string(kf.id) +
                                " has no point with a depth (" + std::to_string(kf.points.size()) +
                                " points)");
  const auto n = static_cast<Eigen::Index>(p_kf_.size());
  std::vector<double> rho(n);
  for (Eigen::Index i = 0; i < n; ++i) rho[i] = g_rho_[i].z();
  std::nth_element(rho.begin(), rho.begin() + n / 2, rho.end());
  median_inv_depth_ = rho[n / 2];
  idx_.reserve(n);
  m_.resize(n);
  mh_.resize(n);
  D_.resize(n, 6);
  A_.resize(n, 6);
}

void EventTracker::linearizeAt(const SE3& T_ef_kf) {
  const Mat3 R = T_ef_kf.rotationMatrix();
  const Vec3 t = T_ef_kf.translation();
  for (std::size_t i = 0; i < p_kf_.size(); ++i) {
    // Behind or nearly in the camera's plane the warp degenerates; such a point is out of view anyway.
    if ((R * p_kf_[i] + t).z() <= 1e-3) continue;
    const Vec3& g = g_rho_[i];
    a_[i] = egmRowAtView(cam_, px_kf_[i].x, px_kf_[i].y, g.x(), g.y(), g.z(), T_ef_kf);
  }
}

int EventTracker::pointsInView(const SE3& T_ef_kf, int width, int height) const {
  int n = 0;
  for (const Vec3& p : p_kf_) {
    const Vec3 q = T_ef_kf * p;
    if (q.z() <= 1e-6) continue;
    const Vec2 u(cam_.fx * q.x() / q.z() + cam_.cx, cam_.fy * q.y() / q.z() + cam_.cy);
    n += u.x() >= cfg_.border && u.y() >= cfg_.border && u.x() <= width - 1 - cfg_.border &&
         u.y() <= height - 1 - cfg_.border;
  }
  return n;
}

int EventTracker::evaluate(const cv::Mat& delta, const SE3& T_ef_kf, const Vec6& nu, Eigen::VectorXd& r,
                           Eigen::MatrixXd* J) const {
  const int W = delta.cols, H = delta.rows;
  const Mat3 R = T_ef_kf.rotationMatrix();
  const Vec3 t = T_ef_kf.translation();
  idx_.clear();
  Eigen::Index k = 0;
  int inside = 0;
  const std::size_t count = use_set_ ? solve_set_.size() : p_kf_.size();
  for (std::size_t j = 0; j < count; ++j) {
    const std::size_t i = use_set_ ? static_cast<std::size_t>(solve_set_[j]) : j;
    const Vec3 q = R * p_kf_[i] + t;
    const double iz = q.z() > 1e-6 ? 1.0 / q.z() : 0.0;
    const double ux = cam_.fx * q.x() * iz + cam_.cx, uy = cam_.fy * q.y() * iz + cam_.cy;
    if (!(iz > 0 && ux >= cfg_.border && uy >= cfg_.border && ux <= W - 1 - cfg_.border &&
          uy <= H - 1 - cfg_.border)) {
      if (!use_set_) continue;
      // A point of this solve's set that left the image measures nothing (m = 0) but keeps its
      // prediction: leaving the image must not be a way to shed residuals. Without this, on a
      // weakly textured view the solver slid the pose along a valley pushing ill-fitting points out
      // (a desk at 5 Hz drifted 20 cm and 15 degrees in 100 ms, the correlation barely changing).
      m_[k] = 0;
      if (J) D_.row(k).setZero(), A_.row(k) = a_[i];
      mh_[k] = a_[i].dot(nu);
      idx_.push_back(static_cast<int>(i));
      ++k;
      continue;
    }
    ++inside;
    double gx, gy;
    m_[k] = sampleBicubic(delta, ux, uy, &gx, &gy);
    if (J) {
      // d(u)/d(q) then d(q)/d(ξ) = [I, -[q]x] for the left perturbation exp(ξ) T.
      const double dux_dqx = cam_.fx * iz, dux_dqz = -cam_.fx * q.x() * iz * iz;
      const double duy_dqy = cam_.fy * iz, duy_dqz = -cam_.fy * q.y() * iz * iz;
      const Vec3 dm_dq(gx * dux_dqx, gy * duy_dqy, gx * dux_dqz + gy * duy_dqz);
      D_.row(k).head<3>() = dm_dq.transpose();
      D_.row(k).tail<3>() = q.cross(dm_dq).transpose();  // -dm_dq^T [q]x = (q x dm_dq)^T
      A_.row(k) = a_[i];
    }
    mh_[k] = a_[i].dot(nu);
    idx_.push_back(static_cast<int>(i));
    ++k;
  }
  const Eigen::Index n = k;
  r.resize(n);
  if (n == 0) return 0;
  const double s = m_.head(n).norm(), sh = mh_.head(n).norm();
  if (!(s > 0) || !(sh > 0)) {
    r.setZero();
    if (J) J->setZero(n, 12);
    return inside;
  }
  r = mh_.head(n) / sh - m_.head(n) / s;
  if (J) {
    // r = n̂(ν) − n(ξ): dn/dξ = (D − n nᵀD)/s, dn̂/dν = (A − n̂ n̂ᵀA)/ŝ.
    const Eigen::VectorXd nn = m_.head(n) / s, nh = mh_.head(n) / sh;
    J->resize(n, 12);
    const Row6 nD = nn.transpose() * D_.topRows(n);
    const Row6 nA = nh.transpose() * A_.topRows(n);
    J->leftCols<6>() = -(D_.topRows(n) - nn * nD) / s;
    J->rightCols<6>() = (A_.topRows(n) - nh * nA) / sh;
  }
  return inside;
}

namespace {
constexpr double kLambdaFloor = 1e-7;

double huberSum(const Eigen::VectorXd& r, double d) {
  double c = 0;
  for (Eigen::Index i = 0; i < r.size(); ++i) c += eds::huberCost(r[i], d);
  return c;
}

// The prior's cost ½ eᵀ Σ⁻¹ e (times the data variance) and its error e at T.
double priorCost(const PosePrior* prior, double scale, const SE3& T, Vec6* e_out = nullptr) {
  if (!prior) return 0;
  const Vec6 e = (T * prior->T_ef_kf.inverse()).log();
  if (e_out) *e_out = e;
  return 0.5 * scale * e.cwiseQuotient(prior->sigma).squaredNorm();
}
}  // namespace

double accumulatePosePrior(const PosePrior& prior, double scale, const SE3& T_ef_kf,
                           Eigen::Matrix<double, 12, 12>& H, Eigen::Matrix<double, 12, 1>& g) {
  Vec6 e;
  const double cost = priorCost(&prior, scale, T_ef_kf, &e);
  const Vec6 info = scale * prior.sigma.cwiseProduct(prior.sigma).cwiseInverse();
  H.topLeftCorner<6, 6>().diagonal() += info;
  g.head<6>() += info.cwiseProduct(e);
  return cost;
}

int EventTracker::solveLevel(const cv::Mat& img, SE3& T_ef_kf, Vec6& nu, const PosePrior* prior,
                             Eigen::VectorXd& r, Eigen::MatrixXd& J, double& cost_out,
                             int& iterations) const {
  // This solve's points: those in view at its start, a margin inside the border (a solve moves them a
  // pixel or two; only a runaway takes them out).
  const Mat3 R = T_ef_kf.rotationMatrix();
  const Vec3 t = T_ef_kf.translation();
  const double lo = cfg_.border + cfg_.set_margin, hi_x = img.cols - 1 - lo, hi_y = img.rows - 1 - lo;
  solve_set_.clear();
  for (std::size_t i = 0; i < p_kf_.size(); ++i) {
    const Vec3 q = R * p_kf_[i] + t;
    if (q.z() <= 1e-6) continue;
    const double ux = cam_.fx * q.x() / q.z() + cam_.cx, uy = cam_.fy * q.y() / q.z() + cam_.cy;
    if (ux >= lo && uy >= lo && ux <= hi_x && uy <= hi_y) solve_set_.push_back(static_cast<int>(i));
  }
  use_set_ = true;
  struct Reset {  // evaluate() called from outside a solve sees every point again
    bool& flag;
    ~Reset() { flag = false; }
  } reset{use_set_};
  int n = evaluate(img, T_ef_kf, nu.norm() > 0 ? nu : Vec6::Unit(0), r, &J);
  if (n < cfg_.min_points) return n;
  if (!(nu.norm() > 0)) {
    // ν from linear least squares A ν ≈ m at the initial pose: the best-aligned prediction.
    const Eigen::MatrixXd A = A_.topRows(n);
    const Eigen::Matrix<double, 6, 6> AtA = A.transpose() * A + 1e-9 * Mat6::Identity();
    nu = AtA.ldlt().solve(A.transpose() * m_.head(n));
    if (!(nu.norm() > 0)) nu = Vec6::Unit(0);
    nu.normalize();
    n = evaluate(img, T_ef_kf, nu, r, &J);
  }
  LmDamping lm(cfg_.lambda_initial, kLambdaFloor);
  const double d = huber_;
  double cost = huberSum(r, d) + priorCost(prior, data_var_, T_ef_kf);
  int done = 0;
  bool converged = false;
  for (int it = 0; it < cfg_.max_iterations && !converged; ++it) {
    ++done;
    // Normal equations with the IRLS weights of the Huber norm (J is column-major: its columns are
    // contiguous).
    w_.resize(r.size());
    for (Eigen::Index i = 0; i < r.size(); ++i) w_[i] = huberWeight(r[i], d);
    WJ_ = J.array().colwise() * w_.array();
    wr_ = w_.cwiseProduct(r);
    const double* cols[12];
    const double* wcols[12];
    for (int c = 0; c < 12; ++c) cols[c] = J.col(c).data(), wcols[c] = WJ_.col(c).data();
    Eigen::Matrix<double, 12, 12> H = Eigen::Matrix<double, 12, 12>::Zero();
    Eigen::Matrix<double, 12, 1> g = Eigen::Matrix<double, 12, 1>::Zero();
    addWeightedGram<12>(cols, wcols, wr_.data(), static_cast<std::size_t>(r.size()), H, g);
    if (prior) accumulatePosePrior(*prior, data_var_, T_ef_kf, H, g);
    bool improved = false;
    for (int tries = 0; tries < 6 && !improved; ++tries) {
      Eigen::Matrix<double, 12, 12> Hd = H;
      Hd.diagonal() += lm.lambda() * H.diagonal() + Eigen::Matrix<double, 12, 1>::Constant(1e-12);
      const Eigen::Matrix<double, 12, 1> delta = -Hd.ldlt().solve(g);
      if (!delta.allFinite()) break;
      const SE3 T_new = SE3::exp(delta.head<6>()) * T_ef_kf;
      Vec6 nu_new = nu + delta.tail<6>();
      nu_new.normalize();
      const int n_new = evaluate(img, T_new, nu_new, r_try_, &J_try_);
      const double cost_new =
          n_new >= cfg_.min_points ? huberSum(r_try_, d) + priorCost(prior, data_var_, T_new) : 1e300;
      if (cost_new < cost) {
        const double gain = cost - cost_new;
        T_ef_kf = T_new;
        nu = nu_new;
        r.swap(r_try_);
        J.swap(J_try_);
        n = n_new;
        cost = cost_new;
        lm.accepted();
        improved = true;
        // Converged when the cost barely moves or the step moves the points by a small fraction of a
        // pixel (rotation, and translation at the median depth): what the events resolve.
        const double step_px =
            cam_.fx * (delta.segment<3>(3).norm() + delta.head<3>().norm() * median_inv_depth_);
        converged = gain < 1e-4 * cost || step_px < cfg_.converged_step_px;
      } else {
        lm.rejected();
      }
    }
    if (!improved) break;
  }
  iterations += done;
  cost_out = cost;
  return n;
}

TrackResult EventTracker::track(const EventFrame& ef, SE3& T_ef_kf, Vec6& nu, int levels,
                                const PosePrior* prior) {
  TrackResult res;
  if (p_kf_.empty()) throw std::logic_error("EventTracker::track before setKeyframe");
  if (cfg_.egm_at_view) linearizeAt(T_ef_kf);
  int n = pointsInView(T_ef_kf, ef.delta.cols, ef.delta.rows);
  if (n < cfg_.min_points) {
    res.points_in_view = n;
    res.failure = "only " + std::to_string(n) + " points in view";
    return res;
  }
  // Coarse to fine: the event frame blurred more at first widens the basin of convergence (a 3x3
  // blurred edge pulls the points from ~1-2 px only).
  Eigen::VectorXd r;
  Eigen::MatrixXd J;
  double cost = 0;
  int iterations = 0;
  for (int level = (levels > 0 ? levels : cfg_.levels) - 1; level >= 0; --level) {
    const cv::Mat* img = &ef.delta;
    if (level > 0) {
      const double sigma = 1.5 * (1 << (level - 1));
      cv::GaussianBlur(ef.delta, blurred_, cv::Size(0, 0), sigma, sigma, cv::BORDER_REPLICATE);
      img = &blurred_;
    }
    n = solveLevel(*img, T_ef_kf, nu, prior, r, J, cost, iterations);
    if (n < cfg_.min_points) break;
  }
  const int it = iterations;
  res.iterations = it;
  res.points_in_view = n;
  res.cost = cost;
  // Correlation of the normalized vectors: 1 - |r|^2 / 2.
  res.correlation = 1.0 - 0.5 * r.squaredNorm();
  if (cfg_.adapt_huber && r.size() > 0) {
    std::vector<double> v(r.data(), r.data() + r.size());
    auto mid = v.begin() + v.size() / 2;
    std::nth_element(v.begin(), mid, v.end());
    const double med = *mid;
    for (double& x : v) x = std::abs(x - med);
    std::nth_element(v.begin(), mid, v.end());
    const double mad = *mid;
    if (mad > 0) huber_ = 1.345 * 1.4826 * mad, data_var_ = std::pow(1.4826 * mad, 2);
  }
  if (!T_ef_kf.translation().allFinite() || !nu.allFinite()) {
    res.failure = "solver diverged (non-finite state)";
  } else if (res.correlation < cfg_.min_correlation) {
    res.failure =
        "prediction does not explain the events (correlation " + std::to_string(res.correlation) + ")";
  } else {
    res.ok = true;
  }
  return res;
}

cv::Mat EventTracker::predictedImage(const SE3& T_ef_kf, const Vec6& nu, int width, int height) const {
  cv::Mat img(height, width, CV_32F, cv::Scalar(0));
  double s = 0;
  for (std::size_t i = 0; i < a_.size(); ++i) {
    const Vec3 p = T_ef_kf * p_kf_[i];
    if (p.z() <= 0) continue;
    const Vec2 u = cam_.project(p);
    const long x = std::lround(u.x()), y = std::lround(u.y());
    if (x < 0 || y < 0 || x >= width || y >= height) continue;
    const double v = a_[i].dot(nu);
    img.at<float>(static_cast<int>(y), static_cast<int>(x)) = static_cast<float>(v);
    s += v * v;
  }
  if (s > 0) img /= std::sqrt(s);
  return img;
}

}  // namespace eds
