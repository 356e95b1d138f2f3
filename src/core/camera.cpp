#include "core/camera.hpp"

#include <cmath>
#include <stdexcept>

namespace eds {

const char* toString(Distortion d) {
  switch (d) {
    case Distortion::kNone: return "none";
    case Distortion::kRadTan: return "radtan";
    case Distortion::kEquidistant: return "equidistant";
  }
  return "?";
}

namespace {

// Distortion and its 2x2 Jacobian with respect to the undistorted normalized point.
Vec2 distortWithJacobian(const CameraModel& c, const Vec2& xn, Eigen::Matrix2d* J) {
  const double x = xn.x(), y = xn.y();
  const auto& k = c.k;
  switch (c.distortion) {
    case Distortion::kNone:
      if (J) J->setIdentity();
      return xn;
    case Distortion::kRadTan: {
      const double r2 = x * x + y * y;
      const double radial = 1 + r2 * (k[0] + r2 * (k[1] + r2 * k[4]));
      const double dradial_dr2 = k[0] + r2 * (2 * k[1] + 3 * r2 * k[4]);
      const double p1 = k[2], p2 = k[3];
      const Vec2 out(x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x),
                     y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y);
      if (J) {
        (*J)(0, 0) = radial + 2 * x * x * dradial_dr2 + 2 * p1 * y + 6 * p2 * x;
        (*J)(0, 1) = 2 * x * y * dradial_dr2 + 2 * p1 * x + 2 * p2 * y;
        (*J)(1, 0) = 2 * x * y * dradial_dr2 + 2 * p1 * x + 2 * p2 * y;
        (*J)(1, 1) = radial + 2 * y * y * dradial_dr2 + 6 * p1 * y + 2 * p2 * x;
      }
      return out;
    }
    case Distortion::kEquidistant: {
      const double r = std::sqrt(x * x + y * y);
      if (r < 1e-9) {
        if (J) J->setIdentity();
        return xn;
      }
      const double th = std::atan(r);
      const double t2 = th * th;
      const double thd = th * (1 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))));
      const double s = thd / r;
      if (J) {
        const double dthd_dth = 1 + t2 * (3 * k[0] + t2 * (5 * k[1] + t2 * (7 * k[2] + t2 * 9 * k[3])));
        const double dth_dr = 1.0 / (1 + r * r);
        const double ds_dr = (dthd_dth * dth_dr * r - thd) / (r * r);
        // d(s * xn)/dxn = s I + xn (ds/dr) (dr/dxn)^T, dr/dxn = xn / r
        *J = s * Eigen::Matrix2d::Identity() + (ds_dr / r) * xn * xn.transpose();
      }
      return s * xn;
    }
  }
  return xn;
}

}  // namespace

Vec2 CameraModel::distort(const Vec2& xn) const { return distortWithJacobian(*this, xn, nullptr); }

Vec2 CameraModel::undistort(const Vec2& xd) const {
  if (distortion == Distortion::kNone) return xd;
  if (distortion == Distortion::kEquidistant) {
    // Solve theta_d(theta) = |xd| in 1D, then scale: exact up to the Newton tolerance.
    const double rd = xd.norm();
    if (rd < 1e-12) return xd;
    double th = rd;
    for (int i = 0; i < 30; ++i) {
      const double t2 = th * th;
      const double f = th * (1 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3])))) - rd;
      const double df = 1 + t2 * (3 * k[0] + t2 * (5 * k[1] + t2 * (7 * k[2] + t2 * 9 * k[3])));
      const double step = f / df;
      th -= step;
      if (std::abs(step) < 1e-15) break;
    }
    return xd * (std::tan(th) / rd);
  }
  // Newton on distort(x) = xd from x = xd; the Jacobian is well conditioned inside the sensor.
  Vec2 x = xd;
  for (int i = 0; i < 20; ++i) {
    Eigen::Matrix2d J;
    const Vec2 err = distortWithJacobian(*this, x, &J) - xd;
    const Vec2 step = J.partialPivLu().solve(err);
    x -= step;
    if (step.squaredNorm() < 1e-28) break;
  }
  return x;
}

Vec2 CameraModel::project(const Vec3& p_c) const {
  const Vec2 xd = distort(Vec2(p_c.x() / p_c.z(), p_c.y() / p_c.z()));
  return {fx * xd.x() + cx, fy * xd.y() + cy};
}

Vec3 CameraModel::unproject(const Vec2& pixel) const {
  const Vec2 xn = undistort(Vec2((pixel.x() - cx) / fx, (pixel.y() - cy) / fy));
  return {xn.x(), xn.y(), 1.0};
}

Vec2 CameraModel::undistortPixel(const Vec2& pixel) const {
  const Vec3 ray = unproject(pixel);
  return {fx * ray.x() + cx, fy * ray.y() + cy};
}

void CameraModel::validate(const std::string& source) const {
  const double vals[4] = {fx, fy, cx, cy};
  for (double v : vals)
    if (!std::isfinite(v)) throw std::invalid_argument(source + ": non-finite intrinsic parameter");
  for (double v : k)
    if (!std::isfinite(v)) throw std::invalid_argument(source + ": non-finite distortion coefficient");
  if (fx <= 0 || fy <= 0) throw std::invalid_argument(source + ": focal length must be positive");
  if (width < 0 || height < 0) throw std::invalid_argument(source + ": negative image size");
}

}  // namespace eds
