#pragma once
// For tests that need simulated frames: the 240x180 pinhole camera they use and a sink that keeps the
// frames and depth maps the simulator renders (events dropped).
#include <cstdint>
#include <filesystem>
#include <opencv2/core.hpp>
#include <vector>

#include "core/camera.hpp"
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
  sim::writeGroundTruth(dir / "groundtruth.txt", motion, motion.start(), motion.end(), sim::kGroundTruthRateHz);
  sim::Simulator(scene, cam, motion, sc).run(motion.start(), motion.end(), sink);
  writer.finish();
}

}  // namespace eds::test
