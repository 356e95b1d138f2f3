// Unit tests of the evaluator on synthetic trajectories: alignment, association, coverage, window.
#include "eval/ate.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>
#include <random>
#include <tuple>

#include "eval/rpe.hpp"

using namespace eds;
using namespace eds::eval;

namespace {

constexpr TimeNs kMs = 1'000'000;

Quat randomRotation(std::mt19937& rng, double max_angle) {
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> u(-max_angle, max_angle);
  const Vec3 axis = Vec3(n(rng), n(rng), n(rng)).normalized();
  return Quat(Eigen::AngleAxisd(u(rng), axis));
}

// A smooth 3-D path with varied orientation, one pose every dt starting at t0.
Trajectory makeTrajectory(std::size_t n, TimeNs t0, TimeNs dt, unsigned seed = 1) {
  std::mt19937 rng(seed);
  Trajectory traj;
  Vec3 p(1.0, -2.0, 0.5);
  Quat q = randomRotation(rng, std::numbers::pi);
  std::normal_distribution<double> step(0.0, 0.05);
  for (std::size_t i = 0; i < n; ++i) {
    const double s = 0.01 * static_cast<double>(i);
    p += Vec3(0.03 * std::cos(s), 0.02 * std::sin(2 * s), 0.01) + Vec3(step(rng), step(rng), step(rng));
    q = (q * randomRotation(rng, 0.05)).normalized();
    traj.push_back({t0 + static_cast<TimeNs>(i) * dt, SE3(q, p)});
  }
  return traj;
}

// est such that gt = s R est + t, i.e. est = (R^T (p - t)) / s and R_est = R^T R_gt.
Trajectory applyInverseSim3(const Trajectory& gt, double s, const Mat3& R, const Vec3& t) {
  Trajectory est;
  for (const StampedPose& g : gt) {
    const Vec3 p = R.transpose() * (g.T_w_c.translation() - t) / s;
    const Quat q(R.transpose() * g.T_w_c.rotationMatrix());
    est.push_back({g.t, SE3(q, p)});
  }
  return est;
}

Trajectory stampsOnly(const std::vector<double>& seconds) {
  Trajectory traj;
  for (const double s : seconds) traj.push_back({fromSeconds(s), SE3()});
  return traj;
}

std::vector<std::pair<std::size_t, std::size_t>> asIndexPairs(const std::vector<MatchedPair>& m) {
  std::vector<std::pair<std::size_t, std::size_t>> out;
  for (const MatchedPair& p : m) out.emplace_back(p.est, p.gt);
  return out;
}

// The toolbox's association, written directly from its definition (all n*m pairs, then greedy).
std::vector<std::pair<std::size_t, std::size_t>> bruteForceAssociate(const Trajectory& est,
                                                                     const Trajectory& gt, TimeNs max_dt) {
  std::vector<std::tuple<TimeNs, TimeNs, TimeNs, std::size_t, std::size_t>> cand;
  for (std::size_t i = 0; i < est.size(); ++i)
    for (std::size_t j = 0; j < gt.size(); ++j)
      if (std::abs(est[i].t - gt[j].t) < max_dt)
        cand.emplace_back(std::abs(est[i].t - gt[j].t), est[i].t, gt[j].t, i, j);
  std::sort(cand.begin(), cand.end());
  std::vector<bool> ue(est.size()), ug(gt.size());
  std::vector<std::pair<std::size_t, std::size_t>> out;
  for (const auto& [d, te, tg, i, j] : cand) {
    if (ue[i] || ug[j]) continue;
    ue[i] = ug[j] = true;
    out.emplace_back(i, j);
  }
  std::sort(out.begin(), out.end(), [&](auto a, auto b) {
    return std::tie(est[a.first].t, a.first) < std::tie(est[b.first].t, b.first);
  });
  return out;
}

}  // namespace

