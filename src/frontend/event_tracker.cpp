#include "frontend/event_tracker.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "core/image_sampling.hpp"
#include "core/parallel.hpp"
#include "core/robust.hpp"
#include "core/weighted_gram.hpp"

namespace eds {

namespace {
// Below this many points an evaluation costs more to hand out to threads than to do.
constexpr std::size_t kParallelPoints = 1000;

// One pose column and one velocity column of the Jacobian of the normalized residuals:
// jd = −(d − m (mᵀD)/s²)/s and ja = (a − m̂ (m̂ᵀA)/ŝ²)/ŝ (restrict: the compiler vectorizes the loop).
void normalizedColumns(const double* __restrict m, const double* __restrict mh, const double* __restrict d,
                       const double* __restrict a, std::size_t n, double md, double ha, double is, double ish,
                       double* __restrict jd, double* __restrict ja) {
  for (std::size_t k = 0; k < n; ++k) {
    jd[k] = (m[k] * md - d[k]) * is;
    ja[k] = (a[k] - mh[k] * ha) * ish;
  }
}
}  // namespace

void EventTrackerConfig::validate() const {
  if (max_iterations < 1) throw std::invalid_argument("event tracker: max_iterations must be >= 1");
  if (!(huber_initial > 0)) throw std::invalid_argument("event tracker: huber_initial must be > 0");
  if (min_points < 6) throw std::invalid_argument("event tracker: min_points must be >= 6");
  if (!(converged_step_px >= 0)) throw std::invalid_argument("event tracker: converged_step_px must be >= 0");
}

EventTracker::EventTracker(const CameraModel& pinhole, EventTrackerConfig cfg)
    : cam_(pinhole),
      cfg_(cfg),
      huber_(cfg.huber_initial),
      data_var_(std::pow(cfg.huber_initial / 1.345, 2)),
      sums_(kReductionChunks) {
  cfg_.validate();
  if (cam_.distortion != Distortion::kNone)
    throw std::invalid_argument("event tracker: works on the undistorted pinhole camera");
}

void EventTracker::setKeyframe(const Keyframe& kf, int max_points) {
  if (max_points < 0) throw std::invalid_argument("event tracker: max_points must be >= 0 (0: all)");
  p_kf_.clear();
  a_.clear();
  px_kf_.clear();
  g_rho_.clear();
  const auto usable = [](const KeyframePoint& p) { return p.inv_depth > 0 && std::isfinite(p.inv_depth); };
  const auto total = static_cast<std::size_t>(std::count_if(kf.points.begin(), kf.points.end(), usable));
  const auto keep = max_points > 0 ? std::min(total, static_cast<std::size_t>(max_points)) : total;
  std::size_t seen = 0;
  for (const KeyframePoint& p : kf.points) {
    if (!usable(p)) continue;
    // The i-th usable point is kept where i·keep/total crosses an integer: evenly spaced, `keep` of them.
    const std::size_t i = seen++;
    if ((i + 1) * keep / total == i * keep / total) continue;
    p_kf_.push_back(cam_.pinholeRay(p.u, p.v) * (1.0 / p.inv_depth));
    a_.push_back(egmRow(cam_, p.u, p.v, p.gx, p.gy, p.inv_depth));
    px_kf_.emplace_back(p.u, p.v);
    g_rho_.emplace_back(p.gx, p.gy, p.inv_depth);
  }
  if (p_kf_.empty())
    throw std::invalid_argument("event tracker: keyframe " + std::to_string(kf.id) +
                                " has no point with a depth (" + std::to_string(kf.points.size()) +
                                " points)");
  strikes_.assign(p_kf_.size(), 0);
  const auto n = static_cast<Eigen::Index>(p_kf_.size());
  std::vector<double> rho(n);
  for (Eigen::Index i = 0; i < n; ++i) rho[i] = g_rho_[i].z();
  std::nth_element(rho.begin(), rho.begin() + n / 2, rho.end());
  median_inv_depth_ = rho[n / 2];
  m_.resize(n);
  mh_.resize(n);
  D_.resize(n, 6);
  A_.resize(n, 6);
}

void EventTracker::linearizeAt(const SE3& T_ef_kf) {
  const Mat3 R = T_ef_kf.rotationMatrix();
  const Vec3 t = T_ef_kf.translation();
  forEachChunk(
      p_kf_.size(),
      [&](int, std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) {
          // Behind or nearly in the camera's plane the warp degenerates; such a point is out of view anyway.
          if ((R * p_kf_[i] + t).z() <= 1e-3) continue;
          const Vec3& g = g_rho_[i];
          a_[i] = egmRowAtView(cam_, px_kf_[i].x, px_kf_[i].y, g.x(), g.y(), g.z(), T_ef_kf);
        }
      },
      p_kf_.size() >= kParallelPoints);
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
  // Outside a solve the points are those in view at this pose (none is then outside the image).
  chooseSet(T_ef_kf, cfg_.border, delta.cols, delta.rows);
  return evaluateSet(delta, T_ef_kf, nu, r, J, huber_, nullptr);
}

