#pragma once
// Point clouds as binary little-endian PLY (x y z as float, intensity as float), which MeshLab,
// CloudCompare and Open3D read. The reader accepts what the writer writes, for tests and tools.
#include <filesystem>
#include <vector>

#include "core/se3.hpp"

namespace eds {

struct PointCloud {
  std::vector<Eigen::Vector3f> xyz;  // world frame
  std::vector<float> intensity;      // same length as xyz
};

void writePly(const std::filesystem::path& file, const PointCloud& cloud);
// Reads a binary little-endian PLY with float x, y, z and optional float intensity; InputError on
// anything else.
PointCloud readPly(const std::filesystem::path& file);

}  // namespace eds