TEST(EvalAlign, Sim3RecoversKnownTransform) {
  const Trajectory gt = makeTrajectory(500, 0, 10 * kMs);
  const Mat3 R = Quat(Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized())).toRotationMatrix();
  const Vec3 t(3.0, -1.0, 2.0);
  const Trajectory est = applyInverseSim3(gt, 2.5, R, t);
  const AteResult r = evaluateAte(est, gt, EvalConfig{});
  EXPECT_EQ(r.pairs.size(), gt.size());
  EXPECT_NEAR(r.transform.s, 2.5, 1e-9);
  EXPECT_LT((r.transform.R - R).norm(), 1e-9);
  EXPECT_LT((r.transform.t - t).norm(), 1e-8);
  EXPECT_LT(r.trans.rmse, 1e-9);
  EXPECT_LT(r.rot.rmse, 1e-6);
  EXPECT_NEAR(r.coverage, 1.0, 1e-12);

  // se3 cannot absorb the scale; sim3 over the first 10 poses is enough for exact data.
  EvalConfig se3;
  se3.alignment = Alignment::kSe3;
  EXPECT_GT(evaluateAte(est, gt, se3).trans.rmse, 0.1);
  EvalConfig first10;
  first10.align_frames = 10;
  EXPECT_LT(evaluateAte(est, gt, first10).trans.rmse, 1e-8);
}

TEST(EvalAlign, AppliedTransformLeavesOnlyTheErrors) {
  // A noisy estimate in another frame and scale: moved by the sim3 the evaluation found, it must give
  // the same errors with no alignment at all (what `eds eval --aligned` writes).
  const Trajectory gt = makeTrajectory(300, 0, 10 * kMs, 3);
  const Mat3 R = Quat(Eigen::AngleAxisd(-1.1, Vec3(0.2, 1, -0.4).normalized())).toRotationMatrix();
  Trajectory est = applyInverseSim3(gt, 0.4, R, Vec3(0.5, 2.0, -1.0));
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 0.002);
  for (StampedPose& p : est)
    p.T_w_c = SE3(p.T_w_c.so3() * SO3::exp(Vec3(n(rng), n(rng), n(rng))),
                  p.T_w_c.translation() + Vec3(n(rng), n(rng), n(rng)));
  const AteResult r = evaluateAte(est, gt, EvalConfig{});
  ASSERT_GT(r.trans.rmse, 1e-3);
  EvalConfig none;
  none.alignment = Alignment::kNone;
  const AteResult raw = evaluateAte(applySim3(est, r.transform), gt, none);
  EXPECT_NEAR(raw.trans.rmse, r.trans.rmse, 1e-12);
  EXPECT_NEAR(raw.rot.rmse, r.rot.rmse, 1e-9);
  EXPECT_NEAR(evaluateAte(applySim3(est, r.transform), gt, EvalConfig{}).transform.s, 1.0, 1e-9);
}

TEST(EvalAlign, AlignFramesUsesOnlyTheFirstPoses) {
  const Trajectory gt = makeTrajectory(200, 0, 10 * kMs);
  Trajectory est = gt;
  // Drift after pose 50: aligning over the first 50 keeps them exact.
  for (std::size_t i = 50; i < est.size(); ++i)
    est[i].T_w_c.translation() += Vec3(0.01 * static_cast<double>(i - 50), 0, 0);
  EvalConfig cfg;
  cfg.alignment = Alignment::kSe3;
  cfg.align_frames = 50;
  const AteResult r = evaluateAte(est, gt, cfg);
  for (std::size_t i = 0; i < 50; ++i) EXPECT_LT(r.trans_errors[i], 1e-9);
  EXPECT_NEAR(r.trans_errors[199], 1.49, 1e-9);
  EXPECT_LT(r.rot.max, 1e-6);

  cfg.alignment = Alignment::kSim3;
  cfg.align_frames = 1;
  EXPECT_THROW(evaluateAte(est, gt, cfg), std::invalid_argument);
}

TEST(EvalAlign, Se3SingleFrameUsesFirstOrientation) {
  const Trajectory gt = makeTrajectory(100, 0, 10 * kMs);
  const Mat3 R = Quat(Eigen::AngleAxisd(1.2, Vec3(0, 1, 1).normalized())).toRotationMatrix();
  const Trajectory est = applyInverseSim3(gt, 1.0, R, Vec3(1, 2, 3));
  EvalConfig cfg;
  cfg.alignment = Alignment::kSe3;
  cfg.align_frames = 1;
  const AteResult r = evaluateAte(est, gt, cfg);
  EXPECT_LT(r.trans.max, 1e-9);
  EXPECT_LT(r.rot.max, 1e-6);
}

