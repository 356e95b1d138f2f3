#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <random>

#include "backend/photometric_ba.hpp"
#include "core/image_sampling.hpp"
#include "core/robust.hpp"
#include "frontend/frame_tracker.hpp"
#include "frontend/point_selection.hpp"
#include "map/keyframe.hpp"
#include "sim/presets.hpp"
#include "sim/simulator.hpp"
#include "sim_frames.hpp"

namespace eds {
namespace {

CameraModel camera() { return test::simCamera(); }
using Frames = test::FrameSink;

// Frames of a textured plane along the hand-held motion, every 0.4 s (baselines of several cm, so
// that depth is observable).
struct Scene {
  sim::Motion motion{sim::handheldMotion(2.01, 9)};
  Frames frames;
  Scene() {
    // A plane (no occlusions).
    sim::Scene scene = sim::makePreset("planar", motion, 9);
    scene.loadTextures();
    sim::SimConfig cfg;
    cfg.fps = 1.0 / 0.4;
    cfg.render.supersample = 2;
    cfg.events.C_pos = cfg.events.C_neg = 1.0;  // events are not needed here
    sim::Simulator(scene, camera(), motion, cfg).run(motion.start(), motion.end(), frames);
  }
};

Scene& scene() {
  static Scene s;
  return s;
}

// The first F frames with their images at their true poses.
std::vector<BaFrame> framesAtTruth(const Scene& s, int F) {
  std::vector<BaFrame> frames(F);
  for (int f = 0; f < F; ++f) {
    frames[f].image = s.frames.images[f];
    frames[f].T_w_c = s.motion.pose(s.frames.times[f]);
  }
  return frames;
}

std::vector<BaPoint> pointsOf(const Scene& s, int host, double depth_noise, std::mt19937& rng, int F) {
  Keyframe kf;
  setKeyframeImage(kf, s.frames.images[host]);
  PointSelectionConfig pc;
  pc.tile = 16;
  pc.fraction = 0.02;
  std::normal_distribution<double> noise(0.0, 1.0);
  std::vector<BaPoint> pts;
  for (const cv::Point& q : selectPoints(kf.grad_x, kf.grad_y, pc)) {
    const float z = s.frames.depths[host].at<float>(q.y, q.x);
    if (!(z > 0)) continue;
    BaPoint p;
    p.host = host;
    p.u = static_cast<float>(q.x);
    p.v = static_cast<float>(q.y);
    p.inv_depth = 1.0 / (z * (1.0 + depth_noise * noise(rng)));
    for (int t = 0; t < F; ++t)
      if (t != host) p.targets.push_back(t);
    pts.push_back(p);
  }
  return pts;
}

// Every column of the residual's Jacobian (host pose, a, b; target pose, a, b; inverse depth) against
// central differences, with non-zero affine brightness on both frames, in both directions (points
// hosted in either frame: neither is special to evaluate()).
TEST(PhotometricBA, JacobianMatchesNumericDifferencesInEveryColumn) {
  const Scene& s = scene();
  std::vector<BaFrame> frames(2);
  const double a[2] = {0.08, -0.05}, b[2] = {0.03, -0.02};
  for (int f = 0; f < 2; ++f) {
    frames[f].T_w_c = s.motion.pose(s.frames.times[f]);
    frames[f].image = s.frames.images[f];
    frames[f].a = a[f];
    frames[f].b = b[f];
  }
  PhotometricBA ba(camera(), {});
  for (int host = 0; host < 2; ++host) {
    const int target = 1 - host;
    std::mt19937 rng(1 + host);
    const std::vector<BaPoint> pts = pointsOf(s, host, 0.05, rng, 2);
    int checked = 0;
    double worst = 0;
    for (std::size_t i = 0; i < pts.size() && checked < 40; i += 7) {
      Eigen::Matrix<double, 8, 1> r, rp, rm;
      Eigen::Matrix<double, 8, 17> J, Jn;
      if (!ba.evaluate(frames, pts[i], target, r, &J)) continue;
      const double h = 1e-7;
      bool ok = true;
      for (int c = 0; c < 17 && ok; ++c) {
        std::vector<BaFrame> fp = frames, fm = frames;
        BaPoint pp = pts[i], pm = pts[i];
        const int f = c < 8 ? host : target, k = c % 8;
        if (c == 16) {
          pp.inv_depth += h, pm.inv_depth -= h;
        } else if (k < 6) {
          fp[f].T_w_c = SE3::exp(Vec6::Unit(k) * h) * frames[f].T_w_c;
          fm[f].T_w_c = SE3::exp(-Vec6::Unit(k) * h) * frames[f].T_w_c;
        } else if (k == 6) {
          fp[f].a += h, fm[f].a -= h;
        } else {
          fp[f].b += h, fm[f].b -= h;
        }
        ok = ba.evaluate(fp, pp, target, rp, nullptr) && ba.evaluate(fm, pm, target, rm, nullptr);
        Jn.col(c) = (rp - rm) / (2 * h);
      }
      if (!ok) continue;
      ++checked;
      for (int c = 0; c < 17; ++c) {  // no column skipped: a zero column must be zero in both
        const double err = (J.col(c) - Jn.col(c)).norm();
        EXPECT_LE(err, 1e-6 + 1e-4 * Jn.col(c).norm()) << "host " << host << ", column " << c;
        worst = std::max(worst, err / (1e-6 + Jn.col(c).norm()));
      }
    }
    EXPECT_GT(checked, 20) << "host " << host;
    std::printf("[ BA Jacobian, host %d ] %d points, worst relative column error %.2e\n", host, checked,
                worst);
  }
}

// The normal equations the solve builds (blocks assembled from one Gram matrix per point and target)
// equal JᵀJ and Jᵀr of evaluate()'s Jacobian, checked itself above: three frames with different
// brightness (so that e^(a_t − a_h) ≠ 1 in the host's and the cross terms), points hosted in each,
// robust and gradient weights at 1.
TEST(PhotometricBA, NormalEquationsAreTheJacobiansGram) {
  const Scene& s = scene();
  const int F = 3;
  std::vector<BaFrame> frames = framesAtTruth(s, F);
  const double a[F] = {0.1, -0.15, 0.05}, b[F] = {0.02, -0.03, 0.01};
  for (int f = 0; f < F; ++f) frames[f].a = a[f], frames[f].b = b[f];
  std::mt19937 rng(5);
  std::vector<BaPoint> pts;
  for (int host = 0; host < F; ++host) {
    const std::vector<BaPoint> p = pointsOf(s, host, 0.03, rng, F);
    for (std::size_t i = 0; i < p.size(); i += 5) pts.push_back(p[i]);
  }
  BaConfig cfg;
  cfg.huber = cfg.grad_weight_c = 1e9;
  const PhotometricBA ba(camera(), cfg);
  Eigen::MatrixXd H;
  Eigen::VectorXd g;
  ba.denseNormalEquations(frames, pts, H, g);
  const auto n = static_cast<Eigen::Index>(8 * F + pts.size());
  Eigen::MatrixXd Hn = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd gn = Eigen::VectorXd::Zero(n);
  int pairs = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    for (int t : pts[i].targets) {
      Eigen::Matrix<double, 8, 1> r;
      Eigen::Matrix<double, 8, 17> J;
      if (!ba.evaluate(frames, pts[i], t, r, &J)) continue;
      Eigen::MatrixXd Jf = Eigen::MatrixXd::Zero(8, n);
      Jf.middleCols<8>(8 * pts[i].host) = J.leftCols<8>();
      Jf.middleCols<8>(8 * t) = J.middleCols<8>(8);
      Jf.col(8 * F + static_cast<Eigen::Index>(i)) = J.col(16);
      Hn += Jf.transpose() * Jf;
      gn += Jf.transpose() * r;
      ++pairs;
    }
  }
  ASSERT_GT(pairs, 100);
  ASSERT_EQ(H.rows(), n);
  const double scale = Hn.cwiseAbs().maxCoeff();
  EXPECT_LT((H - Hn).cwiseAbs().maxCoeff(), 1e-9 * scale);
  // Block by block, so that a wrong small block (the brightness offsets') is not lost in the norm.
  for (int f = 0; f < F; ++f)
    for (int h = 0; h < F; ++h) {
      const Eigen::MatrixXd d = H.block<8, 8>(8 * f, 8 * h) - Hn.block<8, 8>(8 * f, 8 * h);
      EXPECT_LT(d.norm(), 1e-9 * (1.0 + Hn.block<8, 8>(8 * f, 8 * h).norm())) << f << "," << h;
      EXPECT_LT((g.segment<8>(8 * f) - gn.segment<8>(8 * f)).norm(),
                1e-9 * (1.0 + gn.segment<8>(8 * f).norm()))
          << "frame " << f;
    }
  EXPECT_LT((g.tail(n - 8 * F) - gn.tail(n - 8 * F)).norm(), 1e-9 * (1.0 + gn.norm()));
  std::printf("[ BA normal equations ] %d pairs, worst |H - JᵀJ| %.2e of %.2e\n", pairs,
              (H - Hn).cwiseAbs().maxCoeff(), scale);
}

// The energy the solver minimizes: every pattern residual's Huber norm, weighted by the host's
// gradient, c² / (c² + |∇I_h|²), summed here pixel by pixel from evaluate().
TEST(PhotometricBA, InitialCostIsTheGradientWeightedHuberEnergy) {
  const Scene& s = scene();
  const int F = 3;
  std::vector<BaFrame> frames = framesAtTruth(s, F);
  std::mt19937 rng(9);
  std::vector<BaPoint> pts;
  for (int host = 0; host < F; ++host) {
    const std::vector<BaPoint> p = pointsOf(s, host, 0.1, rng, F);
    pts.insert(pts.end(), p.begin(), p.end());
  }
  BaConfig cfg;
  cfg.iterations = 1;
  const PhotometricBA ba(camera(), cfg);
  constexpr int kDsoPattern[8][2] = {{0, -2}, {-1, -1}, {1, -1}, {-2, 0}, {0, 0}, {2, 0}, {-1, 1}, {0, 2}};
  const double c2 = cfg.grad_weight_c * cfg.grad_weight_c;
  double energy = 0, unweighted = 0;
  for (const BaPoint& p : pts)
    for (int t : p.targets) {
      Eigen::Matrix<double, 8, 1> r;
      if (!ba.evaluate(frames, p, t, r, nullptr)) continue;
      for (int k = 0; k < 8; ++k) {
        double gx, gy;
        sampleBilinear(frames[p.host].image, p.u + kDsoPattern[k][0], p.v + kDsoPattern[k][1], gx, gy);
        energy += c2 / (c2 + gx * gx + gy * gy) * huberCost(r[k], cfg.huber);
        unweighted += huberCost(r[k], cfg.huber);
      }
    }
  ASSERT_GT(energy, 0);
  ASSERT_GT(unweighted, 1.05 * energy);  // the weights matter on this scene
  std::vector<BaFrame> f = frames;
  const BaStats st = ba.optimize(f, pts);
  EXPECT_NEAR(st.initial_cost, energy, 1e-9 * energy);
  std::printf("[ BA energy ] %.6g (unweighted %.6g)\n", energy, unweighted);
}

// The residual itself: with both frames at one pose and one image, the geometry cancels and only the
// affine brightness model remains, r = I - b_t - e^(a_t - a_h) (I - b_h), at any depth.
TEST(PhotometricBA, ResidualIsTheAffineBrightnessModel) {
  const Scene& s = scene();
  std::vector<BaFrame> frames(2);
  for (int f = 0; f < 2; ++f) {
    frames[f].T_w_c = s.motion.pose(s.frames.times[0]);
    frames[f].image = s.frames.images[0];
  }
  frames[0].a = 0.12, frames[0].b = 0.04;
  frames[1].a = -0.07, frames[1].b = -0.03;
  PhotometricBA ba(camera(), {});
  BaPoint p;
  p.host = 0;
  p.u = 100.3f, p.v = 70.6f;
  p.inv_depth = 0.4;
  Eigen::Matrix<double, 8, 1> r;
  ASSERT_TRUE(ba.evaluate(frames, p, 1, r, nullptr));
  const double e = std::exp(frames[1].a - frames[0].a);
  // DSO's 8-pixel residual pattern.
  const int pattern[8][2] = {{0, -2}, {-1, -1}, {1, -1}, {-2, 0}, {0, 0}, {2, 0}, {-1, 1}, {0, 2}};
  for (int k = 0; k < 8; ++k) {
    const double I = sampleBilinear(frames[0].image, p.u + pattern[k][0], p.v + pattern[k][1]);
    EXPECT_NEAR(r[k], I - frames[1].b - e * (I - frames[0].b), 1e-6) << "pattern pixel " << k;
  }
}

TEST(PhotometricBA, RefinesPosesAndDepthsOfASimulatedPlane) {
  const Scene& s = scene();
  const int F = static_cast<int>(s.frames.images.size());
  ASSERT_GE(F, 4);
  std::mt19937 rng(2);
  std::vector<BaFrame> frames(F);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int f = 0; f < F; ++f) {
    frames[f].image = s.frames.images[f];
    frames[f].T_w_c = s.motion.pose(s.frames.times[f]);
    frames[f].fixed = f < 2;  // gauge: the first two keyframes (pose and scale)
    if (!frames[f].fixed) {
      Vec6 xi;
      for (int k = 0; k < 3; ++k) xi[k] = 0.003 * n(rng), xi[k + 3] = 0.002 * n(rng);
      frames[f].T_w_c = SE3::exp(xi) * frames[f].T_w_c;
    }
  }
  const double noise = 0.1;
  std::vector<BaPoint> pts = pointsOf(s, 0, noise, rng, F);
  const auto more = pointsOf(s, 1, noise, rng, F);
  pts.insert(pts.end(), more.begin(), more.end());
  const auto depthError = [&](const std::vector<BaPoint>& ps) {
    double ss = 0;
    int c = 0;
    for (const BaPoint& p : ps) {
      if (p.outlier || p.targets.empty()) continue;
      const float z = s.frames.depths[p.host].at<float>(static_cast<int>(p.v), static_cast<int>(p.u));
      ss += std::pow(1.0 / p.inv_depth / z - 1.0, 2);
      ++c;
    }
    return std::sqrt(ss / c);
  };
  const auto poseError = [&](const std::vector<BaFrame>& fr) {
    double worst = 0;
    for (int f = 0; f < F; ++f)
      worst = std::max(worst,
                       (fr[f].T_w_c.translation() - s.motion.pose(s.frames.times[f]).translation()).norm());
    return worst;
  };
  const double d0 = depthError(pts), p0 = poseError(frames);
  BaConfig cfg;
  cfg.iterations = 30;
  const BaStats st = PhotometricBA(camera(), cfg).optimize(frames, pts);
  const double d1 = depthError(pts), p1 = poseError(frames);
  double ratio = 0;
  int nr = 0;
  for (const BaPoint& p : pts)
    if (!p.outlier && !p.targets.empty())
      ratio +=
          1.0 / p.inv_depth / s.frames.depths[p.host].at<float>(static_cast<int>(p.v), static_cast<int>(p.u)),
          ++nr;
  std::printf("[ ba ] mean depth ratio %.4f over %d points\n", ratio / nr, nr);
  EXPECT_NEAR(ratio / nr, 1.0, 0.01);
  std::printf(
      "[ ba ] %zu points, %d residuals, rmse %.4f -> %.4f, depth error %.1f%% -> %.1f%%, worst position "
      "error %.2f mm -> %.2f mm, %d outlier observations\n",
      pts.size(), st.residuals, st.initial_rmse, st.final_rmse, d0 * 100, d1 * 100, p0 * 1e3, p1 * 1e3,
      st.outliers_removed);
  EXPECT_LT(st.final_rmse, st.initial_rmse * 0.5);
  EXPECT_LT(d1, d0 / 3);
  EXPECT_LT(p1, 2e-3);
}

