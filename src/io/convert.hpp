#pragma once
// Rewrites any sequence or recording eds reads in eds's own HDF5 layout (eds_hdf5.hpp).
#include <cstddef>
#include <filesystem>

#include "io/sequence.hpp"

namespace eds {

struct ConvertCounts {
  std::size_t events = 0, frames = 0, ground_truth = 0, imu = 0, triggers = 0;
  bool calibration = false;
};

// Streams the events (a chunk at a time) and frames (one at a time) of `seq` into `target`, then its
// calibration, ground truth, IMU samples and trigger edges. `target` appears only when complete.
ConvertCounts convertToEdsHdf5(const Sequence& seq, const std::filesystem::path& target, bool compress);

}  // namespace eds