TEST(EvalAlign, PosYawAbsorbsYawOnly) {
  const Trajectory gt = makeTrajectory(300, 0, 10 * kMs);
  const Mat3 yaw = rotZ(2.0);
  const Trajectory est = applyInverseSim3(gt, 1.0, yaw, Vec3(0.5, -0.3, 1.0));
  for (const int frames : {-1, 1, 20}) {
    EvalConfig cfg;
    cfg.alignment = Alignment::kPosYaw;
    cfg.align_frames = frames;
    const AteResult r = evaluateAte(est, gt, cfg);
    EXPECT_LT(r.trans.max, 1e-9) << frames;
    EXPECT_LT(r.rot.max, 1e-6) << frames;
    EXPECT_LT((r.transform.R - yaw).norm(), 1e-9) << frames;
  }
  // A roll offset is beyond posyaw (gravity is observable) but within se3.
  const Mat3 roll = Quat(Eigen::AngleAxisd(0.3, Vec3::UnitX())).toRotationMatrix();
  const Trajectory rolled = applyInverseSim3(gt, 1.0, roll * yaw, Vec3::Zero());
  EvalConfig posyaw;
  posyaw.alignment = Alignment::kPosYaw;
  EXPECT_GT(evaluateAte(rolled, gt, posyaw).rot.min, 5.0);
  EvalConfig se3;
  se3.alignment = Alignment::kSe3;
  EXPECT_LT(evaluateAte(rolled, gt, se3).rot.max, 1e-6);
}

TEST(EvalAlign, NoneMeasuresRawOffsets) {
  const Trajectory gt = makeTrajectory(50, 0, 10 * kMs);
  Trajectory est = gt;
  for (StampedPose& p : est) p.T_w_c.translation() += Vec3(0.3, 0.4, 0.0);
  EvalConfig cfg;
  cfg.alignment = Alignment::kNone;
  const AteResult r = evaluateAte(est, gt, cfg);
  EXPECT_NEAR(r.trans.rmse, 0.5, 1e-12);
  EXPECT_NEAR(r.trans.std, 0.0, 1e-12);
  EXPECT_EQ(r.transform.s, 1.0);
}

TEST(EvalAssociate, OneToOneClosestFirstWithin20ms) {
  const TimeNs max_dt = 20 * kMs;
  // e1 would prefer g1 but e2 is closer to it; e1 falls back to g2 at 15 ms.
  EXPECT_EQ(asIndexPairs(associate(stampsOnly({1.000, 1.010}), stampsOnly({1.008, 0.985}), max_dt)),
            (std::vector<std::pair<std::size_t, std::size_t>>{{0, 1}, {1, 0}}));
  // Equal distance: the earlier estimate wins.
  EXPECT_EQ(asIndexPairs(associate(stampsOnly({1.000, 1.010}), stampsOnly({1.005}), max_dt)),
            (std::vector<std::pair<std::size_t, std::size_t>>{{0, 0}}));
  // The limit is strict: 19.999999 ms matches, 20 ms does not.
  EXPECT_EQ(associate(stampsOnly({2.0}), stampsOnly({2.019999999}), max_dt).size(), 1u);
  EXPECT_EQ(associate(stampsOnly({2.0}), stampsOnly({2.020}), max_dt).size(), 0u);
  EXPECT_EQ(associate(stampsOnly({2.0}), stampsOnly({1.980}), max_dt).size(), 0u);
  // Three estimates, one gt pose: exactly one pair.
  EXPECT_EQ(associate(stampsOnly({3.0, 3.001, 3.002}), stampsOnly({3.0015}), max_dt).size(), 1u);
}

