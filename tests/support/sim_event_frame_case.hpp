#pragma once
// One event-tracking case from the simulator, for tests and studies of the event tracker alone: a
// textured plane ~1 m ahead, hand-held motion, a keyframe rendered at a chosen time with its true
// depth, and one event frame of the simulated events a little later. The events come from the
// simulator's sensor model (sim/event_sim.hpp), not from the event generation model the tracker
// uses, so the case measures the tracker against physics rather than against itself.
#include <cstddef>

#include "core/camera.hpp"
#include "core/se3.hpp"
#include "frontend/event_frame.hpp"
#include "frontend/event_tracker.hpp"
#include "map/keyframe.hpp"

namespace eds {

struct SimEventFrameCaseConfig {
  double keyframe_time_s = 0.0;       // when the keyframe is rendered; the sensor runs from t = 0
  double event_frame_delay_s = 0.04;  // the event frame's centre event, after the keyframe
  int num_events = 30000;             // N of the event frame
  double contrast = 0.15;             // C, both polarities
  bool hysteresis = true;             // the sensor model's (false: an idealized sensor)
  bool reversal_compensation = EventFrameConfig{}.reversal_compensation;  // the builder's
  double texture_blur_px = 3.0;  // detail above the pixel scale, as natural scenes at 1 m
  unsigned seed = 21;            // motion and scene
};

struct SimEventFrameCase {
  CameraModel cam;  // 240x180 pinhole, f = 200
  Keyframe kf;      // image, gradients, points with true inverse depth
  EventFrame ef;
  SE3 T_ef_kf_true;
  std::size_t total_events = 0;
};

// Throws std::runtime_error when the events around the requested time cannot fill an event frame.
SimEventFrameCase makeSimEventFrameCase(const SimEventFrameCaseConfig& cfg);

struct SimCaseSolution {
  SE3 T_ef_kf;
  TrackResult first, second;  // the solve from the offset start, then the one from its solution
  double rot_err_deg = 0;
  double trans_err_mm = 0;  // camera position error
};

// Tracks the case's event frame from `offset * T_ef_kf_true` with zero velocity, then once more from
// the solution (as consecutive event frames do, with the Huber scale adapted), with default tracker
// settings; max_points > 0 thins the keyframe's points to that many (EventTracker::setKeyframe).
SimCaseSolution trackSimCase(const SimEventFrameCase& c, const SE3& offset, int max_points = 0);

}  // namespace eds
