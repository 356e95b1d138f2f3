#pragma once
// The pipeline behind the stream merge: frames through the quality check, the bootstrap and the frame
// front-end; event frames (when used) through the event front-end; each given in time order. It also
// keeps the track alive: a lost track is relocalized, and when that keeps failing a new map segment
// starts with a new bootstrap (its own world frame and scale).
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "core/undistorter.hpp"
#include "frontend/frame_quality.hpp"
#include "init/bootstrap.hpp"
#include "system/event_frontend.hpp"
#include "system/frame_frontend.hpp"
#include "system/odometry.hpp"
#include "system/stage_clock.hpp"

namespace eds {

struct StampedImage {
  TimeNs t = -1;
  cv::Mat image;
};

class OdometryCore {
 public:
  OdometryCore(const CameraModel& camera, const OdometryConfig& cfg, OdometryResult& res, StageClock& clock);

  // A raw 8-bit frame.
  void frame(TimeNs t, const cv::Mat& raw);
  void eventFrame(const EventFrame& ef);
  // The exposure (of that length) of the raw frame at time t has ended; events[begin, end) are those of
  // the exposure. When that frame is the event tracker's reference, its image is deblurred with them.
  void exposureEnded(TimeNs t, TimeNs exposure, const cv::Mat& raw, const EventArray& events,
                     std::size_t begin, std::size_t end);
  // After the last input: finishes the current segment's back-end and fills the result's keyframes,
  // map, refined trajectories and back-end figures from every segment.
  void finish();

  // Called (on the caller's thread) with each keyframe the back-end retires; when it returns true,
  // the result keeps only the keyframe's time and pose, not its image and points.
  void setRetiredSink(std::function<bool(const RetiredKeyframe&)> sink) { retired_sink_ = std::move(sink); }

  TimeNs lastTime() const { return last_t_; }
  // The current segment's frame front-end.
  FrameFrontend& frontend() { return *odo_; }
  const Undistorter& undistorter() const { return und_; }

 private:
  void bootstrapFrame(TimeNs t, const cv::Mat& img);
  void trackFrame(TimeNs t, const cv::Mat& img);
  bool trackRefused(TimeNs t, const cv::Mat& raw);  // true: the refused frame gave a pose
  void initialize(TimeNs t, const cv::Mat& img);
  void trackBufferedEvents(const Trajectory& boot_traj);
  void trackEventsBeforeReference(const Keyframe& ref, const Trajectory& boot_traj);
  bool recover(TimeNs t, const cv::Mat& img, std::optional<SE3>& found);
  void trackEventsSinceLoss(TimeNs t, const SE3& T_w_f);
  void keepForBackfill(const EventFrame& ef);
  void keepSinceFrame(const EventFrame& ef);
  void sinceFrame(const StampedPose& frame, bool sparse);  // frame: the last aligned from now on
  void loseTrack(TimeNs t_last_pose, const std::string& cause);
  void startSegment(TimeNs t);
  void retireSegment();
  void collectRetired();
  void pruneBuffered(TimeNs now);
  void syncBootstrapEvents(TimeNs t);
  void syncReference();
  void trackEvents(const EventFrame& ef, const SE3* prior,
                   const std::function<bool(const SE3&)>& plausible = nullptr,
                   const std::pair<const StampedPose*, const StampedPose*>& bracket = {});
  void snapshot(const EventFrame& ef);

  const OdometryConfig& cfg_;
  OdometryResult& res_;
  StageClock& clock_;
  Undistorter und_;
  FrameQualityGate quality_;
  // The current map segment: its back-end, bootstrap and trackers start anew with each segment.
  std::unique_ptr<FrameFrontend> odo_;
  std::unique_ptr<Bootstrap> boot_;
  std::unique_ptr<EventFrontend> events_;
  bool initialized_ = false;    // the current segment's map exists
  int event_ref_version_ = -1;  // of the frame front-end's reference the events took last
  StampedImage sharp_;  // the last keyframe image deblurred for the event tracker (undistorted, float)
  std::vector<EventFrame> buffered_;
  // The event frames tracked since the last aligned frame, kept while frames come
  // feature_start.min_interval_s or more apart: tracked again from the next frame.
  std::vector<EventFrame> since_frame_;
  TimeNs since_min_dt_ = 0;                   // their spacing once they were thinned
  StampedPose last_aligned_{-1, SE3()};       // the last frame aligned
  bool sparse_frames_ = false;                // it came a sparse interval after the one before
  TimeNs buffered_min_dt_ = 0;                // spacing of the buffered event frames once they were thinned
  std::optional<EventFrontend> boot_events_;  // events against the bootstrap's reference
  TimeNs boot_ref_t_ = -1;
  int boot_restarts_ = -1;
  StampedPose boot_event_;
  bool has_boot_event_ = false;
  StampedPose last_event_;
  bool has_event_pose_ = false;
  TimeNs last_t_ = 0;
  TimeNs last_good_t_ = 0;  // of the last pose from a frame or event frame
  bool lost_ = false;
  int failed_in_row_ = 0;        // frame alignments
  int inputs_without_pose_ = 0;  // frames and event frames since the last pose
  int snapshot_ref_id_ = -1;
  std::size_t snapshot_refs_ = 0, snapshot_stride_ = 1;
  std::vector<char> frame_ok_;  // parallel to the result's frames: the alignment succeeded
  // What the back-ends of the segments before the current one left.
  std::vector<RetiredKeyframe> retired_keyframes_;
  std::function<bool(const RetiredKeyframe&)> retired_sink_;
  std::vector<MapPoint> retired_points_;
  BackendTimings retired_timings_;
  StageSeconds retired_backend_stages_{};
};

}  // namespace eds
