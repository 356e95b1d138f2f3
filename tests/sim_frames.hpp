#pragma once
// For tests that need simulated frames: the 240x180 pinhole camera they use and a sink that keeps the
// frames and depth maps the simulator renders (events dropped).
#include <cstdint>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "core/camera.hpp"
#include "core/se3.hpp"
#include "sim/event_faults.hpp"
#include "sim/simulator.hpp"
#include "sim/writer.hpp"

namespace eds::test {

inline CameraModel simCamera() {
  CameraModel c;
  c.width = 240, c.height = 180;
  c.fx = c.fy = 200;
  c.cx = 119.5, c.cy = 89.5;
  return c;
}

// The fronto-parallel plane `depth` ahead of the keyframe's camera, seen from T_f_kf: each frame pixel's
// ray meets the plane in the keyframe's image (bilinear; 0.5 where it falls outside).
inline cv::Mat renderPlaneView(const cv::Mat& kf_img, const CameraModel& cam, const SE3& T_f_kf,
                               double depth) {
  const SE3 T_kf_f = T_f_kf.inverse();
  cv::Mat mx(kf_img.size(), CV_32F), my(kf_img.size(), CV_32F), frame;
  for (int y = 0; y < kf_img.rows; ++y)
    for (int x = 0; x < kf_img.cols; ++x) {
      const Vec3 ray = T_kf_f.so3() * cam.pinholeRay(x, y);
      const Vec3& o = T_kf_f.translation();
      const Vec3 p = o + (depth - o.z()) / ray.z() * ray;
      mx.at<float>(y, x) = static_cast<float>(cam.fx * p.x() / p.z() + cam.cx);
      my.at<float>(y, x) = static_cast<float>(cam.fy * p.y() / p.z() + cam.cy);
    }
  cv::remap(kf_img, frame, mx, my, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0.5));
  return frame;
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

// What the system tests simulate: frames at 20 Hz, threshold noise 0.03 and 0.1 Hz of background
// events per pixel.
inline sim::SimConfig noisySimConfig(std::uint64_t seed) {
  sim::SimConfig sc;
  sc.fps = 20;
  sc.events.sigma_C = 0.03;
  sc.events.noise_rate_hz = 0.1;
  sc.events.seed = seed;
  return sc;
}

// Writes a simulated sequence to `dir` in the ECD layout (plain-text events, no depth maps) with the
// test camera and ground truth at sim::kGroundTruthRateHz, as `eds simulate` does.
inline void writeSimSequence(const std::filesystem::path& dir, const sim::Scene& scene,
                             const sim::Motion& motion, const sim::SimConfig& sc,
                             std::vector<sim::FrameGain> frame_gains = {},
                             const sim::EventFaults& event_faults = {}) {
  const CameraModel cam = simCamera();
  sim::EcdWriter writer(dir, false, false);
  writer.setFrameGains(std::move(frame_gains));
  sim::EventFaultSink faulty(writer, event_faults, cam.width, cam.height);
  sim::SimSink& sink = event_faults.any() ? static_cast<sim::SimSink&>(faulty) : writer;
  sim::writeEcdCalib(dir / "calib.txt", cam);
  sim::writeGroundTruth(dir / "groundtruth.txt", motion, motion.start(), motion.end(),
                        sim::kGroundTruthRateHz);
  sim::Simulator(scene, cam, motion, sc).run(motion.start(), motion.end(), sink);
  writer.finish();
}

}  // namespace eds::test
