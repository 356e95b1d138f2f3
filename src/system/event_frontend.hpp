#pragma once
// The event half of the front-end (paper §3.2): every event frame is tracked against the newest
// keyframe reference by the EGM tracker, giving event-rate poses between frames. The reference is the
// back-end's (its window points projected into the newest keyframe); the keyframe's other selected
// pixels take the inverse depth of the nearest of those points (k-d tree), so the tracker sees the
// paper's 10-15 % of pixels. Frames, when they come, correct the estimate (they are sharper).
#include <optional>

#include "frontend/event_frame.hpp"
#include "frontend/event_tracker.hpp"
#include "frontend/point_selection.hpp"
#include "mapping/depth_fill.hpp"

namespace eds {

struct EventFrontendConfig {
  EventTrackerConfig tracker;
  PointSelectionConfig points;  // selection on the keyframe's log gradient (as in tracking-only mode)
  DepthFillConfig fill{.max_distance_px = 1, .neighbours = 3};
  double depth_median_px = 10.0;  // median filter of the reference's inverse depths (0: off)
};

class EventFrontend {
 public:
  EventFrontend(const CameraModel& pinhole, EventFrontendConfig cfg);

  // A new reference: keyframe intensity image and points with inverse depths, and its pose.
  void setReference(const Keyframe& ref, const SE3& T_w_kf);
  bool hasReference() const { return has_ref_; }
  // Tracks an event frame from the prior (if given) or a constant-velocity prediction. The pose
  // (T_w_ef), or nullopt when the frame cannot be tracked (the estimate then stays as it was).
  std::optional<SE3> track(const EventFrame& ef, const SE3* prior, std::string* failure = nullptr);
  // A better pose at time t (a tracked frame): the next event frame starts from it.
  void correct(TimeNs t, const SE3& T_w_c);
  int numPoints() const { return static_cast<int>(tracker_.numPoints()); }

 private:
  CameraModel cam_;
  EventFrontendConfig cfg_;
  EventTracker tracker_;
  bool has_ref_ = false;
  SE3 T_w_kf_;
  SE3 T_ef_kf_, T_prev_;  // current estimate and the one before (constant-velocity prediction)
  Vec6 nu_ = Vec6::Zero();
  TimeNs t_last_ = -1, t_prev_ = -1;
  bool corrected_ = false;
};

}  // namespace eds
