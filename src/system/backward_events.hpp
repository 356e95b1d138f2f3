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

// retrackEvents keeps a forward pose the backward pass disagrees with when the backward one fits its
// event frame worse by more than this (n̂·n; 0 and 0.02 measured alike, both better than no check).
constexpr double kRetrackCorrelationMargin = 0.02;

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
  std::vector<double> correlations;  // the tracker's n̂·n at each pose
  int kf_id = -1;
  SE3 T_w_kf;
};

// Tracks buffered[k] (time order) with t_min <= t < start.t, newest first, from start's pose; lists
// each rejection in `failures`.
BackwardPoses trackBackwards(const std::vector<EventFrame>& buffered, const BackwardPass& pass,
                             const CameraModel& pinhole, const OdometryConfig& cfg,
                             std::vector<OdometryFailure>& failures);

// A frame aligned after a sparse interval: the event frames tracked since the frame `before`
// (`since`, time order) are tracked again backwards from `frame` against `ref`, and the refined
// trajectory (event_anchors) merges the two passes, each trustworthy near the frame it started from:
// where they agree within the buffered gate's margins, their blend, weighted towards the later frame
// by the time fraction; where they do not, the backward pose, unless its correlation is lower than the
// forward one's by more than kRetrackCorrelationMargin. The live poses stay as tracked. Returns how many
// poses moved.
std::size_t retrackEvents(const std::vector<EventFrame>& since, const StampedPose& before,
                          const StampedPose& frame, const Keyframe& ref, const SE3& T_w_kf,
                          const CameraModel& pinhole, const OdometryConfig& cfg, OdometryResult& res);

// trackBackwards, then appends the accepted poses
// to `res` in time order (events, event_last_t, event_anchors; they must come after every pose there)
// and each rejection to its failures. Returns the number of poses added.
std::size_t trackEventsBackwards(const std::vector<EventFrame>& buffered, const BackwardPass& pass,
                                 const CameraModel& pinhole, const OdometryConfig& cfg, OdometryResult& res);

}  // namespace eds