TEST(EvalAssociate, MatchesBruteForceOnRandomStamps) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<TimeNs> jitter(-15 * kMs, 15 * kMs);
  for (int trial = 0; trial < 20; ++trial) {
    Trajectory est, gt;
    for (int i = 0; i < 300; ++i) gt.push_back({i * 5 * kMs + jitter(rng) / 8, SE3()});
    for (int i = 0; i < 200; ++i) est.push_back({i * 7 * kMs + jitter(rng), SE3()});
    // Some exact duplicates and ties.
    est.push_back(est[10]);
    gt.push_back({est[20].t + 3 * kMs, SE3()});
    gt.push_back({est[20].t - 3 * kMs, SE3()});
    const auto expected = bruteForceAssociate(est, gt, 20 * kMs);
    EXPECT_EQ(asIndexPairs(associate(est, gt, 20 * kMs)), expected);
    // Input order does not matter (up to index relabelling).
    Trajectory shuffled = est;
    std::shuffle(shuffled.begin(), shuffled.end(), rng);
    EXPECT_EQ(associate(shuffled, gt, 20 * kMs).size(), expected.size());
  }
}

TEST(EvalCoverage, TrackLostAfter30Percent) {
  const Trajectory gt = makeTrajectory(1001, 0, 10 * kMs);  // 10 s
  Trajectory est;
  for (std::size_t i = 0; i <= 300; i += 2) est.push_back(gt[i]);  // 0..3 s at 50 Hz
  const AteResult r = evaluateAte(est, gt, EvalConfig{});
  EXPECT_LT(r.trans.rmse, 1e-9);       // accurate where it tracks...
  EXPECT_NEAR(r.coverage, 0.3, 1e-9);  // ...but only 30 % of the time

  // A 3 s gap in the middle is not covered; a 0.5 s gap is.
  Trajectory gap;
  for (std::size_t i = 0; i <= 1000; ++i)
    if (i <= 300 || i >= 600) gap.push_back(gt[i]);
  EXPECT_NEAR(evaluateAte(gap, gt, EvalConfig{}).coverage, 0.7, 1e-9);
  Trajectory small_gap;
  for (std::size_t i = 0; i <= 1000; ++i)
    if (i <= 300 || i >= 350) small_gap.push_back(gt[i]);
  EXPECT_NEAR(evaluateAte(small_gap, gt, EvalConfig{}).coverage, 1.0, 1e-9);
}

TEST(EvalWindow, FiltersOnGroundTruthStamp) {
  const Trajectory gt = makeTrajectory(11, 0, 100 * kMs);  // 0.0 .. 1.0 s
  Trajectory est = gt;
  for (StampedPose& p : est) p.t += 15 * kMs;
  EvalConfig cfg;
  cfg.window = TimeWindow{100 * kMs, 500 * kMs};
  const AteResult r = evaluateAte(est, gt, cfg);
  // gt 0.1 .. 0.5 s: five pairs, although the estimate at 0.515 s lies outside the window.
  ASSERT_EQ(r.pairs.size(), 5u);
  EXPECT_EQ(gt[r.pairs.front().gt].t, 100 * kMs);
  EXPECT_EQ(gt[r.pairs.back().gt].t, 500 * kMs);
  // Span 0.4 s; covered from 0.115 to 0.5 (clipped at the window end).
  EXPECT_NEAR(r.coverage, 0.385 / 0.4, 1e-9);
}

TEST(EvalStats, NumpyConventions) {
  const ErrorStats s = computeStats({4.0, 1.0, 3.0, 2.0});
  EXPECT_DOUBLE_EQ(s.median, 2.5);
  EXPECT_DOUBLE_EQ(s.mean, 2.5);
  EXPECT_DOUBLE_EQ(s.std, std::sqrt(1.25));  // population
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(7.5));
  EXPECT_DOUBLE_EQ(s.min, 1.0);
  EXPECT_DOUBLE_EQ(s.max, 4.0);
  EXPECT_EQ(s.num_samples, 4u);
  EXPECT_DOUBLE_EQ(computeStats({3.0, 1.0, 2.0}).median, 2.0);
}

