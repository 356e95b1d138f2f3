#pragma once
// Sparse feature tracks through a frame sequence (pyramidal Lucas-Kanade, OpenCV), in raw (distorted)
// pixels. They serve lens self-calibration: a long track is a sample of the lens's mapping across the
// image, which a window of direct odometry cannot observe (each point's depth absorbs it).
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "core/camera.hpp"

namespace eds {

struct FeatureTrack {
  std::vector<int> frames;  // indices into the frame list, increasing by 1 (a track has no gaps)
  std::vector<Vec2> px;     // raw pixel in each of those frames
};

struct FeatureTrackConfig {
  int max_features = 400;        // features kept alive at once
  double quality = 0.01;         // goodFeaturesToTrack, relative to the frame's strongest corner
  double min_distance_px = 8.0;  // between features (new ones keep this far from live ones)
  int window_px = 21;            // Lucas-Kanade window
  int pyramid_levels = 3;
  double max_fb_error_px = 0.5;  // forward-backward check: track back and land within this
  int border_px = 4;             // features closer to the edge are dropped
  int min_length = 5;            // shorter tracks are not returned

  // std::invalid_argument with the offending parameter if out of range.
  void validate() const;
};

// Tracks features through `frames` (8-bit grayscale, all the same size; empty Mats are gaps that end
// every live track). Each frame pair is tracked forward and back; features that do not return to within
// max_fb_error_px are dropped, so tracks stop at occlusions rather than slide along edges.
std::vector<FeatureTrack> trackFeatures(const std::vector<cv::Mat>& frames, const FeatureTrackConfig& cfg);

}  // namespace eds
