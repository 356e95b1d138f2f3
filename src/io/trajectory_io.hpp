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
Trajectory readTum(const std::filesystem::path& file, bool allow_unsorted = false);
// Writes with 9 decimals for time and position, 9 for quaternions.
void writeTum(const std::filesystem::path& file, const Trajectory& traj);

}  // namespace eds
