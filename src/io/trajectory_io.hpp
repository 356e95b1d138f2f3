#pragma once
// TUM trajectory files: one pose per line, `t tx ty tz qx qy qz qw`, camera-to-world (T_w_c), seconds.
#include <filesystem>
#include <vector>

#include "core/se3.hpp"
#include "core/time.hpp"

namespace eds {

struct StampedPose {
  TimeNs t = 0;
  SE3 T_w_c;
};
using Trajectory = std::vector<StampedPose>;

// Reads a TUM (or ECD groundtruth.txt) file. Lines starting with '#' and blank lines are skipped;
// commas count as separators. Throws InputError naming file and line for malformed content,
// non-finite values, zero quaternions, or (unless allow_unsorted) decreasing timestamps.
// `segment_starts` (optional): the index of the first pose after each "# segment" line.
Trajectory readTum(const std::filesystem::path& file, bool allow_unsorted = false,
                   std::vector<std::size_t>* segment_starts = nullptr);
// Writes with 9 decimals for time and position, 9 for quaternions. `segment_starts`: indices of
// poses that begin a new map segment (its own world frame and scale), each marked by a line
// "# segment K" before it.
void writeTum(const std::filesystem::path& file, const Trajectory& traj,
              const std::vector<std::size_t>& segment_starts = {});
// The index of the first pose at or after each time (poses in time order): where segments begin.
std::vector<std::size_t> indicesFrom(const Trajectory& traj, const std::vector<TimeNs>& times);

}  // namespace eds
