#pragma once
// Event frames tracked backwards in time: from a pose known later (the bootstrap's reference frame, or
// the frame that recovered a lost track) each buffered event frame is tracked from the next one's pose
// by an event front-end of its own. No frames bracket these event frames, so a pose is accepted only if
// it moves from the last accepted one at most kMaxSpeedup times as fast as the camera moved on average
// around them; the pass ends after a few rejections in a row.
#include <string>
#include <utility>
#include <vector>

#include "core/camera.hpp"
#include "frontend/event_frame.hpp"
#include "map/keyframe.hpp"
#include "system/odometry.hpp"

namespace eds {

// A buffered event pose may move from the last accepted one at most this many times faster than the
// frames around it do on average (3 dropped good poses where the camera went back and forth within a
// second; 6 let more wrong ones through).
constexpr double kMaxSpeedup = 4.0;

struct BackwardPass {
  const Keyframe* ref = nullptr;  // the keyframe the events track against, at T_w_kf
  SE3 T_w_kf;
  StampedPose start;                // later than every event frame tracked
  TimeNs t_min = 0;                 // event frames before this are left alone
  double speed_t = 0, speed_r = 0;  // the camera's mean speed around them: m/s, rad/s
  std::string what;                 // names the pass in the failures it lists
};

// Translation (m/s) and rotation (rad/s) from a to b over their time apart (0 when at the same time).
std::pair<double, double> meanSpeed(const StampedPose& a, const StampedPose& b);

// The accepted poses of a backward pass, newest first, with their event frames' last event times and
// the reference they were tracked against.
struct BackwardPoses {
  Trajectory poses;
  std::vector<TimeNs> last_t;
  int kf_id = -1;
  SE3 T_w_kf;
};

// Tracks buffered[k] (time order) with t_min <= t < start.t, newest first, from start's pose; lists
// each rejection in `failures`.
BackwardPoses trackBackwards(const std::vector<EventFrame>& buffered, const BackwardPass& pass,
                             const CameraModel& pinhole, const OdometryConfig& cfg,
                             std::vector<OdometryFailure>& failures);

// A frame whose pose came from its features, away from where the events had taken the camera: the
// event frames tracked since the frame `before` (`since`, time order) are tracked again backwards from
// `frame` against `ref`. From the newest back to the first where the two agree within the buffered
// gate's margins, the refined trajectory takes the new pose (event_anchors); the live poses stay as
// tracked. Returns how many were replaced.
std::size_t retrackDriftedEvents(const std::vector<EventFrame>& since, const StampedPose& before,
                                 const StampedPose& frame, const Keyframe& ref, const SE3& T_w_kf,
                                 const CameraModel& pinhole, const OdometryConfig& cfg, OdometryResult& res);

// trackBackwards, then appends the accepted poses
// to `res` in time order (events, event_last_t, event_anchors; they must come after every pose there)
// and each rejection to its failures. Returns the number of poses added.
std::size_t trackEventsBackwards(const std::vector<EventFrame>& buffered, const BackwardPass& pass,
                                 const CameraModel& pinhole, const OdometryConfig& cfg, OdometryResult& res);

}  // namespace eds