void EventTracker::chooseSet(const SE3& T_ef_kf, double lo, int width, int height) const {
  const Mat3 R = T_ef_kf.rotationMatrix();
  const Vec3 t = T_ef_kf.translation();
  const double hi_x = width - 1 - lo, hi_y = height - 1 - lo;
  solve_set_.clear();
  for (std::size_t i = 0; i < p_kf_.size(); ++i) {
    if (isPersistentOutlier(i)) continue;
    const Vec3 q = R * p_kf_[i] + t;
    if (q.z() <= 1e-6) continue;
    const double ux = cam_.fx * q.x() / q.z() + cam_.cx, uy = cam_.fy * q.y() / q.z() + cam_.cy;
    if (ux >= lo && uy >= lo && ux <= hi_x && uy <= hi_y) solve_set_.push_back(static_cast<int>(i));
  }
  // The set's EGM rows, contiguous by column for the Jacobian; they stay fixed for the whole solve.
  const auto n = static_cast<Eigen::Index>(solve_set_.size());
  for (Eigen::Index k = 0; k < n; ++k) A_.row(k) = a_[static_cast<std::size_t>(solve_set_[k])];
}

void EventTracker::measureChunk(int ch, std::size_t b, std::size_t e, const cv::Mat& delta, const Mat3& R,
                                const Vec3& t, const Vec6& nu, bool jacobian) const {
  const int W = delta.cols, H = delta.rows;
  double* __restrict m = m_.data();
  double* __restrict mh = mh_.data();
  // The prediction m̂ = A ν, a column at a time (contiguous: vectorized).
  std::fill(mh + b, mh + e, 0.0);
  for (int c = 0; c < 6; ++c) {
    const double* a = A_.col(c).data();
    for (std::size_t k = b; k < e; ++k) mh[k] += a[k] * nu[c];
  }
  int inside = 0;
  for (std::size_t k = b; k < e; ++k) {
    const Vec3 q = R * p_kf_[static_cast<std::size_t>(solve_set_[k])] + t;
    const double iz = q.z() > 1e-6 ? 1.0 / q.z() : 0.0;
    const double ux = cam_.fx * q.x() * iz + cam_.cx, uy = cam_.fy * q.y() * iz + cam_.cy;
    if (!(iz > 0 && ux >= cfg_.border && uy >= cfg_.border && ux <= W - 1 - cfg_.border &&
          uy <= H - 1 - cfg_.border)) {
      // A point of the set that left the image measures nothing (m = 0) but keeps its prediction:
      // leaving the image must not be a way to shed residuals. Without this, on a weakly textured view
      // the solver slid the pose along a valley pushing ill-fitting points out (a desk at 5 Hz drifted
      // 20 cm and 15 degrees in 100 ms, the correlation barely changing).
      m[k] = 0;
      if (jacobian) D_.row(static_cast<Eigen::Index>(k)).setZero();
      continue;
    }
    ++inside;
    double gx, gy;
    m[k] = sampleBicubic(delta, ux, uy, &gx, &gy);
    if (jacobian) {
      // d(u)/d(q) then d(q)/d(ξ) = [I, -[q]x] for the left perturbation exp(ξ) T.
      const double dux_dqx = cam_.fx * iz, dux_dqz = -cam_.fx * q.x() * iz * iz;
      const double duy_dqy = cam_.fy * iz, duy_dqz = -cam_.fy * q.y() * iz * iz;
      const Vec3 dm_dq(gx * dux_dqx, gy * duy_dqy, gx * dux_dqz + gy * duy_dqz);
      D_.row(static_cast<Eigen::Index>(k)).head<3>() = dm_dq.transpose();
      D_.row(static_cast<Eigen::Index>(k)).tail<3>() = q.cross(dm_dq).transpose();  // -dm_dqᵀ[q]x
    }
  }
  ChunkSums& sums = sums_[ch];
  sums = ChunkSums{};
  sums.inside = inside;
  sums.mm = dot4(m + b, m + b, e - b);
  sums.hh = dot4(mh + b, mh + b, e - b);
  for (int c = 0; c < 6; ++c) {
    sums.hA[c] = dot4(mh + b, A_.col(c).data() + b, e - b);
    if (jacobian) sums.mD[c] = dot4(m + b, D_.col(c).data() + b, e - b);
  }
}

