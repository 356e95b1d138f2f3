#pragma once
// The odometry pipeline: bootstrap on frames, event-rate tracking of every event frame against the
// newest keyframe, direct alignment of every frame (seeded by the event pose; constant velocity with
// --frames-only), keyframes by DSO's optical-flow criterion, mapping by depth transfer, k-d tree fill and
// epipolar search, and the sliding-window photometric bundle adjustment (system/backend_worker.hpp: in
// its own thread by default).
//
// `Odometry` is the pipeline as a push API (events and frames as they arrive, results as they are
// produced); `runOdometry` drives it from a recorded sequence.
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "backend/sliding_window.hpp"
#include "core/reflect.hpp"
#include "frontend/event_frame.hpp"
#include "frontend/exposure_deblur.hpp"
#include "frontend/flicker_filter.hpp"
#include "frontend/frame_quality.hpp"
#include "frontend/frame_tracker.hpp"
#include "frontend/point_selection.hpp"
#include "frontend/relocalizer.hpp"
#include "init/bootstrap.hpp"
#include "io/sequence.hpp"
#include "mapping/depth_fill.hpp"
#include "mapping/epipolar_search.hpp"
#include "system/backend_worker.hpp"
#include "system/event_frontend.hpp"

namespace eds {

// DSO's keyframe rule: a new keyframe when the image has moved enough (flows in pixels, relative to
// width + height), when too few keyframe points remain in view, or when the brightness changed a lot.
struct FlowKeyframePolicyConfig {
  double flow_t = 0.022;       // RMS flow of the translation alone / (w + h)   (DSO: 1 / (0.04·1120))
  double flow_rt = 0.045;      // RMS flow of the whole motion / (w + h)        (DSO: 1 / (0.02·1120))
  double min_in_view = 0.7;    // fraction of the keyframe's points still in view
  double max_log_alpha = 0.7;  // |log α| of the affine brightness between frame and keyframe
  // Events mode: also a keyframe when, at the next frame (constant velocity), the translation flow or
  // the points in view would be this far past their thresholds (0: off): the events track against
  // this keyframe until then.
  double lookahead = 1.5;
  double lookahead_depth_ratio = 1.5;  // the flow part only where depths span this ratio (90th / 10th)
};

EDS_FIELDS(FlowKeyframePolicyConfig, flow_t, flow_rt, min_in_view, max_log_alpha, lookahead,
           lookahead_depth_ratio)

// How the two input streams of `Odometry` are merged into one time order. Items are processed in time
// order (a frame before an event frame of the same time). A frame waits until the events have passed
// its time stamp (the next event packet starts at or after it); an event frame waits until a frame at
// or after its time has arrived. The waits are bounded so that a stalled stream neither stops the
// other nor fills memory: an event frame goes ahead once the events have run `max_frame_wait_s` past
// it, a frame once more than `max_pending_frames` frames wait. Data that arrives after later data of
// the other stream was processed is still used when it is a frame, and dropped (as a failure) when it
// is an event frame.
struct StreamConfig {
  double max_frame_wait_s = 0.2;  // event time: how long an event frame waits for a frame before it
  int max_pending_frames = 8;     // frames waiting for events; one more and the oldest goes ahead
  // Event intake and event-frame building on a thread of their own, beside the tracking (the same
  // results; off: all on the thread that feeds the odometry).
  bool event_thread = true;
};

EDS_FIELDS(StreamConfig, max_frame_wait_s, max_pending_frames, event_thread)

// When the track is lost (frames or event frames came but gave no pose for `gap_s`, or `failed_frames`
// frame alignments failed in a row), each usable frame is relocalized against the newest keyframe (features,
// then the direct alignment) until one is found; meanwhile no pose is written and event frames wait.
struct RecoveryConfig {
  bool enabled = true;
  double gap_s = 0.3;
  int failed_frames = 3;
  double max_refinement = 0.1;  // the alignment may move the features' pose this fraction of the depth
  RelocalizerConfig relocalizer;
  // Relocalization failed on this many usable frames and for this long since the loss: a new map
  // (segment) starts with a new bootstrap.
  int new_map_after_frames = 3;
  double new_map_after_s = 1.0;
  // The event frames of the last this many seconds of a loss are kept and, once a frame relocalizes,
  // tracked backwards from it (0: the time lost keeps no event pose).
  double backfill_s = 2.0;
};

EDS_FIELDS(RecoveryConfig, enabled, gap_s, failed_frames, max_refinement, relocalizer, new_map_after_frames,
           new_map_after_s, backfill_s)

// Frames at least min_interval_s apart (0: never) are also aligned from the pose that ORB features
// matched to the reference give (recovery.relocalizer's settings); that alignment is kept when its
// residual is below max_rmse_ratio times the other starts' best over nearly as many points (or they
// failed). With retrack_events, the event poses since the frame before such a frame are tracked again
// backwards from it, and the refined trajectory merges the two passes (see backward_events.hpp): over a
// long interval the forward pass can slide along the direction one event frame resolves least.
struct FeatureStartConfig {
  double min_interval_s = 0.4;
  double max_rmse_ratio = 0.8;
  bool retrack_events = true;
  // Whether a frame at t comes a sparse interval after one at t_before (t_before < 0: none).
  bool sparse(TimeNs t_before, TimeNs t) const {
    return min_interval_s > 0 && t_before >= 0 && t - t_before >= fromSeconds(min_interval_s);
  }
};

EDS_FIELDS(FeatureStartConfig, min_interval_s, max_rmse_ratio, retrack_events)

struct OdometryConfig {
  StreamConfig stream;
  FrameQualityConfig frame_quality;
  // The frames' exposure, when known: a keyframe's image is deblurred with the events of its exposure
  // for the event tracker (off by default: exposure_s 0).
  ExposureDeblurConfig deblur;
  BootstrapConfig bootstrap;
  // The bootstrap's alignments (bootstrap.tracker) keep min_step 0: their short baselines make the
  // first map sensitive to the last tiny steps.
  FrameTrackerConfig frame_tracker{.levels = 4, .max_iterations = 20, .max_rmse = 0.1, .min_step = 1e-5};
  // Pyramid levels of the frame alignment when the event pose seeds it, and of a refused frame's.
  int prior_levels = 2;
  // Events mode: the frame alignment always starts from the frames' own constant-velocity prediction
  // too and keeps the lower residual (off: only when the event-seeded one is 15 % worse than usual).
  // The two starts end in different minima along the direction one frame resolves least; ESIM rotation
  // 0.236 -> 0.182 deg for one more alignment per frame.
  bool frame_always_tries_cv = true;
  // ... unless the constant-velocity start lies closer than this (the norm of the twist between it and
  // the event-seeded result, radians and map units) to where the first alignment ended: from there it
  // converges to the same minimum (ESIM: 125 of 128 such pairs agreed to 1e-7).
  double frame_cv_min_distance = 0.01;
  FeatureStartConfig feature_start;
  MappingConfig mapping;
  BackendConfig backend;
  FlowKeyframePolicyConfig policy;
  // The back-end in its own thread (tracking never waits for it, except when a keyframe is due while
  // the previous one is still being mapped). Off: after each keyframe, deterministic results.
  bool threaded_backend = true;
  // Threaded back-end: the frame after a keyframe waits until the back-end has mapped and optimized
  // it, and is tracked against it (as DSO runs recorded data by default). Off: tracking never waits
  // (a live camera), and events and frames track against the previous keyframe meanwhile: faster and
  // less accurate.
  bool wait_for_keyframe = true;
  // Threaded back-end, waiting for keyframes, with events: the frame after a keyframe waits only until
  // the back-end has mapped it and tracks against it at its submitted pose (seeded by the events'
  // pose); the optimized keyframe is taken up at the frame after it is published. Frames alone wait
  // for the optimized keyframe: from the constant-velocity start they lose accuracy without it. So does
  // a frame the quality check refuses, after which the events carry the pose alone.
  bool early_reference = true;
  // Events track the camera between frames (EDS); off: frames only.
  bool use_events = true;
  FlickerFilterConfig flicker_filter;
  EventFrameConfig event_frame;
  EventFrontendConfig events;
  // Event frames that arrive during the bootstrap are tracked once the map exists, from the frames'
  // poses; results farther than half the motion between the bracketing frames plus these margins are
  // rejected (translation in map units: the bootstrap's mean inverse depth is 1).
  double buffered_gate_translation = 0.002, buffered_gate_rotation_deg = 0.2;
  // Memory for those event frames: beyond it they are thinned to twice their mean spacing (evenly, so
  // that their poses still span the bootstrap), which bounds the memory of a long bootstrap at any size.
  double buffered_max_mb = 128;
  // Event frames up to this long before the bootstrap's reference are kept too, and tracked backwards
  // from it once the map exists: a restarted bootstrap leaves the time before its new reference
  // without a frame in the map (0: none).
  double buffered_before_reference_s = 1.0;
  // The refined event-rate positions (trajectory_events.txt): a local quadratic fit over ±this many
  // seconds (system/trajectory_smoothing.hpp; 0: as composed). The live poses are never smoothed.
  double event_smoothing_s = 0.1;
  // The refined event-rate poses are then anchored to the successfully aligned frames' refined poses
  // (anchorToFrames) when the median interval between those frames is at most max_interval (at lower
  // frame rates the frame poses are no better than the events'), between frames at most max_gap apart.
  double event_anchor_max_interval_s = 0.5, event_anchor_max_gap_s = 2.0;
  RecoveryConfig recovery;
  double frame_rate = 0;  // > 0: keep the frames nearest this rate
  double start_s = 0;     // skip this much from the first frame
  double duration_s = 0;  // 0: to the end
};

EDS_FIELDS(OdometryConfig, stream, frame_quality, deblur, bootstrap, frame_tracker, prior_levels,
           frame_always_tries_cv, frame_cv_min_distance, feature_start, mapping, backend, policy,
           threaded_backend, wait_for_keyframe, early_reference, use_events, flicker_filter, event_frame,
           events, buffered_gate_translation, buffered_gate_rotation_deg, buffered_max_mb,
           buffered_before_reference_s, event_smoothing_s, event_anchor_max_interval_s,
           event_anchor_max_gap_s, recovery, frame_rate, start_s, duration_s)

struct OdometryFailure {
  TimeNs t = 0;
  std::string reason;
};

// A lost track and its recovery: from the last pose before it to the first after it (-1: never).
struct TrackLoss {
  TimeNs t_lost = 0, t_recovered = -1;
  std::string cause, recovery;
  int attempts = 0;  // frames tried
  // Event frames of the time lost, tracked backwards from the frame that recovered the track.
  std::size_t event_poses_backfilled = 0;
};

// A map of its own, with its own world frame and scale: the first from the first frame, a new one each
// time relocalization kept failing. A pose belongs to the segment whose span holds its time.
struct MapSegment {
  int id = 0;
  TimeNs t_start = 0;  // its first frame (the bootstrap's first try)
  TimeNs t_init = -1;  // its map was initialized (-1: never)
  std::string cause;   // why the segment before it was left
};

// An event frame next to the event generation model's prediction at its tracked pose (both on the
// undistorted grid, unit norm), for reports: the first event frame tracked against a keyframe, for
// keyframes spread evenly over the run (at most kMax of them, whatever its length).
struct EventFrameSnapshot {
  static constexpr std::size_t kMax = 12;
  TimeNs t = 0;
  int kf_id = -1;
  double correlation = 0;    // n̂·n of the solve
  cv::Mat delta, predicted;  // CV_32F
};

// The keyframe a pose was tracked against (-1: none) and the pose relative to it.
struct PoseAnchor {
  int kf_id = -1;
  SE3 T_kf_c;
};

struct OdometryResult {
  Trajectory frames;  // one pose per frame from the bootstrap's reference on (T_w_c), as tracked
  Trajectory events;  // one pose per tracked event frame (T_w_ef), events mode, as tracked
  // Parallel to frames / events. The back-end keeps refining a keyframe after the trackers used it;
  // composed with the keyframes' final poses, the anchors give the refined trajectories (as DSO
  // writes its frames' poses: through their tracking reference's final pose).
  std::vector<PoseAnchor> frame_anchors, event_anchors;
  std::vector<double> event_correlations;  // parallel to events: the tracker's n̂·n at each pose
  Trajectory frames_refined, events_refined;
  std::size_t event_frames = 0, events_tracked = 0;  // event frames handed to the tracker, tracked
  std::vector<double> event_track_ms;
  std::vector<EventFrameSnapshot> event_snapshots;  // in time order
  Trajectory keyframes;                             // final (optimized) keyframe poses
  // Every keyframe at its final pose with its image and points, in time order (the reference map that
  // `eds track --reference` tracks against), on the undistorted grid of `pinhole`.
  std::vector<RetiredKeyframe> keyframe_maps;
  CameraModel pinhole;
  std::vector<MapPoint> map;
  std::size_t frames_in = 0, tracked = 0;
  std::size_t events_flicker_dropped = 0;  // events of flickering pixels, never put into event frames
  std::size_t frames_rejected = 0;         // kept out by the frame quality check (each one also a failure)
  std::size_t frames_tracked_only = 0;     // of those, the frames that still gave a pose (not a keyframe)
  // The frames' exposure, given, recorded with them (the median) or estimated from the first frames with
  // motion (exposure_pairs of them); 0: none. The keyframes were deblurred with it when `deblurred`.
  double exposure_s = 0;
  bool exposure_estimated = false, exposure_recorded = false, deblurred = false;
  int exposure_pairs = 0;
  std::size_t backend_waits = 0;  // times the tracking thread waited for the threaded back-end
  // Without wait_for_keyframe: keyframes wanted while the back-end was busy, left to a later frame.
  std::size_t keyframes_deferred = 0;
  std::size_t early_references = 0;  // keyframes tracked against before their bundle adjustment
  std::size_t feature_starts = 0;    // frames whose pose came from the alignment from ORB features
  std::size_t events_retracked = 0;  // event poses moved by tracking sparse intervals again backwards
  std::size_t buffered_thinned = 0;  // times the event frames kept during the bootstrap were thinned
  bool initialized = false;
  TimeNs init_t = 0;   // time of the frame that completed the initialization
  TimeNs first_t = 0;  // first frame considered
  int init_frames = 0, init_restarts = 0;
  std::vector<OdometryFailure> failures;
  std::vector<TrackLoss> losses;
  std::vector<MapSegment> segments;  // in time order; one unless the track was lost for good
  std::vector<TimeNs> event_last_t;  // per event pose: the time of its event frame's last event
  std::vector<double> track_ms, mapping_ms, ba_ms;  // per frame; per keyframe (both)
  std::vector<int> window_points;                   // per keyframe, after the solve
  double wall_s = 0, sequence_s = 0;
  // Wall time by stage of the thread that fed the odometry (they add up to wall_s), and of the
  // threaded back-end's thread (zeros without one).
  StageSeconds stages_s{}, backend_stages_s{};
  bool event_thread = false;  // event frames were built on a thread of their own, whose stages follow
  StageSeconds event_stages_s{};
  double peak_rss_mb = 0;
  // Stopped on request before the end of the input (what was computed so far is in the result).
  bool interrupted = false;
  TimeNs interrupted_t = 0;  // the last input time fed
  // Fed on the wall clock (system/realtime_run.hpp): what had to be dropped, and how late poses came.
  struct Realtime {
    bool on = false;
    double speed = 0;
    std::vector<double> latency_ms;  // per event pose: from its frame's last event to the pose
    std::size_t events_skipped = 0, frames_skipped = 0;
    int max_event_frame_stride = 1;  // the most event frames shed: all but every k-th (see below)
  } realtime;
  std::size_t event_frames_shed = 0;  // passed over, never built (Odometry::setEventFrameStride)
};

// The start times of map segments 1, 2, ... (segment 0 holds everything before the first).
std::vector<TimeNs> segmentStartTimes(const OdometryResult& r);

// A keyframe as the back-end published it (mapped and optimized once; later solves move it further).
struct KeyframeUpdate {
  int id = -1;
  TimeNs t = 0;
  SE3 T_w_kf;
  std::size_t points = 0;  // window points seen from it
};

// Results as they are produced. Every callback runs on the thread that called the `Odometry` method
// during which the result was produced (addEvents, addFrame or finish), before that call returns; the
// back-end's own thread never calls the listener. A callback must not call back into the Odometry.
class OdometryListener {
 public:
  virtual ~OdometryListener() = default;
  virtual void onInitialized(TimeNs /*t*/) {}
  // A frame's pose as tracked, and the keyframe it was tracked against (-1: none).
  virtual void onFramePose(const StampedPose& /*T_w_f*/, int /*kf_id*/) {}
  // An event frame's pose (its median event's time) as tracked.
  virtual void onEventPose(const StampedPose& /*T_w_ef*/, int /*kf_id*/) {}
  // A new tracking reference (keyframe) taken up by the trackers.
  virtual void onKeyframe(const KeyframeUpdate& /*kf*/) {}
  virtual void onFailure(const OdometryFailure& /*f*/) {}
  // The track was lost for good and a new map starts (its bootstrap from the segment's t_start on):
  // poses from here on are in the new segment's world frame and scale.
  virtual void onNewMapSegment(const MapSegment& /*segment*/) {}
  // A keyframe left the back-end's window for good: its final pose, image and points. Returning true
  // says the listener kept what it needs, and the result's keyframe_maps then hold only its time and
  // pose (no image, no points), so that a long run's memory does not grow with them.
  virtual bool onKeyframeRetired(const RetiredKeyframe& /*kf*/) { return false; }
};

// The odometry as a push API: events and frames go in as they arrive, poses come out as they are
// produced (listener and/or polling `result()`), and `finish()` ends the run with the final window
// solve, the refined trajectories, keyframe poses and map.
//
// Threading contract: an Odometry is used from one thread at a time (any thread; calls from several
// threads must be serialized by the caller). The work happens inside the calling thread's addEvents /
// addFrame / finish calls, except the back-end (mapping + bundle adjustment), which runs in a thread of
// its own when `threaded_backend` is on, and the event intake and event-frame building, in a thread of
// their own when `stream.event_thread` is on; both are joined by finish() or the destructor.
//
// Buffering: see StreamConfig. Memory is bounded by the waits (frames waiting for events, event frames
// waiting for frames), by the events of one packet and its lookahead, the producer's queue (about 1 M
// events), and the event frames kept during the bootstrap (buffered_max_mb); the only thing that grows
// with the run's length is the result itself (the poses, the points the window retires, and the
// retired keyframes' images and points unless the listener takes them).
class Odometry {
 public:
  // `camera`: the raw sensor's calibration (events and frames are in raw, distorted pixels).
  Odometry(const CameraModel& camera, const OdometryConfig& cfg, OdometryListener* listener = nullptr);
  ~Odometry();
  Odometry(const Odometry&) = delete;
  Odometry& operator=(const Odometry&) = delete;

