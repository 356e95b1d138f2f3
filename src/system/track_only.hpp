#pragma once
// Tracking-only mode (for studies and tests): keyframes come from the sequence's frames with the TRUE
// depth of their depth maps (optionally perturbed), and the event front-end of `eds run` tracks every
// event frame against the current keyframe. The first keyframe takes its ground-truth pose; every
// later one takes the pose estimated at its frame's time (event pose, refined by aligning the frame
// to the previous keyframe), so errors accumulate as in the full system.
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "frontend/event_frame.hpp"
#include "frontend/frame_tracker.hpp"
#include "io/sequence.hpp"
#include "system/event_frontend.hpp"

namespace eds {

struct KeyframePolicyConfig {
  double max_point_drop = 0.25;         // new keyframe when points in view fall by this fraction
  double max_rotation_deg = 10.0;       // ... or the rotation from the keyframe exceeds this
  double max_translation_ratio = 0.15;  // ... or translation / median scene depth exceeds this
};

struct TrackOnlyConfig {
  EventFrameConfig event_frame;
  // The event front-end: tracker, point selection, the median filter of the keyframe's inverse depths
  // (noisy depth attenuates the tracker's translation: with 10 % noise on the ESIM plane the ATE is
  // 15 cm unfiltered, 0.9 cm at 10 px) and the lost-track check (a lost event frame's pose is not
  // kept; the next keyframe's frame is aligned from the last good pose).
  // Without the persistent-outlier rule: no frames gate it here, and keyframes of known depth come at
  // the keyframe rate.
  EventFrontendConfig events = [] {
    EventFrontendConfig c;
    c.persistent_outliers.frames = 0;
    return c;
  }();
  KeyframePolicyConfig policy;
  FrameTrackerConfig frame_tracker;
  // A new keyframe's pose: the event pose at its frame's time, refined by aligning the frame to the
  // previous keyframe (on by default; off = event poses only).
  bool refine_keyframes = true;
  double depth_noise = 0.0;  // sigma of additive depth noise, as a fraction of the median depth
  std::uint64_t seed = 1;
  double duration_s = 0.0;          // 0 = the whole sequence (from the first frame)
  std::filesystem::path debug_dir;  // non-empty: write event frame | prediction PNGs there
};

struct TrackFailure {
  TimeNs t = 0;
  std::string reason;
};

struct TrackOnlyResult {
  Trajectory trajectory;  // first keyframe's pose, then one pose per tracked event frame (T_w_ef)
  std::size_t event_frames = 0, tracked = 0, keyframes = 0;
  std::vector<TrackFailure> failures;
  std::vector<double> build_ms, track_ms;  // per event frame
  std::vector<double> frame_track_ms;      // per keyframe hand-over
  std::vector<double> correlations;        // per tracked event frame: n̂·n after the solve
  std::vector<int> points_per_keyframe;
  double wall_s = 0;
  double sequence_s = 0;  // span of the event frames processed
};

TrackOnlyResult runTrackOnly(const Sequence& seq, const TrackOnlyConfig& cfg);

// summary.json of a run (counts, timings with median/p95, failures, real-time factor); `mode` names
// the command, `config` the parameters worth recording as (name, value) pairs.
void writeTrackSummary(const std::filesystem::path& file, const TrackOnlyResult& r, const std::string& mode,
                       const std::vector<std::pair<std::string, double>>& config);
// The same for tracking-only with depth from the ground truth.
void writeTrackSummary(const std::filesystem::path& file, const TrackOnlyResult& r,
                       const TrackOnlyConfig& cfg);

}  // namespace eds
