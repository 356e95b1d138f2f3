#pragma once
// SO(3) and SE(3) on Eigen (Sophus is not in Debian). Conventions (DESIGN.md section 5): T_a_b maps a
// point from frame b to frame a, p_a = T_a_b * p_b. Tangent vectors are ordered (translation, rotation)
// for SE(3), and perturbations are left-multiplied unless a function says otherwise.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace eds {

using Vec3 = Eigen::Vector3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat3 = Eigen::Matrix3d;
using Mat6 = Eigen::Matrix<double, 6, 6>;
using Quat = Eigen::Quaterniond;

inline Mat3 hat(const Vec3& w) {
  Mat3 m;
  m << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return m;
}
inline Vec3 vee(const Mat3& m) { return {m(2, 1), m(0, 2), m(1, 0)}; }

class SO3 {
 public:
  SO3() : q_(Quat::Identity()) {}
  explicit SO3(const Quat& q) : q_(q.normalized()) {}
  explicit SO3(const Mat3& R) : q_(Quat(R).normalized()) {}

  static SO3 exp(const Vec3& w) {
    const double theta2 = w.squaredNorm();
    const double theta = std::sqrt(theta2);
    // Taylor expansion near zero keeps the map exact to double precision and differentiable.
    double imag_factor, real;
    if (theta < 1e-8) {
      imag_factor = 0.5 - theta2 / 48.0;
      real = 1.0 - theta2 / 8.0;
    } else {
      imag_factor = std::sin(0.5 * theta) / theta;
      real = std::cos(0.5 * theta);
    }
    return SO3(Quat(real, imag_factor * w.x(), imag_factor * w.y(), imag_factor * w.z()));
  }

  // Rotation vector with angle in [0, pi]. atan2 keeps precision for small and near-pi angles.
  Vec3 log() const {
    Quat q = q_;
    if (q.w() < 0) q.coeffs() = -q.coeffs();
    const double n = q.vec().norm();
    if (n < 1e-10) return 2.0 / q.w() * q.vec();
    const double angle = 2.0 * std::atan2(n, q.w());
    return angle / n * q.vec();
  }

  double angle() const { return log().norm(); }

  SO3 operator*(const SO3& o) const { return SO3(q_ * o.q_); }
  Vec3 operator*(const Vec3& p) const { return q_ * p; }
  SO3 inverse() const { return SO3(q_.conjugate()); }
  Mat3 matrix() const { return q_.toRotationMatrix(); }
  const Quat& quaternion() const { return q_; }
  Mat3 adjoint() const { return matrix(); }

  // Right and left Jacobians of SO(3): exp(w + d) ~= exp(w) exp(Jr(w) d) = exp(Jl(w) d) exp(w).
  static Mat3 leftJacobian(const Vec3& w) {
    const double theta = w.norm();
    const Mat3 W = hat(w);
    if (theta < 1e-6) return Mat3::Identity() + 0.5 * W + W * W / 6.0;
    const double t2 = theta * theta;
    return Mat3::Identity() + (1 - std::cos(theta)) / t2 * W +
           (theta - std::sin(theta)) / (t2 * theta) * W * W;
  }
  static Mat3 rightJacobian(const Vec3& w) { return leftJacobian(-w); }
  static Mat3 leftJacobianInverse(const Vec3& w) {
    const double theta = w.norm();
    const Mat3 W = hat(w);
    if (theta < 1e-6) return Mat3::Identity() - 0.5 * W + W * W / 12.0;
    const double t2 = theta * theta;
    const double c = 1.0 / t2 - (1 + std::cos(theta)) / (2 * theta * std::sin(theta));
    return Mat3::Identity() - 0.5 * W + c * W * W;
  }

 private:
  Quat q_;
};

class SE3 {
 public:
  SE3() : t_(Vec3::Zero()) {}
  SE3(const SO3& R, const Vec3& t) : R_(R), t_(t) {}
  SE3(const Quat& q, const Vec3& t) : R_(q), t_(t) {}

  // xi = (v, w): translation part first.
  static SE3 exp(const Vec6& xi) {
    const Vec3 v = xi.head<3>();
    const Vec3 w = xi.tail<3>();
    return SE3(SO3::exp(w), SO3::leftJacobian(w) * v);
  }
  Vec6 log() const {
    const Vec3 w = R_.log();
    Vec6 xi;
    xi.head<3>() = SO3::leftJacobianInverse(w) * t_;
    xi.tail<3>() = w;
    return xi;
  }

  SE3 operator*(const SE3& o) const { return SE3(R_ * o.R_, R_ * o.t_ + t_); }
  Vec3 operator*(const Vec3& p) const { return R_ * p + t_; }
  SE3 inverse() const {
    const SO3 Ri = R_.inverse();
    return SE3(Ri, -(Ri * t_));
  }

  // Adjoint: exp(Ad(T) xi) = T exp(xi) T^-1, for xi = (v, w).
  Mat6 adjoint() const {
    Mat6 A = Mat6::Zero();
    const Mat3 R = R_.matrix();
    A.topLeftCorner<3, 3>() = R;
    A.topRightCorner<3, 3>() = hat(t_) * R;
    A.bottomRightCorner<3, 3>() = R;
    return A;
  }

  Eigen::Matrix4d matrix() const {
    Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
    M.topLeftCorner<3, 3>() = R_.matrix();
    M.topRightCorner<3, 1>() = t_;
    return M;
  }

  const SO3& so3() const { return R_; }
  const Vec3& translation() const { return t_; }
  Vec3& translation() { return t_; }
  const Quat& quaternion() const { return R_.quaternion(); }
  Mat3 rotationMatrix() const { return R_.matrix(); }

 private:
  SO3 R_;
  Vec3 t_;
};

// Interpolation between poses with s in [0, 1]: linear in position, slerp in rotation. This is what
// trajectory files mean between samples (and what the simulator uses); it is not the SE(3) geodesic.
inline SE3 interpolate(const SE3& a, const SE3& b, double s) {
  const Quat q = a.quaternion().slerp(s, b.quaternion());
  return SE3(q, (1.0 - s) * a.translation() + s * b.translation());
}

// Geodesic interpolation on SE(3): a * exp(s * log(a^-1 b)).
inline SE3 interpolateGeodesic(const SE3& a, const SE3& b, double s) {
  return a * SE3::exp(s * (a.inverse() * b).log());
}

}  // namespace eds
