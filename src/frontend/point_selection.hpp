#pragma once
// Point selection (paper §3.2): the image is cut into tiles and, in each, the pixels with the largest
// log-intensity gradient are kept, so that points spread over the image rather than cluster on the
// strongest edge. The same points feed the event tracker and (a subset) the back-end.
#include <opencv2/core.hpp>
#include <vector>

#include "core/reflect.hpp"

namespace eds {

struct PointSelectionConfig {
  int tile = 11;               // tile size, px
  double fraction = 0.12;      // fraction of each tile's pixels kept
  double min_gradient = 0.02;  // |∇ log I| per pixel below this is never selected (flat areas)
  int border = 4;              // pixels this close to the image border are skipped
  int max_points = 0;          // 0 = no cap; else the strongest over the whole image
  // 0 = off; else an image with more pixels than this gets the count of points of one this size:
  // tiles √(pixels / this) times larger, keeping as many points each (spread as before).
  double full_density_pixels = 0;
  void validate() const;  // throws std::invalid_argument
};

EDS_FIELDS(PointSelectionConfig, tile, fraction, min_gradient, border, max_points, full_density_pixels)

// Returns selected pixel coordinates (x, y), sorted by row then column.
std::vector<cv::Point> selectPoints(const cv::Mat& grad_x, const cv::Mat& grad_y,
                                    const PointSelectionConfig& cfg);

// The same on the gradient of an intensity image (CV_32F in [0, 1]; Sobel / 8, per pixel): what the
// frame half selects on (DSO), since the log amplifies sensor noise in dark areas of real frames.
std::vector<cv::Point> selectPointsOnIntensity(const cv::Mat& image, const PointSelectionConfig& cfg);

}  // namespace eds
