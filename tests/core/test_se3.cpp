#include <gtest/gtest.h>

#include <random>

#include "core/se3.hpp"

namespace eds {
namespace {

Vec6 randomTwist(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  Vec6 xi;
  for (int i = 0; i < 6; ++i) xi[i] = u(rng);
  return xi;
}

TEST(SO3, ExpLogRoundTripIncludingSmallAndLargeAngles) {
  std::mt19937 rng(1);
  for (double scale : {1e-10, 1e-6, 1e-3, 0.5, 1.5}) {
    for (int i = 0; i < 50; ++i) {
      const Vec3 w = randomTwist(rng, scale).tail<3>();
      const Vec3 back = SO3::exp(w).log();
      EXPECT_LT((back - w).norm(), 1e-12 + 1e-10 * w.norm()) << "scale " << scale;
    }
  }
  // Near pi: the angle is recovered even if the axis sign may flip.
  const Vec3 w(0, 0, M_PI - 1e-9);
  EXPECT_NEAR(SO3::exp(w).log().norm(), M_PI - 1e-9, 1e-9);
}

TEST(SO3, ExpMatchesAngleAxis) {
  const Vec3 w(0.3, -0.2, 0.7);
  const Mat3 R = Eigen::AngleAxisd(w.norm(), w.normalized()).toRotationMatrix();
  EXPECT_LT((SO3::exp(w).matrix() - R).norm(), 1e-14);
}

TEST(SE3, ExpLogRoundTrip) {
  std::mt19937 rng(2);
  for (double scale : {1e-9, 1e-4, 0.1, 1.0}) {
    for (int i = 0; i < 50; ++i) {
      const Vec6 xi = randomTwist(rng, scale);
      const Vec6 back = SE3::exp(xi).log();
      EXPECT_LT((back - xi).norm(), 1e-12 + 1e-10 * xi.norm());
    }
  }
}

TEST(SE3, ComposeInverseAndPointAction) {
  std::mt19937 rng(3);
  const SE3 T_a_b = SE3::exp(randomTwist(rng, 1.0));
  const SE3 T_b_c = SE3::exp(randomTwist(rng, 1.0));
  const Vec3 p_c(0.3, -1.2, 2.5);
  const Vec3 p_a = T_a_b * (T_b_c * p_c);
  EXPECT_LT(((T_a_b * T_b_c) * p_c - p_a).norm(), 1e-12);
  EXPECT_LT((T_a_b.inverse() * p_a - T_b_c * p_c).norm(), 1e-12);
  EXPECT_LT(((T_a_b * T_a_b.inverse()).matrix() - Eigen::Matrix4d::Identity()).norm(), 1e-12);
  EXPECT_LT(((T_a_b * T_b_c).matrix() - T_a_b.matrix() * T_b_c.matrix()).norm(), 1e-12);
}

TEST(SE3, AdjointMovesTwistsAcrossAPose) {
  std::mt19937 rng(4);
  const SE3 T = SE3::exp(randomTwist(rng, 1.0));
  const Vec6 xi = randomTwist(rng, 0.5);
  const SE3 lhs = SE3::exp(T.adjoint() * xi);
  const SE3 rhs = T * SE3::exp(xi) * T.inverse();
  EXPECT_LT((lhs.matrix() - rhs.matrix()).norm(), 1e-12);
}

// d exp(w + d) = exp(Jl(w) d) exp(w) to first order, checked by central differences.
TEST(SO3, LeftAndRightJacobiansMatchNumericDifferences) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const Vec3 w = randomTwist(rng, 1.2).tail<3>();
    const double h = 1e-6;
    Mat3 Jl_num, Jr_num;
    for (int i = 0; i < 3; ++i) {
      const Vec3 d = Vec3::Unit(i) * h;
      Jl_num.col(i) = ((SO3::exp(w + d) * SO3::exp(w).inverse()).log() -
                       (SO3::exp(w - d) * SO3::exp(w).inverse()).log()) /
                      (2 * h);
      Jr_num.col(i) = ((SO3::exp(w).inverse() * SO3::exp(w + d)).log() -
                       (SO3::exp(w).inverse() * SO3::exp(w - d)).log()) /
                      (2 * h);
    }
    const Mat3 Jl = SO3::leftJacobian(w), Jr = SO3::rightJacobian(w);
    EXPECT_LT((Jl - Jl_num).norm() / Jl.norm(), 1e-7);
    EXPECT_LT((Jr - Jr_num).norm() / Jr.norm(), 1e-7);
    EXPECT_LT((SO3::leftJacobianInverse(w) * Jl - Mat3::Identity()).norm(), 1e-12);
  }
}

// Derivative of the action of a left-perturbed pose on a point: d(exp(xi) T p)/dxi = [I, -[Tp]x].
TEST(SE3, PointJacobianOfLeftPerturbationMatchesNumeric) {
  std::mt19937 rng(6);
  const SE3 T = SE3::exp(randomTwist(rng, 1.0));
  const Vec3 p(0.4, 0.1, 2.0);
  Eigen::Matrix<double, 3, 6> J_num;
  const double h = 1e-6;
  for (int i = 0; i < 6; ++i) {
    const Vec6 d = Vec6::Unit(i) * h;
    J_num.col(i) = ((SE3::exp(d) * T) * p - (SE3::exp(-d) * T) * p) / (2 * h);
  }
  Eigen::Matrix<double, 3, 6> J;
  J.leftCols<3>().setIdentity();
  J.rightCols<3>() = -hat(T * p);
  EXPECT_LT((J - J_num).norm() / J.norm(), 1e-8);
}

TEST(SE3, InterpolationEndpointsAndMidpoint) {
  const SE3 a(SO3::exp(Vec3(0, 0, 0.2)), Vec3(1, 2, 3));
  const SE3 b(SO3::exp(Vec3(0, 0, 0.6)), Vec3(3, 2, 1));
  EXPECT_LT((interpolate(a, b, 0.0).matrix() - a.matrix()).norm(), 1e-12);
  EXPECT_LT((interpolate(a, b, 1.0).matrix() - b.matrix()).norm(), 1e-12);
  const SE3 m = interpolate(a, b, 0.5);
  EXPECT_LT((m.translation() - Vec3(2, 2, 2)).norm(), 1e-12);
  EXPECT_NEAR(m.so3().log().z(), 0.4, 1e-12);
  const SE3 g = interpolateGeodesic(a, b, 0.5);
  EXPECT_NEAR(g.so3().log().z(), 0.4, 1e-12);
  EXPECT_LT((interpolateGeodesic(a, b, 1.0).matrix() - b.matrix()).norm(), 1e-12);
}

}  // namespace
}  // namespace eds