// Gauss-Newton is exact on the linearized problem: from near the optimum (poses 1 mm / 0.06 deg off,
// depths 2 % off) one undamped step of the Schur-complement solve and the point back-substitution goes
// most of the way to the converged cost. A wrong frame-point coupling in the back-substitution leaves
// the depths off and the cost barely lower.
// Four frames near the truth (the last two free: poses 1 mm / 0.06 deg off) and points hosted in the
// first `hosts`, depths 2 % off. `a`, `b`: each frame's true affine brightness (its image is e^a I + b);
// the free frames start `da` and `db` away from theirs.
void oneStepAndConverged(const double (&a)[4], const double (&b)[4], double da, double db, int hosts,
                         const char* name) {
  const Scene& s = scene();
  const int F = 4;
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<BaFrame> frames = framesAtTruth(s, F);
  for (int f = 0; f < F; ++f) {
    frames[f].image = frames[f].image * std::exp(a[f]) + b[f];
    frames[f].fixed = f < 2;
    frames[f].a = a[f] + (frames[f].fixed ? 0.0 : da);
    frames[f].b = b[f] + (frames[f].fixed ? 0.0 : db);
    if (frames[f].fixed) continue;
    Vec6 xi;
    for (int k = 0; k < 3; ++k) xi[k] = 0.001 * n(rng), xi[k + 3] = 0.001 * n(rng);
    frames[f].T_w_c = SE3::exp(xi) * frames[f].T_w_c;
  }
  std::vector<BaPoint> pts;
  for (int host = 0; host < hosts; ++host) {
    const std::vector<BaPoint> more = pointsOf(s, host, 0.02, rng, F);
    pts.insert(pts.end(), more.begin(), more.end());
  }
  BaConfig cfg;
  cfg.lambda_initial = 1e-12;
  cfg.outlier_energy = 1e9;  // the same residuals in both runs
  cfg.iterations = 1;
  std::vector<BaFrame> f1 = frames;
  std::vector<BaPoint> p1 = pts;
  const BaStats one = PhotometricBA(camera(), cfg).optimize(f1, p1);
  cfg.iterations = 20;
  const BaStats conv = PhotometricBA(camera(), cfg).optimize(frames, pts);
  std::printf("[ ba one step, %s ] rmse %.5f -> %.5f after one step, %.5f converged\n", name,
              one.initial_rmse, one.final_rmse, conv.final_rmse);
  EXPECT_LT(one.final_rmse - conv.final_rmse, 0.2 * (one.initial_rmse - conv.final_rmse)) << name;
}

