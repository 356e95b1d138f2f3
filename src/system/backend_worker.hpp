#pragma once
// The back-end side of the odometry: mapping a new keyframe (point selection, depth transfer and
// epipolar search against the window) and the sliding-window bundle adjustment, in a thread of its
// own so that frame tracking never waits for it (paper Fig. 2; DSO's mapping thread). The front-end
// submits a keyframe and goes on tracking against the previous reference; when the worker has mapped
// and optimized the keyframe it publishes a new tracking reference (the newest keyframe with every
// window point projected into it), which the front-end picks up at its next frame; with
// early_reference also a preliminary one as soon as the keyframe is mapped.
#include <condition_variable>
#include <deque>
#include <mutex>
#include <optional>
#include <thread>
#include <vector>

#include "backend/sliding_window.hpp"
#include "core/reflect.hpp"
#include "frontend/point_selection.hpp"
#include "mapping/depth_fill.hpp"
#include "mapping/epipolar_search.hpp"
#include "system/stage_clock.hpp"

namespace eds {

struct MappingConfig {
  PointSelectionConfig points{
      .tile = 8, .fraction = 0.06, .min_gradient = 0.01, .border = 4, .max_points = 0};
  DepthFillConfig fill;
  EpipolarSearchConfig search;
  bool epipolar_search = true;           // new points' depth by search in older keyframes (off: fill only)
  double search_max_disagreement = 0.2;  // two keyframes' inverse depths differ more: point dropped
  double min_intensity = 0.02, max_intensity = 0.98;  // black or saturated pixels are not selected
};

EDS_FIELDS(MappingConfig, points, fill, search, epipolar_search, search_max_disagreement, min_intensity,
           max_intensity)

struct KeyframeJob {
  TimeNs t = 0;
  cv::Mat image;  // undistorted, CV_32F in [0, 1]
  SE3 T_w_kf;
  double a = 0, b = 0;
  std::vector<KeyframePoint> points;  // with depth already (bootstrap), or empty: mapping selects them
};

// What the front-end tracks against.
struct TrackingReference {
  int id = -1;
  Keyframe kf;  // image and points (window points projected into it, with inverse depths)
  double a = 0, b = 0;
  // Published once the keyframe is mapped, before the bundle adjustment: the keyframe at the pose it
  // was submitted with and the window's earlier points as the last solve left them (its own new ones,
  // from the epipolar search alone, left out). The optimized one follows (same id).
  bool preliminary = false;
};

struct BackendTimings {
  std::vector<double> mapping_ms, ba_ms;
  std::vector<int> window_points;
};

class BackendWorker {
 public:
  // `caller_clock` (may be null): the submitting thread's stage clock; it is charged with the waits
  // for the worker and, without a thread, with the mapping and the bundle adjustment.
  // `early_reference` (threaded only): each keyframe's reference is published twice, once mapped
  // (preliminary) and once optimized.
  BackendWorker(const CameraModel& pinhole, const MappingConfig& mapping, const BackendConfig& backend,
                bool threaded, StageClock* caller_clock = nullptr, int first_id = 0,
                bool early_reference = false);
  ~BackendWorker();
  BackendWorker(const BackendWorker&) = delete;
  BackendWorker& operator=(const BackendWorker&) = delete;

  // Queues a keyframe (threaded) or processes it at once; returns the id it gets (ids are given in
  // the order of submission).
  int submit(KeyframeJob job);
  bool busy() const;
  // The id the next keyframe submitted will get (read while no keyframe is queued or in work).
  int nextId() const;
  void waitIdle();
  // Waits until every submitted keyframe is mapped (with early_reference; else until idle).
  void waitMapped();
  // Waits for the queued keyframes, then converges the window once more and retires it (the last
  // keyframes had fewer solves than the ones before them), on the worker's thread when it has one.
  // The window's outputs are final afterwards; no keyframe may be submitted after it.
  void finish();
  // The newest reference published since the last call, if any.
  std::optional<TrackingReference> takeReference();
  // The keyframes the window retired (at their final poses) since the last call; from any thread.
  std::vector<RetiredKeyframe> takeRetired();
  // After waitIdle(): the window (for outputs) and the timings.
  SlidingWindow& window() { return window_; }
  const BackendTimings& timings() const { return timings_; }
  // After finish(), threaded: the worker thread's time by stage (mapping, bundle adjustment, idle).
  StageSeconds threadStageSeconds() { return thread_clock_.seconds(); }

 private:
  void run();
  void finalSolve();
  void publishRetired();  // with mutex_ held
  void process(KeyframeJob& job);
  // The newest keyframe with the window's points projected into it; without its own new points
  // (their depths not yet optimized) for the preliminary reference.
  TrackingReference newestReference(int id, TimeNs t, bool with_new_points = true) const;
  void searchDepths(const cv::Mat& img, const SE3& T_w_new, double a, double b,
                    const std::vector<cv::Point>& px, const std::vector<ProjectedPoint>& proj,
                    std::vector<double>& rho) const;

  CameraModel cam_;
  MappingConfig mcfg_;
  SlidingWindow window_;
  BackendTimings timings_;
  int next_id_ = 0;       // the worker's
  int submitted_id_ = 0;  // the caller's

  bool threaded_, early_reference_;
  StageClock* caller_clock_;
  StageClock thread_clock_{Stage::kIdle};  // only the worker thread uses it until finish()
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<KeyframeJob> queue_;
  bool working_ = false, stop_ = false, finish_ = false, finished_ = false;
  bool mapped_ = false;  // the keyframe in work is mapped
  std::optional<TrackingReference> published_;
  std::vector<RetiredKeyframe> retired_;  // moved out of the window after each keyframe
  std::thread thread_;
};

}  // namespace eds