TEST(EvalJson, HasDocumentedKeys) {
  const Trajectory gt = makeTrajectory(100, 0, 10 * kMs);
  const nlohmann::json j = toJson(evaluateAte(gt, gt, EvalConfig{}));
  for (const char* k : {"rmse", "mean", "median", "std", "min", "max"}) {
    EXPECT_TRUE(j.at("trans").contains(k)) << k;
    EXPECT_TRUE(j.at("rot").contains(k)) << k;
  }
  EXPECT_EQ(j.at("matched_pairs").get<int>(), 100);
  EXPECT_EQ(j.at("alignment").get<std::string>(), "sim3");
  EXPECT_NEAR(j.at("scale").get<double>(), 1.0, 1e-9);
  EXPECT_NEAR(j.at("coverage").get<double>(), 1.0, 1e-12);
}

TEST(EvalRpe, ExactSim3EstimateHasNoRelativeError) {
  const Trajectory gt = makeTrajectory(400, 0, 10 * kMs);
  const Mat3 R = Quat(Eigen::AngleAxisd(0.4, Vec3(0, 0, 1))).toRotationMatrix();
  const Trajectory est = applyInverseSim3(gt, 3.0, R, Vec3(1, 1, 1));
  const EvalConfig cfg;
  const AteResult ate = evaluateAte(est, gt, cfg);
  const std::vector<RpeResult> rpe = evaluateRpe(est, gt, ate, cfg);
  ASSERT_EQ(rpe.size(), 5u);
  for (const RpeResult& r : rpe) {
    EXPECT_GT(r.trans.num_samples, 10u) << r.distance;
    EXPECT_LT(r.trans.max, 1e-9) << r.distance;
    EXPECT_LT(r.rot.max, 1e-4) << r.distance;  // acos of the trace: ~1e-6 rad resolution
    EXPECT_LT(r.yaw.max, 1e-6) << r.distance;
  }
  // Lengths grow with the fraction of the path.
  EXPECT_LT(rpe.front().distance, rpe.back().distance);
  EXPECT_EQ(rpeDistanceTag(8.0), "8_0");
  EXPECT_EQ(rpeDistanceTag(13.34), "13_3");
}

TEST(EvalRpe, ConstantYawDriftShowsInYawNotGravity) {
  // The estimate turns 0.1 deg more per pose about the world z axis than the truth.
  Trajectory gt, est;
  for (int i = 0; i < 300; ++i) {
    const double a = 0.01 * i;
    const Vec3 p(std::cos(a) * 5, std::sin(a) * 5, 0.1 * a);
    gt.push_back({i * 10 * kMs, SE3(Quat(Eigen::AngleAxisd(a, Vec3::UnitZ())), p)});
    const Mat3 drift = rotZ(i * 0.1 * std::numbers::pi / 180);
    est.push_back({i * 10 * kMs, SE3(Quat(drift * gt.back().T_w_c.rotationMatrix()), drift * p)});
  }
  EvalConfig cfg;
  cfg.alignment = Alignment::kSe3;
  const AteResult ate = evaluateAte(est, gt, cfg);
  const std::vector<RpeResult> rpe = evaluateRpe(est, gt, ate, cfg);
  for (const RpeResult& r : rpe) {
    ASSERT_GT(r.yaw.num_samples, 0u);
    EXPECT_GT(r.yaw.mean, 1.0) << r.distance;
    EXPECT_LT(r.gravity.max, 1e-6) << r.distance;
    EXPECT_NEAR(r.rot.mean, r.yaw.mean, 1e-6) << r.distance;
  }
}