int EventTracker::evaluateSet(const cv::Mat& delta, const SE3& T_ef_kf, const Vec6& nu, Eigen::VectorXd& r,
                              Eigen::MatrixXd* J, double huber, double* cost) const {
  const Mat3 R = T_ef_kf.rotationMatrix();
  const Vec3 t = T_ef_kf.translation();
  const std::size_t n = solve_set_.size();
  const bool parallel = n >= kParallelPoints;
  forEachChunk(
      n, [&](int ch, std::size_t b, std::size_t e) { measureChunk(ch, b, e, delta, R, t, nu, J != nullptr); },
      parallel);
  ChunkSums total;  // in chunk order: the same sums whatever the threads
  for (const ChunkSums& c : sums_) total.add(c);
  r.resize(static_cast<Eigen::Index>(n));
  if (J) J->resize(static_cast<Eigen::Index>(n), 12);
  if (cost) *cost = 0;
  const double s = std::sqrt(total.mm), sh = std::sqrt(total.hh);
  if (!(s > 0) || !(sh > 0)) {
    r.setZero();
    if (J) J->setZero();
    return total.inside;
  }
  // r = n̂(ν) − n(ξ): dn/dξ = (D − n nᵀD)/s, dn̂/dν = (A − n̂ n̂ᵀA)/ŝ, with n = m/s and n̂ = m̂/ŝ.
  const double is = 1.0 / s, ish = 1.0 / sh;
  const Row6 md = total.mD * (is * is), ha = total.hA * (ish * ish);
  forEachChunk(
      n,
      [&](int ch, std::size_t b, std::size_t e) {
        const double* m = m_.data();
        const double* mh = mh_.data();
        double* rk = r.data();
        double c = 0;
        for (std::size_t k = b; k < e; ++k) rk[k] = mh[k] * ish - m[k] * is, c += huberCost(rk[k], huber);
        sums_[ch].cost = c;
        if (!J) return;
        for (int col = 0; col < 6; ++col)
          normalizedColumns(m + b, mh + b, D_.col(col).data() + b, A_.col(col).data() + b, e - b, md[col],
                            ha[col], is, ish, J->col(col).data() + b, J->col(col + 6).data() + b);
      },
      parallel);
  if (cost)
    for (const ChunkSums& c : sums_) *cost += c.cost;
  return total.inside;
}

