#pragma once
// Mapping (paper §3.3): a new keyframe's selected pixels get inverse depths from the map. The window's
// points are projected into the new keyframe; each selected pixel takes the inverse depth of the
// nearest projected point (a k-d tree over the projections, nanoflann), and the back-end refines it.
#include <opencv2/core.hpp>
#include <vector>

#include "core/camera.hpp"
#include "core/se3.hpp"
#include "core/reflect.hpp"

namespace eds {

struct ProjectedPoint {
  float u = 0, v = 0;    // pixel in the new keyframe
  double inv_depth = 0;  // 1 / z in the new keyframe
};

struct DepthFillConfig {
  double max_distance_px = 12.0;  // farther from every projected point: the pixel gets no depth (0)
  int neighbours = 3;             // inverse depth = median over this many nearest projections
};

EDS_FIELDS(DepthFillConfig, max_distance_px, neighbours)

// Projects world points (with the keyframe pose T_w_kf) into a pinhole camera; keeps those in front
// of the camera and inside the image.
std::vector<ProjectedPoint> projectPoints(const std::vector<Vec3>& p_w, const SE3& T_w_kf,
                                          const CameraModel& pinhole);

// Inverse depth per pixel from the nearest projected points; 0 where none is within reach.
std::vector<double> fillInverseDepth(const std::vector<cv::Point>& pixels,
                                     const std::vector<ProjectedPoint>& projected,
                                     const DepthFillConfig& cfg);

// Replaces each inverse depth by the median over the points within `radius_px` (itself included):
// i.i.d. depth noise shrinks the translational part of a direct tracker's motion estimate (the
// regressor is noisy: attenuation), most where the scene's depth varies little; the median keeps
// depth edges. Points with no depth (0) are neither changed nor used.
void medianFilterInverseDepth(std::vector<cv::Point2f>& px, std::vector<double>& inv_depth, double radius_px);

}  // namespace eds
