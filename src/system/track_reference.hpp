#pragma once
// Tracking against a previous run's map (`eds track SEQUENCE --reference RUN_DIR`): every event frame
// of the sequence is tracked by the event front-end of `eds run` against the run's keyframe nearest in
// time, with that keyframe's final pose and the inverse depths the run's window gave its points. The
// sequence and the run must share the camera (the same undistorted pinhole grid).
#include "system/odometry.hpp"
#include "system/reference_run.hpp"
#include "system/track_only.hpp"

namespace eds {

// Uses cfg.event_frame, cfg.events, cfg.frame_tracker and cfg.duration_s (from the first event frame;
// 0: all). With use_frames, the sequence's frames (if any) are aligned to the keyframe nearest in time
// and correct the event front-end, whose motion prior then holds what one event frame resolves least,
// as in eds run; the output holds the event-rate poses only.
TrackOnlyResult trackAgainstReference(const Sequence& seq, const ReferenceRun& ref, const OdometryConfig& cfg,
                                      bool use_frames = true);

}  // namespace eds
