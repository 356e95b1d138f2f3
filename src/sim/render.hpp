#pragma once
// Renders a Scene of textured rectangles seen by a camera (with its distortion: the images are raw,
// as a real sensor's) by ray casting with a z-buffer: each plane is rasterized only over the pixels
// its outline can cover, so a room of ~30 planes costs about as much as the image area it covers.
#include <opencv2/core.hpp>
#include <vector>

#include "core/camera.hpp"
#include "sim/scene.hpp"

namespace eds::sim {

struct RenderOptions {
  int supersample = 1;      // rays per pixel along each axis (box-filtered): anti-aliasing
  double background = 0.5;  // intensity where a ray hits no plane
};

class Renderer {
 public:
  // The scene's textures must be loaded. Keeps references to scene and camera.
  Renderer(const Scene& scene, const CameraModel& camera, RenderOptions opts = {});

  // Intensity (CV_32F, in (0, 1]) and, if depth != nullptr, z-depth in metres (CV_32F, 0 where no
  // plane is hit) of the pixel centres, at camera pose T_w_c.
  void render(const SE3& T_w_c, cv::Mat& intensity, cv::Mat* depth = nullptr) const;

  const CameraModel& camera() const { return camera_; }

 private:
  struct PlaneInView;  // a plane in camera coordinates, with its pixel bounding box
  void prepare(const SE3& T_w_c, std::vector<PlaneInView>& planes) const;

  const Scene& scene_;
  CameraModel camera_;
  RenderOptions opts_;
  int ss_w_ = 0, ss_h_ = 0;                 // supersampled grid size
  std::vector<float> ray_x_, ray_y_;        // normalized ray (x, y, 1) per supersample
  std::vector<float> centre_x_, centre_y_;  // rays of the pixel centres (for depth)
};

// Bilinear sample of a CV_32F texture at (col, row), texel centres at integers; mirrored beyond the
// edges (reflect-101).
float sampleBilinearMirror(const cv::Mat& tex, double col, double row);

}  // namespace eds::sim