TEST(PhotometricBA, OneStepFromNearTheOptimumGoesMostOfTheWay) {
  oneStepAndConverged({0, 0, 0, 0}, {0, 0, 0, 0}, 0, 0, 2, "one exposure");
  // Every frame exposed differently, and points hosted in a free frame too: the exposure ratios
  // e^(a_t - a_h) and the offsets b enter every block of the normal equations.
  oneStepAndConverged({0, 0.3, -0.25, 0.2}, {0, 0.04, -0.03, 0.02}, 0.05, -0.02, 3, "four exposures");
}

// The prior alone: its energy is E(x) = bᵀx + ½ xᵀHx in the solve's left perturbation
// x = (log(T_w_c T0⁻¹), a − a0, b − b0), and the solve ends at its minimum x* = −H⁻¹b, E* = −½ bᵀH⁻¹b.
TEST(PhotometricBA, PriorAloneIsMinimizedWhereItsQuadraticModelSays) {
  const Scene& s = scene();
  std::vector<BaFrame> frames = framesAtTruth(s, 3);
  frames[0].fixed = true;
  BaPrior prior;
  prior.frames = {1, 2};
  for (int f : prior.frames) {
    frames[f].a = 0.1 * f, frames[f].b = -0.02 * f;
    prior.T0.push_back(frames[f].T_w_c), prior.a0.push_back(frames[f].a), prior.b0.push_back(frames[f].b);
  }
  std::mt19937 rng(6);
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::MatrixXd A(16, 16);
  for (Eigen::Index k = 0; k < A.size(); ++k) A.data()[k] = n(rng);
  prior.H = A * A.transpose() + 16 * Eigen::MatrixXd::Identity(16, 16);
  Eigen::VectorXd x_star(16);
  for (int k = 0; k < 16; ++k) x_star[k] = 0.03 * n(rng);
  prior.b = -prior.H * x_star;
  const auto xOf = [&](const std::vector<BaFrame>& fr) {
    Eigen::VectorXd x(16);
    for (int i = 0; i < 2; ++i) {
      const BaFrame& f = fr[prior.frames[i]];
      x.segment<6>(8 * i) = (f.T_w_c * prior.T0[i].inverse()).log();
      x[8 * i + 6] = f.a - prior.a0[i], x[8 * i + 7] = f.b - prior.b0[i];
    }
    return x;
  };
  // At a state moved by known left perturbations.
  std::vector<BaFrame> moved = frames;
  Eigen::VectorXd x(16);
  for (int k = 0; k < 16; ++k) x[k] = 0.02 * n(rng);
  for (int i = 0; i < 2; ++i) {
    BaFrame& f = moved[prior.frames[i]];
    f.T_w_c = SE3::exp(x.segment<6>(8 * i)) * prior.T0[i];
    f.a += x[8 * i + 6], f.b += x[8 * i + 7];
  }
  EXPECT_LT((prior.delta(moved) - x).norm(), 1e-12);
  EXPECT_NEAR(prior.energy(moved), prior.b.dot(x) + 0.5 * x.dot(prior.H * x), 1e-12);
  // The solve, started at the linearization point, with no points.
  std::vector<BaPoint> none;
  BaConfig cfg;
  cfg.iterations = 30;
  PhotometricBA(camera(), cfg).optimize(frames, none, &prior);
  EXPECT_LT((xOf(frames) - x_star).norm(), 1e-6 * x_star.norm()) << xOf(frames).transpose();
  EXPECT_NEAR(prior.energy(frames), 0.5 * prior.b.dot(x_star), 1e-9);  // = -½ bᵀH⁻¹b
}

