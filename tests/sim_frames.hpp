#pragma once
// For tests that need simulated frames: the 240x180 pinhole camera they use and a sink that keeps the
// frames and depth maps the simulator renders (events dropped).
#include <opencv2/core.hpp>
#include <vector>

#include "core/camera.hpp"
#include "sim/simulator.hpp"

namespace eds::test {

inline CameraModel simCamera() {
  CameraModel c;
  c.width = 240, c.height = 180;
  c.fx = c.fy = 200;
  c.cx = 119.5, c.cy = 89.5;
  return c;
}

struct FrameSink : sim::SimSink {
  void onEvents(const EventArray&) override {}
  void onFrame(TimeNs t, const cv::Mat& intensity, const cv::Mat& depth) override {
    times.push_back(t);
    images.push_back(intensity.clone());
    depths.push_back(depth.clone());
  }
  std::vector<TimeNs> times;
  std::vector<cv::Mat> images, depths;
};

}  // namespace eds::test
