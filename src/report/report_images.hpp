#pragma once
// Images for the HTML report, inlined as PNG data URIs: keyframes with their points coloured by
// inverse depth, their sparse depth, and signed images (event frames, the model's prediction).
#include <opencv2/core.hpp>
#include <string>

#include "map/keyframe.hpp"

namespace eds::report {

// data:image/png;base64,... of an 8-bit gray or BGR image: for drawings with few colours.
std::string pngDataUri(const cv::Mat& image);
// data:image/jpeg;base64,... (quality 90): for photographs, which PNG keeps at ten times the size.
std::string jpegDataUri(const cv::Mat& image);

// Scale factor that brings a sensor image to at least `min_width` pixels wide (whole numbers).
int displayScale(int width, int min_width = 480);

// The keyframe's image with each point drawn in the turbo colour map of its inverse depth (near: red,
// far: blue; between the 5th and 95th percentiles of the keyframe's points).
cv::Mat keyframePointsImage(const Keyframe& kf);
// The same points alone on black: the keyframe's sparse inverse depth.
cv::Mat keyframeDepthImage(const Keyframe& kf);
// A signed CV_32F image: positive red, negative blue, zero white, saturating at the 99th percentile of
// the non-zero magnitudes. At the image's own size (the page scales it up).
cv::Mat signedImage(const cv::Mat& x);

}  // namespace eds::report