// Marginalization is exact for the linearized problem: one Gauss-Newton step of the remaining frames
// with the prior equals the step of the joint problem in which the marginalized frame and its points
// are still variables (when, as here, no other point is observed in the marginalized frame).
TEST(PhotometricBA, MarginalizationPriorReproducesTheJointStep) {
  const Scene& s = scene();
  const int F = 5;
  ASSERT_GE(static_cast<int>(s.frames.images.size()), F);
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<BaFrame> frames = framesAtTruth(s, F);
  for (int f = 0; f < F; ++f) {
    Vec6 xi;
    for (int k = 0; k < 3; ++k) xi[k] = 0.002 * n(rng), xi[k + 3] = 0.001 * n(rng);
    // Gauge and scale: frames 1 and 2 are held (with one, the scale direction would be a null space
    // of both systems and the two steps could differ along it).
    frames[f].fixed = f == 1 || f == 2;
    if (!frames[f].fixed) frames[f].T_w_c = SE3::exp(xi) * frames[f].T_w_c;
  }
  std::vector<BaPoint> pts = pointsOf(s, 0, 0.05, rng, F);
  std::vector<BaPoint> others = pointsOf(s, 2, 0.05, rng, F);
  for (BaPoint& p : others) p.targets = {1, 3, 4};  // nothing else observed in frame 0
  pts.insert(pts.end(), others.begin(), others.end());

  BaConfig cfg;
  cfg.iterations = 1;
  cfg.lambda_initial = 1e-12;
  cfg.outlier_energy = 1e9;
  const PhotometricBA ba(camera(), cfg);
  // Joint: every frame and point.
  std::vector<BaFrame> joint_f = frames;
  std::vector<BaPoint> joint_p = pts;
  ba.optimize(joint_f, joint_p);
  // Reduced: frame 0 and its points marginalized at the start state.
  const BaPrior prior = ba.marginalize(frames, pts, nullptr, 0);
  ASSERT_EQ(prior.frames, (std::vector<int>{1, 2, 3, 4}));
  std::vector<BaFrame> red_f(frames.begin() + 1, frames.end());
  std::vector<BaPoint> red_p;
  for (const BaPoint& p : pts) {
    if (p.host == 0) continue;
    BaPoint q = p;
    q.host -= 1;
    for (int& t : q.targets) t -= 1;
    red_p.push_back(q);
  }
  BaPrior shifted = prior;
  shifted.eraseFrameIndex(0);  // frame 0 is gone: 1, 2, 3, 4 -> 0, 1, 2, 3
  ASSERT_EQ(shifted.frames, (std::vector<int>{0, 1, 2, 3}));
  ba.optimize(red_f, red_p, &shifted);
  for (int f = 3; f < F; ++f) {
    const double step = (joint_f[f].T_w_c * frames[f].T_w_c.inverse()).log().norm();
    const double diff = (joint_f[f].T_w_c * red_f[f - 1].T_w_c.inverse()).log().norm();
    std::printf("[ marg ] frame %d: joint step %.3e, joint vs reduced %.3e\n", f, step, diff);
    EXPECT_GT(step, 1e-4);
    EXPECT_LT(diff, 1e-3 * step);
    EXPECT_NEAR(joint_f[f].a, red_f[f - 1].a, 1e-6);
    EXPECT_NEAR(joint_f[f].b, red_f[f - 1].b, 1e-6);
  }
  // The prior's energy is the quadratic model: zero at its linearization point.
  EXPECT_NEAR(prior.energy(frames), 0.0, 1e-12);
}

