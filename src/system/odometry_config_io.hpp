#pragma once
// Every parameter of the odometry by a dotted name ("backend.window", "events.tracker.levels"), so
// that a YAML file can override any of them (`eds run --config FILE`) and each run can dump what it
// used (config_used.yaml), defaults included.
#include <filesystem>
#include <string>

#include "system/odometry.hpp"

namespace eds {

// Overrides the parameters the YAML file names; InputError naming the file and the key for an unknown
// key or a value of the wrong type.
void loadOdometryConfig(const std::filesystem::path& file, OdometryConfig& cfg);
void saveOdometryConfig(const std::filesystem::path& file, const OdometryConfig& cfg);
// Copies one parameter by its dotted name (std::invalid_argument if there is no such parameter).
void copyOdometryParameter(const OdometryConfig& from, OdometryConfig& to, const std::string& key);

}  // namespace eds
