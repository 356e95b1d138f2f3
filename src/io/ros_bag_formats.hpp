#pragma once
// The containers behind openRosBag, one file each.
#include <filesystem>
#include <memory>
#include <unordered_map>

#include "io/decompress.hpp"
#include "io/ros_bag.hpp"

namespace eds {

std::unique_ptr<RosBagReader> openRosBag1(const std::filesystem::path& file);
std::unique_ptr<RosBagReader> openSqliteBag(const std::filesystem::path& file);
std::unique_ptr<RosBagReader> openMcap(const std::filesystem::path& file);

}  // namespace eds