// An estimate that is the truth itself, at 1.3 ms past each 200 Hz ground-truth stamp (event-rate poses
// are not on the ground truth's grid): the toolbox's nearest-stamp pairing charges it with its motion
// over 1.3 ms (what no alignment absorbs: the weave); paired with the ground truth interpolated at its
// stamps, it is exact to the interpolation's error (weave'' h^2 / 8 = 2.5 um).
TEST(Ate, GroundTruthInterpolatedAtTheEstimateStampsRemovesThePairingOffset) {
  const double turn = 0.5;  // rad/s about z
  const auto truth = [&](TimeNs t) {
    const double s = toSeconds(t);  // 0.5 m/s along x, weaving 5 cm in y at 4 rad/s
    return SE3(Quat(Eigen::AngleAxisd(turn * s, Vec3::UnitZ())), Vec3(0.5 * s, 0.05 * std::sin(4 * s), 0.0));
  };
  Trajectory gt, est;
  for (TimeNs t = 0; t <= 2000 * kMs; t += 5 * kMs) gt.push_back({t, truth(t)});
  for (TimeNs t = 13 * kMs / 10; t < 2000 * kMs; t += 5 * kMs) est.push_back({t, truth(t)});
  const AteResult nearest = evaluateAte(est, gt, EvalConfig{});
  const Trajectory gt_at_est = interpolatedAtStamps(gt, est, 50 * kMs);
  EXPECT_EQ(gt_at_est.size(), gt.size() + est.size());
  const AteResult interpolated = evaluateAte(est, gt_at_est, EvalConfig{});
  EXPECT_GT(nearest.trans.rmse, 1e-4);  // 0.2 m/s x 1.3 ms x ~0.7 (the weave's RMS speed)
  EXPECT_LT(interpolated.trans.rmse, 3e-6);
  EXPECT_GT(nearest.rot.rmse, 0.02);  // 0.5 rad/s x 1.3 ms = 0.037 deg, less what the alignment takes
  EXPECT_LT(interpolated.rot.rmse, 1e-3);
  EXPECT_EQ(interpolated.pairs.size(), nearest.pairs.size());
  EXPECT_NEAR(interpolated.coverage, nearest.coverage, 1e-9);
  // Samples further apart than the bracket are not interpolated between.
  EXPECT_EQ(interpolatedAtStamps(gt, est, 4 * kMs).size(), gt.size());
}

namespace {

// A path 2 cm long, turning through tens of degrees (a rotation-dominated motion).
Trajectory shortTurningPath(std::size_t n) {
  std::mt19937 rng(3);
  Trajectory traj;
  Quat q = randomRotation(rng, std::numbers::pi);
  for (std::size_t i = 0; i < n; ++i) {
    const double s = static_cast<double>(i) / static_cast<double>(n);
    q = (q * randomRotation(rng, 0.02)).normalized();
    traj.push_back({static_cast<TimeNs>(i) * 10 * kMs, SE3(q, Vec3(0.02 * s, 0.005 * std::sin(6 * s), 0))});
  }
  return traj;
}

}  // namespace

TEST(Ate, OrientationsAlignedRemoveAConstantRotationAndIgnoreThePositionsFit) {
  const Trajectory gt = shortTurningPath(200);
  // The estimate's orientations all turned by 2 degrees, its positions exact: the sim3 alignment (from
  // the positions) keeps the 2 degrees, the orientations' own alignment removes them.
  const Mat3 R_c =
      Eigen::AngleAxisd(2.0 * std::numbers::pi / 180.0, Vec3(0.3, -0.5, 0.8).normalized()).toRotationMatrix();
  Trajectory est = gt;
  for (StampedPose& p : est) p.T_w_c = SE3(Quat(R_c * p.T_w_c.rotationMatrix()), p.T_w_c.translation());
  const AteResult turned = evaluateAte(est, gt, EvalConfig{});
  EXPECT_NEAR(turned.rot.rmse, 2.0, 1e-6);
  EXPECT_LT(turned.rot_oriented.rmse, 1e-6);
  // Exact orientations and positions 2 mm off at random: on a 2 cm path the positions' fit turns the
  // alignment by degrees, and every rotation error with it; the orientations' own alignment does not.
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.002);
  est = gt;
  for (StampedPose& p : est)
    p.T_w_c = SE3(p.T_w_c.quaternion(), p.T_w_c.translation() + Vec3(noise(rng), noise(rng), noise(rng)));
  const AteResult noisy = evaluateAte(est, gt, EvalConfig{});
  std::printf("[ ate ] 2 cm path, 2 mm position noise: rotation RMSE %.3f deg, orientations aligned %.2g\n",
              noisy.rot.rmse, noisy.rot_oriented.rmse);
  EXPECT_GT(noisy.rot.rmse, 1.0);
  EXPECT_LT(noisy.rot_oriented.rmse, 1e-6);
  EXPECT_TRUE(toJson(noisy).at("rot_oriented").contains("rmse"));
}