  // Events [begin, end) of `events` (end clamped to the size), in time order, also across calls.
  // std::invalid_argument for an event out of order or outside the sensor. Ignored with
  // use_events = false.
  void addEvents(const EventArray& events, std::size_t begin = 0, std::size_t end = SIZE_MAX);
  // An 8-bit grayscale frame of the sensor's size, exposed at time t (frames in increasing time);
  // std::invalid_argument otherwise. The image is copied. `exposure`: the frame's exposure time as the
  // camera recorded it, t being its middle (0: not known). Unless the configuration gives one, frames
  // with a recorded exposure of up to 80 ms are deblurred with it, and none is estimated.
  void addFrame(TimeNs t, const cv::Mat& gray8, TimeNs exposure = 0);
  // Processes what is still waiting, converges the window and returns the whole result. Nothing may
  // be added afterwards.
  const OdometryResult& finish();
  // The result so far (poses as tracked, counts, failures); complete after finish().
  const OdometryResult& result() const;
  // Load shedding for a live caller that falls behind: from now on only every k-th event frame is
  // built and tracked (k = 1, the default: all); the others are counted in event_frames_shed. The event
  // tracker's steps grow by k, which it follows at hand-held speeds; frames and keyframes are kept.
  void setEventFrameStride(int k);
  // After finish(): moves the result out (no copy of the keyframes and map); result() is then empty.
  OdometryResult takeResult();

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

// `progress`, if given, is called now and then (at most every 0.1 s of sequence time) with the
// sequence time done and the total, in seconds (the total is the frames' span). `stop`, if given, is
// polled between chunks of input (from any thread, e.g. a signal handler): once true, no more input is
// fed, the odometry finishes with what it has, and the result says `interrupted`.
using ProgressFn = std::function<void(double done_s, double total_s)>;
OdometryResult runOdometry(const Sequence& seq, const OdometryConfig& cfg, const ProgressFn& progress = {},
                           const std::atomic<bool>* stop = nullptr, OdometryListener* listener = nullptr);

// What a run over a recorded sequence processes: the selected frames (indices into seq.frames()) and
// the time range; checks that the sequence holds what the configuration needs.
struct RunPlan {
  std::vector<std::size_t> frames;
  TimeNs first_t = 0, t_end = 0;  // the first selected frame; the end of the range (inclusive)
  double total_s = 0;             // the selected frames' span within the range
};
RunPlan planRun(const Sequence& seq, const OdometryConfig& cfg);

// Frame indices to process: [start, start + duration) from the first frame, thinned to the frames
// nearest a lower rate when frame_rate > 0.
std::vector<std::size_t> selectFrames(const std::vector<FrameRef>& frames, double start_s, double duration_s,
                                      double frame_rate);

// What a run read, for summary.json and `eds report` (left empty by callers that feed an Odometry
// themselves).
struct RunInputs {
  std::string sequence, format;
  Trajectory groundtruth;  // the recording's own, written beside the estimate (empty: none)
};

// trajectory_frames.txt (refined) and trajectory_frames_live.txt (as tracked), the same for events,
// keyframes.txt, map.ply, summary.json, timings.json (every stage's per-item times), keyframes/
// (system/reference_run.hpp), event_frames/ (system/event_snapshots.hpp) and groundtruth.txt.
void writeOdometryOutputs(const std::filesystem::path& dir, const OdometryResult& r,
                          const OdometryConfig& cfg, const RunInputs& inputs = {});

}  // namespace eds
