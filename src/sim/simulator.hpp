#pragma once
// Drives the renderer and the event generator along a motion: renders at a rate adapted to the motion
// (no pixel moves more than ~max_px_per_step between renders) or at a fixed rate, emits events between
// renders, renders frames (optionally exposure-blurred) with z-depth at the frame rate.
#include <functional>

#include "sim/event_sim.hpp"
#include "sim/motion.hpp"
#include "sim/render.hpp"

namespace eds::sim {

struct SimConfig {
  EventSimConfig events;
  RenderOptions render;
  double fps = 25.0;             // frames per second; 0 = no frames
  double exposure_s = 0.0;       // frame exposure (motion blur); 0 = instantaneous
  double render_hz = 0.0;        // fixed render rate; 0 = adaptive
  double max_px_per_step = 0.5;  // adaptive: largest pixel displacement between renders
  double min_step_s = 2e-5, max_step_s = 5e-3;
  bool quantize_8bit = false;  // events from 8-bit images (as ESIM on stored frames)
};

struct SimStats {
  std::size_t events = 0, renders = 0, frames = 0;
  double wall_s = 0;
};

class SimSink {
 public:
  virtual ~SimSink() = default;
  virtual void onEvents(const EventArray& events) = 0;  // time-ordered batches
  // Raw (distorted) intensity in (0, 1] (CV_32F) and z-depth in metres (CV_32F, 0 = no hit).
  virtual void onFrame(TimeNs t, const cv::Mat& intensity, const cv::Mat& depth) = 0;
};

// The camera `eds simulate` uses by default: pinhole, about 62 degrees of horizontal field of view like
// a DAVIS240 with its standard lens (f = 200 px at 240 px wide), principal point at the centre.
CameraModel defaultCamera(int width, int height);

class Simulator {
 public:
  Simulator(const Scene& scene, const CameraModel& camera, const Motion& motion, SimConfig cfg);
  // Simulates [t0, t1] (within the motion's span).
  SimStats run(TimeNs t0, TimeNs t1, SimSink& sink);

 private:
  double maxDisplacement(const SE3& T_w_a, const SE3& T_w_b) const;  // px, over sample points
  void refreshSamplePoints(const SE3& T_w_c);
  void renderFrame(TimeNs t, SimSink& sink);

  const Scene& scene_;
  CameraModel camera_;
  const Motion& motion_;
  SimConfig cfg_;
  Renderer renderer_;
  std::vector<Vec3> sample_points_w_;  // scene points seen on a sparse pixel grid
};

}  // namespace eds::sim