namespace {

// A 1 m rail along x whose positions leave it by `wobble` (m) in y, orientations turning slowly.
Trajectory railPath(double wobble) {
  std::mt19937 rng(8);
  Trajectory traj;
  Quat q = randomRotation(rng, std::numbers::pi);
  for (int i = 0; i < 400; ++i) {
    const double s = i / 400.0;
    q = (q * randomRotation(rng, 0.01)).normalized();
    traj.push_back({static_cast<TimeNs>(i) * 10 * kMs, SE3(q, Vec3(s, wobble * std::sin(40 * s), 0))});
  }
  return traj;
}

Trajectory withPositionNoise(Trajectory traj, double sigma) {
  std::mt19937 rng(9);
  std::normal_distribution<double> noise(0.0, sigma);
  for (StampedPose& p : traj)
    p.T_w_c = SE3(p.T_w_c.quaternion(), p.T_w_c.translation() + Vec3(noise(rng), noise(rng), noise(rng)));
  return traj;
}

}  // namespace

TEST(Ate, AStraightPathSaysTheAlignmentsRotationIsFree) {
  // On a straight rail the positions fix no rotation about it: with 1 mm noise the sim3 rotation is
  // whatever the noise makes it, and the result says so.
  const Trajectory rail = railPath(0.0);
  const AteResult straight = evaluateAte(withPositionNoise(rail, 0.001), rail, EvalConfig{});
  std::printf(
      "[ ate ] rail, 1 mm noise: rotation RMSE %.2f deg, orientations aligned %.2g, off axis %.2g m\n",
      straight.rot.rmse, straight.rot_oriented.rmse, straight.path_off_axis_m);
  EXPECT_LT(straight.path_off_axis_m, 1e-9);
  EXPECT_TRUE(rotationFreeAboutPath(straight));
  EXPECT_TRUE(toJson(straight).at("alignment_rotation_free").get<bool>());
  EXPECT_LT(straight.rot_oriented.rmse, 1e-6);
  // The same rail wobbling by 5 cm (RMS 5/√2 cm off its axis) holds the rotation: not flagged.
  const Trajectory wobbly = railPath(0.05);
  const AteResult held = evaluateAte(withPositionNoise(wobbly, 0.001), wobbly, EvalConfig{});
  EXPECT_NEAR(held.path_off_axis_m, 0.05 / std::sqrt(2.0), 0.002);
  EXPECT_FALSE(rotationFreeAboutPath(held));
  EXPECT_LT(held.rot.rmse, 0.2);
  // Wobbling by 7 mm (5 mm RMS off its axis) against an error of 1.7 mm: flagged, and the rotation
  // through the alignment is off by most of a degree where the orientations are exact (independent
  // noise at 400 poses; drift, whose errors run together, turns it further).
  const Trajectory slight = railPath(0.007);
  const AteResult loose = evaluateAte(withPositionNoise(slight, 0.001), slight, EvalConfig{});
  std::printf("[ ate ] rail wobbling by 7 mm, 1 mm noise: rotation RMSE %.2f deg, off axis %.4f m\n",
              loose.rot.rmse, loose.path_off_axis_m);
  EXPECT_TRUE(rotationFreeAboutPath(loose));
  EXPECT_GT(loose.rot.rmse, 0.5);
  // Aligned on its first two poses, any path is a straight line: the spread is that of the poses the
  // alignment used.
  EvalConfig two;
  two.align_frames = 2;
  const AteResult on_two = evaluateAte(withPositionNoise(wobbly, 0.001), wobbly, two);
  EXPECT_LT(on_two.path_off_axis_m, 1e-9);
  EXPECT_TRUE(rotationFreeAboutPath(on_two));
  // Nor is an alignment that takes no rotation from the positions flagged: none, or se3 on one pose
  // (its rotation is that pose's orientation).
  EvalConfig none;
  none.alignment = Alignment::kNone;
  EXPECT_FALSE(rotationFreeAboutPath(evaluateAte(withPositionNoise(rail, 0.001), rail, none)));
  EvalConfig first_pose;
  first_pose.alignment = Alignment::kSe3;
  first_pose.align_frames = 1;
  EXPECT_FALSE(rotationFreeAboutPath(evaluateAte(withPositionNoise(rail, 0.001), rail, first_pose)));
}