namespace {
constexpr double kLambdaFloor = 1e-7;

// Median of |r − median(r)|; 0 for no residuals.
double medianAbsoluteDeviation(const Eigen::VectorXd& r) {
  if (r.size() == 0) return 0;
  std::vector<double> v(r.data(), r.data() + r.size());
  auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  const double med = *mid;
  for (double& x : v) x = std::abs(x - med);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
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

// The normal equations of the Huber-weighted (IRLS) residuals, per chunk of the points as in the
// evaluation, summed in chunk order.
void EventTracker::normalEquations(const Eigen::VectorXd& r, const Eigen::MatrixXd& J, double huber,
                                   Eigen::Matrix<double, 12, 12>& H, Eigen::Matrix<double, 12, 1>& g) const {
  const auto n = static_cast<std::size_t>(r.size());
  w_.resize(r.size());
  wr_.resize(r.size());
  WJ_.resize(r.size(), 12);
  std::array<Eigen::Matrix<double, 12, 12>, kReductionChunks> Hc;
  std::array<Eigen::Matrix<double, 12, 1>, kReductionChunks> gc;
  forEachChunk(
      n,
      [&](int ch, std::size_t b, std::size_t e) {
        const double* rk = r.data();
        double* w = w_.data();
        double* wr = wr_.data();
        for (std::size_t k = b; k < e; ++k) w[k] = huberWeight(rk[k], huber), wr[k] = w[k] * rk[k];
        const double* cols[12];
        const double* wcols[12];
        for (int c = 0; c < 12; ++c) {
          double* wc = WJ_.col(c).data();
          const double* jc = J.col(c).data();
          for (std::size_t k = b; k < e; ++k) wc[k] = w[k] * jc[k];
          cols[c] = jc + b, wcols[c] = wc + b;
        }
        Hc[ch].setZero(), gc[ch].setZero();
        addWeightedGram<12>(cols, wcols, wr_.data() + b, e - b, Hc[ch], gc[ch]);
      },
      n >= kParallelPoints);
  H.setZero(), g.setZero();
  for (int ch = 0; ch < kReductionChunks; ++ch) H += Hc[ch], g += gc[ch];
}

int EventTracker::solveLevel(const cv::Mat& img, SE3& T_ef_kf, Vec6& nu, const PosePrior* prior,
                             Eigen::VectorXd& r, Eigen::MatrixXd& J, double& cost_out,
                             int& iterations) const {
  // This solve's points: those in view at its start, a margin inside the border (a solve moves them a
  // pixel or two; only a runaway takes them out).
  chooseSet(T_ef_kf, cfg_.border + cfg_.set_margin, img.cols, img.rows);
  const double d = huber_;
  double cost = 0;
  int n = evaluateSet(img, T_ef_kf, nu.norm() > 0 ? nu : Vec6::Unit(0), r, &J, d, &cost);
  if (n < cfg_.min_points) return n;
  if (!(nu.norm() > 0)) {
    // ν from linear least squares A ν ≈ m at the initial pose: the best-aligned prediction.
    const Eigen::MatrixXd A = A_.topRows(n);
    const Eigen::Matrix<double, 6, 6> AtA = A.transpose() * A + 1e-9 * Mat6::Identity();
    nu = AtA.ldlt().solve(A.transpose() * m_.head(n));
    if (!(nu.norm() > 0)) nu = Vec6::Unit(0);
    nu.normalize();
    n = evaluateSet(img, T_ef_kf, nu, r, &J, d, &cost);
  }
  LmDamping lm(cfg_.lambda_initial, kLambdaFloor);
  cost += priorCost(prior, data_var_, T_ef_kf);
  int done = 0;
  bool converged = false;
  for (int it = 0; it < cfg_.max_iterations && !converged; ++it) {
    ++done;
    Eigen::Matrix<double, 12, 12> H;
    Eigen::Matrix<double, 12, 1> g;
    normalEquations(r, J, d, H, g);
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
      double data_cost = 0;
      const int n_new = evaluateSet(img, T_new, nu_new, r_try_, &J_try_, d, &data_cost);
      const double cost_new =
          n_new >= cfg_.min_points ? data_cost + priorCost(prior, data_var_, T_new) : 1e300;
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
  const double mad = (cfg_.adapt_huber || outlier_frames_ > 0) ? medianAbsoluteDeviation(r) : 0;
  if (cfg_.adapt_huber && mad > 0) huber_ = 1.345 * 1.4826 * mad, data_var_ = std::pow(1.4826 * mad, 2);
  if (!T_ef_kf.translation().allFinite() || !nu.allFinite()) {
    res.failure = "solver diverged (non-finite state)";
  } else if (res.correlation < cfg_.min_correlation) {
    res.failure =
        "prediction does not explain the events (correlation " + std::to_string(res.correlation) + ")";
  } else {
    res.ok = true;
    if (outlier_frames_ > 0 && mad > 0) countStrikes(r, 1.4826 * mad);
  }
  return res;
}

void EventTracker::setPersistentOutliers(int frames, double sigmas) {
  if (frames < 0 || frames > 255 || (frames > 0 && !(sigmas > 0)))
    throw std::invalid_argument("event tracker: persistent outliers need 0 <= frames <= 255 and sigmas > 0");
  if (frames == 0 && outlier_frames_ > 0) std::fill(strikes_.begin(), strikes_.end(), 0);
  outlier_frames_ = frames;
  outlier_sigmas_ = sigmas;
}

int EventTracker::numPersistentOutliers() const {
  int n = 0;
  for (std::size_t i = 0; i < strikes_.size(); ++i) n += isPersistentOutlier(i);
  return n;
}

// r holds the last solve's residuals, in the order of its set (solve_set_); points outside the set
// keep their counts.
void EventTracker::countStrikes(const Eigen::VectorXd& r, double sigma) {
  const double limit = outlier_sigmas_ * sigma;
  for (Eigen::Index k = 0; k < r.size(); ++k) {
    std::uint8_t& s = strikes_[static_cast<std::size_t>(solve_set_[static_cast<std::size_t>(k)])];
    s = std::abs(r[k]) > limit ? static_cast<std::uint8_t>(std::min(255, s + 1)) : 0;
  }
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
