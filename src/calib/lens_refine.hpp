#pragma once
// Lens self-calibration from feature tracks: a bundle adjustment over all frames (poses, points and
// the lens) in raw pixels, with Ceres. Direct odometry cannot do this inside its window (7 keyframes
// over a few centimetres: each point's depth absorbs the lens error), but a track that crosses the image
// pins the lens down: under motion, its raw pixels must be the projection of one 3D point. How well it
// does is part of the result (lens_sigma_px); see README "Lens self-calibration" for what it finds on
// the shared sequences.
#include <array>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "calib/feature_tracks.hpp"
#include "core/camera.hpp"
#include "core/se3.hpp"

namespace eds {

struct LensRefineConfig {
  bool refine_radial = true;       // k1, k2
  bool refine_k3 = false;          // rarely observable on small sensors
  bool refine_tangential = false;  // p1, p2
  // fx, fy, cx, cy. Off by default: a mostly translating camera does not observe them (a pure
  // translation maps straight lines through the focus of expansion to straight lines for any fx).
  bool refine_projection = false;
  double huber_px = 1.0;          // robust loss on the reprojection error
  double outlier_px = 3.0;        // observations off by more after the fixed-lens solve are dropped
  double min_parallax_deg = 1.0;  // tracks whose rays span less are not used (no depth)
  int min_observations = 5;       // per track, after outlier removal
  int max_iterations = 100;
  // The tracks are also split into this many groups, each refined alone, for a second estimate of the
  // lens's uncertainty that sees errors correlated along a track (0: skip; costs about one more solve).
  int split_groups = 4;

  // std::invalid_argument naming the offending parameter if out of range.
  void validate() const;
};

struct LensRefineResult {
  CameraModel camera;  // the refined lens (the input's size and model)
  std::size_t tracks_used = 0;
  std::size_t observations = 0;
  double rms_fixed_px = 0;    // reprojection RMS with the given lens (poses and points optimized)
  double rms_refined_px = 0;  // with the refined lens
  bool converged = false;
  // How well the data determine the lens, as the standard deviation of the refined lens's projection at
  // the image border (worst of corners and edge midpoints, px): the larger of two estimates, NaN when
  // there is neither. Well above the tracks' noise per observation, the refined lens is a guess: keep
  // the given one (see `eds calibrate`).
  double lens_sigma_px = std::numeric_limits<double>::quiet_NaN();
  // From the solution's covariance (independent errors assumed); NaN if Ceres could not compute it.
  double lens_sigma_cov_px = std::numeric_limits<double>::quiet_NaN();
  // From the spread of the lenses refined on split_groups disjoint groups of tracks (0 if not run).
  double lens_sigma_split_px = 0;
  std::array<double, 5> k_sigma{};        // standard deviations of k1 k2 p1 p2 k3 (0 where fixed)
  std::vector<std::optional<SE3>> T_w_c;  // refined poses (scale as given)
};

// Refines the radtan lens of `camera` from `tracks` (raw pixels, indices into `T_w_c`). `T_w_c` is an
// initial pose per frame (from a first odometry pass; nullopt where there is none: observations there are
// unused); any scale. The first posed frame and the distance from it to the last posed frame fix the
// gauge. Throws std::invalid_argument if the camera is not radtan (or undistorted), there are fewer
// than two posed frames, or too few usable tracks (fewer than 20).
LensRefineResult refineLens(const CameraModel& camera, const std::vector<FeatureTrack>& tracks,
                            const std::vector<std::optional<SE3>>& T_w_c, const LensRefineConfig& cfg);

// Largest distance (px) between where lenses a and b project the rays through a's border pixels (corners
// and edge midpoints): the scale on which lens_sigma_px is given.
double lensBorderDifferencePx(const CameraModel& a, const CameraModel& b);

// The radtan distortion (OpenCV's model: k1 k2 p1 p2 k3) of the normalized point (x, y), generic in
// the scalar so that Ceres can differentiate it; k holds k1 k2 p1 p2 k3.
template <typename T>
void distortRadTan(const T* k, const T& x, const T& y, T* xd, T* yd) {
  const T r2 = x * x + y * y;
  const T radial = T(1) + r2 * (k[0] + r2 * (k[1] + r2 * k[4]));
  *xd = x * radial + T(2) * k[2] * x * y + k[3] * (r2 + T(2) * x * x);
  *yd = y * radial + k[2] * (r2 + T(2) * y * y) + T(2) * k[3] * x * y;
}

}  // namespace eds
