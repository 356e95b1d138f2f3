#pragma once
// The back-end's sliding window (paper §3.3, DSO): up to `window` keyframes with the points they host,
// optimized together by the photometric bundle adjustment. When the window is full one keyframe leaves:
// by DSO's rule (keyframeToRemove), not simply the oldest, so that the window keeps a long baseline.
// With `marginalize`, its points' residuals and the old prior become a Gaussian prior on the keyframes
// that stay (Schur complement); without, its information is dropped, as the authors' code does. The
// oldest keyframe in the window is held fixed (gauge).
#include <utility>
#include <vector>

#include "backend/photometric_ba.hpp"
#include "core/camera.hpp"
#include "core/reflect.hpp"
#include "core/time.hpp"
#include "map/keyframe.hpp"

namespace eds {

enum class WindowRemoval { kOldest, kDso };
constexpr std::array<std::pair<WindowRemoval, std::string_view>, 2> enumNames(WindowRemoval) {
  return {{{WindowRemoval::kOldest, "oldest"}, {WindowRemoval::kDso, "dso"}}};
}

struct BackendConfig {
  int window = 7;                 // keyframes
  int points_per_keyframe = 300;  // points hosted by each keyframe in the optimization
  // Keep dropped keyframes' information as a prior (first-estimate Jacobians, see photometric_ba.hpp).
  // Off by default: measured against dropping it (the authors' code drops it), --sync-backend:
  //   frames only: slider 0.53 -> 0.46 cm, rotation drift 4.4 -> 3.8 deg; ESIM 0.109 cm / 0.191 deg
  //   -> 0.108 cm / 0.213 deg; room 0.076 -> 0.083 cm;
  //   events: ESIM 0.133 cm / 0.180 deg -> 0.132 cm / 0.214 deg, room and desk within 0.01 cm.
  // (Without first estimates it had pulled the scale: ESIM 0.76 cm, slider 2.4 cm.) Those with the
  // oldest-leaves rule; with DSO's (below), threaded: slider drift over the slide, median of 5 start
  // times, 1.42 -> 2.18 deg; ESIM frames 0.086 cm / 0.100 deg -> 0.083 / 0.094, events 0.113 / 0.124
  // -> 0.109 / 0.097; room frames and desk events at 5 Hz within 0.01 cm.
  bool marginalize = false;
  // Which keyframe leaves a full window. kDso, DSO's rule: the oldest one whose points have left the
  // newest keyframe's view (fewer than min_visible of them inside its image), else the one maximizing
  // sqrt(d(i, newest)) · Σ_j 1 / d(i, j) over the camera distances d in the window; the newest two
  // always stay. The window keeps keyframes spread along the path, old ones included, and so a long
  // baseline: on a slide the rotation is observable only through second-order image terms that grow
  // with the baseline. kOldest: the oldest leaves (docs/experiments.md compares them).
  WindowRemoval removal = WindowRemoval::kDso;
  double min_visible = 0.05;
  BaConfig ba;
  void validate() const;
};

EDS_FIELDS(BackendConfig, window, points_per_keyframe, marginalize, removal, min_visible, ba)

struct MapPoint {
  Vec3 p_w;
  float intensity = 0;  // host image intensity in [0, 1]
};

// A keyframe that left the window, at its final pose, with what a later run needs to track against it
// (eds track --reference): its image and the window's points seen from it.
struct RetiredKeyframe {
  int id = 0;
  TimeNs t = 0;
  SE3 T_w_kf;
  cv::Mat image;                      // CV_8U, undistorted (the window's image, rounded)
  std::vector<KeyframePoint> points;  // u, v, inv_depth only
};

class SlidingWindow {
 public:
  SlidingWindow(const CameraModel& pinhole, BackendConfig cfg);

  // Adds a keyframe with its image (undistorted, CV_32F in [0, 1]), its pose and brightness, and the
  // points it hosts (points without an inverse depth are skipped; at most points_per_keyframe, spread
  // evenly over the list). Every point in the window is then observed in every other keyframe.
  void addKeyframe(int id, TimeNs t, const SE3& T_w_kf, double a, double b, const cv::Mat& image,
                   const std::vector<KeyframePoint>& points);
  // Optimizes the window; then removes keyframes (keyframeToRemove) while there are more than `window`.
  BaStats optimize();
  // Index in frames() of the keyframe that leaves the window next (BackendConfig::removal).
  int keyframeToRemove() const;

  int size() const { return static_cast<int>(frames_.size()); }
  int newestId() const { return ids_.back(); }
  const BaFrame& newest() const { return frames_.back(); }
  const std::vector<BaFrame>& frames() const { return frames_; }
  // Pose of keyframe `id` if it is in the window.
  const BaFrame* frame(int id) const;
  // Points of the window in the newest keyframe's pixel grid, with inverse depths there (for the
  // trackers and for mapping a new keyframe); `hosted` false leaves out the keyframe's own points.
  std::vector<KeyframePoint> pointsInNewest(bool hosted = true) const { return pointsIn(size() - 1, hosted); }
  // The same in the pixel grid of frames()[f].
  std::vector<KeyframePoint> pointsIn(int f, bool hosted = true) const;
  std::vector<Vec3> worldPoints() const;
  int numPoints() const;
  int numPriorFrames() const { return static_cast<int>(prior_.frames.size()); }

  // Everything that left the window (marginalized), and, with flush(), what is in it now; moved out
  // (a long run's keyframe images and points are its largest share of memory: no second copy).
  std::vector<RetiredKeyframe> takeRetiredKeyframes() { return std::exchange(retired_kf_, {}); }
  std::vector<MapPoint> takeRetiredPoints() { return std::exchange(retired_pts_, {}); }
  void flush();

 private:
  void removeKeyframe(int m);
  void retirePointsOf(int frame_index);
  void retireKeyframe(int frame_index);

  CameraModel cam_;
  BackendConfig cfg_;
  PhotometricBA ba_;
  std::vector<BaFrame> frames_;
  std::vector<int> ids_;
  std::vector<TimeNs> times_;
  std::vector<BaPoint> points_;
  BaPrior prior_;
  std::vector<RetiredKeyframe> retired_kf_;
  std::vector<MapPoint> retired_pts_;
};

}  // namespace eds
