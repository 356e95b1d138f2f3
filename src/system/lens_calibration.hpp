#pragma once
// Lens self-calibration of a sequence: feature tracks through its frames and a bundle adjustment of the
// lens with the poses of a first odometry pass (calib/). `eds calibrate` runs it; `eds run --calib`
// then uses the refined lens.
#include <cstddef>
#include <optional>
#include <vector>

#include "calib/feature_tracks.hpp"
#include "calib/lens_refine.hpp"
#include "io/sequence.hpp"
#include "io/trajectory_io.hpp"

namespace eds {

struct LensCalibrationConfig {
  FeatureTrackConfig tracks;
  LensRefineConfig refine;
  double max_pose_gap_s = 0.005;  // a frame takes the trajectory's pose nearest in time, if this close
};

struct LensCalibrationReport {
  LensRefineResult result;
  std::size_t frames = 0, posed_frames = 0, tracks = 0;
  double mean_track_length = 0;
};

// The trajectory's pose for each frame (nearest in time within max_gap_s, else nullopt).
std::vector<std::optional<SE3>> posesAtFrames(const std::vector<FrameRef>& frames, const Trajectory& T_w_c,
                                              double max_gap_s);

// Throws std::invalid_argument when the trajectory poses fewer than two frames or the refinement has too
// little to work with (the message says which).
LensCalibrationReport calibrateLens(const Sequence& seq, const Trajectory& T_w_c,
                                    const LensCalibrationConfig& cfg);

}  // namespace eds
