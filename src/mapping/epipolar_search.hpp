#pragma once
// Depth of a new keyframe's points by search along the epipolar line in an older keyframe of the window
// (DSO refines its immature points this way, forward in time; the window's older keyframes already
// give the baseline, so the search can run at once). For each point, inverse depths between rho_lo and
// rho_hi are scanned in sub-pixel steps along the line, comparing DSO's 8-pixel pattern under the
// affine brightness of both frames; the best match must be good and unique, and is refined by
// Gauss-Newton on the inverse depth. Depth filled from the nearest projected point (depth_fill.hpp)
// cannot tell surfaces apart at occlusion boundaries; the search can.
#include <opencv2/core.hpp>
#include <vector>

#include "core/camera.hpp"
#include "core/se3.hpp"
#include "core/reflect.hpp"

namespace eds {

struct EpipolarSearchConfig {
  double step_px = 0.5;      // sampling step along the line
  double max_rms = 0.04;     // pattern RMS (intensity) of an acceptable match
  double uniqueness = 1.5;   // second-best match (two steps away or more) ≥ this × best, in energy
  double min_line_px = 2.0;  // shorter search lines: depth unobservable, no result
  int max_samples = 400;     // per point (long lines are sampled more coarsely)
};

EDS_FIELDS(EpipolarSearchConfig, step_px, max_rms, uniqueness, min_line_px, max_samples)

struct SearchFrame {
  const cv::Mat* image = nullptr;  // CV_32F in [0, 1], undistorted
  SE3 T_w_c;
  double a = 0, b = 0;  // affine brightness (photometric BA convention)
};

struct EpipolarMatch {
  double inv_depth = 0;  // 0: no result
  double line_px = 0;    // length of the searched segment (baseline proxy)
  double rms = 0;
};

// One result per pixel of the host.
std::vector<EpipolarMatch> epipolarSearch(const SearchFrame& host, const SearchFrame& ref,
                                          const CameraModel& cam, const std::vector<cv::Point>& pixels,
                                          double rho_lo, double rho_hi, const EpipolarSearchConfig& cfg);

}  // namespace eds
