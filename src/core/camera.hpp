#pragma once
// Camera models: pinhole with radial-tangential (k1 k2 p1 p2 k3, OpenCV/Kalibr "radtan") or
// equidistant fisheye (k1..k4, Kalibr "equidistant", OpenCV fisheye) distortion. Pixel centres are at
// integer coordinates (OpenCV convention). Camera axes: x right, y down, z forward.
#include <Eigen/Core>
#include <array>
#include <string>

#include "core/se3.hpp"

namespace eds {

using Vec2 = Eigen::Vector2d;

enum class Distortion { kNone, kRadTan, kEquidistant };

const char* toString(Distortion d);

struct CameraModel {
  int width = 0;
  int height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  Distortion distortion = Distortion::kNone;
  std::array<double, 5> k{};  // radtan: k1 k2 p1 p2 k3; equidistant: k1 k2 k3 k4 (k[4] unused)

  // Normalized undistorted coordinates (x/z, y/z) -> normalized distorted coordinates.
  Vec2 distort(const Vec2& xn) const;
  // Inverse of distort, by Newton iterations (converges to ~1e-12 within the sensor).
  Vec2 undistort(const Vec2& xd) const;

  // 3D point in the camera frame -> raw (distorted) pixel.
  Vec2 project(const Vec3& p_c) const;
  // Raw pixel -> point on the normalized plane (x, y, 1) of its ray.
  Vec3 unproject(const Vec2& pixel) const;
  // The same for a camera without distortion (the undistorted grid the trackers work on), inline for
  // per-point loops.
  Vec3 pinholeRay(double u, double v) const { return {(u - cx) / fx, (v - cy) / fy, 1.0}; }

  // Raw pixel -> pixel of the undistorted pinhole image with the same fx, fy, cx, cy.
  Vec2 undistortPixel(const Vec2& pixel) const;

  bool inside(const Vec2& px, double border = 0.0) const {
    return px.x() >= border && px.y() >= border && px.x() <= width - 1 - border &&
           px.y() <= height - 1 - border;
  }
  // Throws std::invalid_argument (with `source` in the message) if a parameter is non-finite,
  // a focal length is not positive, or the size is negative.
  void validate(const std::string& source) const;
};

}  // namespace eds