// First-estimate Jacobians: a prior built over two marginalizations, with the frames moved in between
// (as the optimizer moves them), keeps the problem's gauge (a similarity of the whole scene, and one
// brightness offset a for every frame) as its null space at its linearization points. Relinearizing
// the second marginalization at the moved frames gave the prior information along the gauge, which
// pulled the monocular scale (ESIM frames-only: scale 1.00 -> 1.12 over 6 s).
TEST(PhotometricBA, MarginalizationPriorKeepsTheGaugeFree) {
  const Scene& s = scene();
  const int F = 5;
  ASSERT_GE(static_cast<int>(s.frames.images.size()), F);
  std::mt19937 rng(4);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<BaFrame> frames = framesAtTruth(s, F);
  std::vector<BaPoint> pts;
  for (int host : {0, 1, 2}) {
    const std::vector<BaPoint> p = pointsOf(s, host, 0.02, rng, F);
    pts.insert(pts.end(), p.begin(), p.end());
  }
  const PhotometricBA ba(camera(), BaConfig{});
  BaPrior prior = ba.marginalize(frames, pts, nullptr, 0);
  // Frame 0 and its points leave; the others move by up to a few mm and tenths of a degree.
  frames.erase(frames.begin());
  std::vector<BaPoint> kept;
  for (BaPoint p : pts) {
    if (p.host == 0) continue;
    p.host -= 1;
    std::vector<int> targets;
    for (int t : p.targets)
      if (t != 0) targets.push_back(t - 1);
    p.targets = targets;
    kept.push_back(p);
  }
  prior.eraseFrameIndex(0);
  for (BaFrame& f : frames) {
    Vec6 xi;
    for (int k = 0; k < 3; ++k) xi[k] = 0.003 * n(rng), xi[k + 3] = 0.004 * n(rng);
    f.T_w_c = SE3::exp(xi) * f.T_w_c;
    f.a += 0.01 * n(rng);
  }
  const BaPrior p2 = ba.marginalize(frames, kept, &prior, 0);
  ASSERT_EQ(p2.frames.size(), 3u);
  const Eigen::Index D = p2.H.rows();
  std::vector<Eigen::VectorXd> gauge(8, Eigen::VectorXd::Zero(D));
  for (std::size_t i = 0; i < p2.frames.size(); ++i) {
    for (int k = 0; k < 6; ++k) gauge[k][8 * i + k] = 1.0;  // a rigid motion of everything
    gauge[6].segment<3>(8 * i) = p2.T0[i].translation();    // scale, about the world origin
    gauge[7][8 * i + 6] = 1.0;                              // brightness: a + c for every frame
  }
  const double h = p2.H.norm();
  for (int k = 0; k < 8; ++k) {
    const double leak = (p2.H * gauge[k]).norm() / (h * gauge[k].norm());
    std::printf("[ marg gauge ] direction %d: |H n| / (|H| |n|) = %.2e\n", k, leak);
    EXPECT_LT(leak, 1e-6);
  }
  // A direction that is not a gauge is observed (a check that the test can fail).
  Eigen::VectorXd other = Eigen::VectorXd::Zero(D);
  other[8] = 1.0;  // the second frame alone moves along x
  EXPECT_GT((p2.H * other).norm() / h, 1e-3);
}

}  // namespace
}  // namespace eds
