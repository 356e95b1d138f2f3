#pragma once
// A run's event-frame snapshots (EventFrameSnapshot) on disk, for `eds report`. Layout, under
// RUN_DIR/event_frames/:
//   index.txt         one line per snapshot: `t_ns kf_id correlation scale_delta scale_predicted`
//   ef_NN_delta.png   the event frame ΔL, 16-bit: value = 32768 + round(32767 x / scale_delta)
//   ef_NN_model.png   the model's prediction ΔL̂, encoded the same way with scale_predicted
#include <filesystem>
#include <vector>

#include "system/odometry.hpp"

namespace eds {

void writeEventSnapshots(const std::filesystem::path& dir, const std::vector<EventFrameSnapshot>& shots);
// Reads dir/event_frames/ (empty when the folder does not exist: a frames-only run); InputError naming
// the file (and line) for anything malformed.
std::vector<EventFrameSnapshot> readEventSnapshots(const std::filesystem::path& dir);

}  // namespace eds
