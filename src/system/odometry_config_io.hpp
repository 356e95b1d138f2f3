#pragma once
// Every parameter of the odometry by a dotted name ("backend.window", "events.tracker.levels"), so
// that a YAML file can override any of them (`eds run --config FILE`) and each run can dump what it
// used (config_used.yaml), defaults included.
#include <filesystem>
#include <string>
#include <vector>

#include "system/odometry.hpp"

namespace eds {

// The defaults for a sensor of this size (DESIGN.md §2, the authors' configurations): 240×180 and
// smaller keep OdometryConfig's; from 640×480 up (EDS dataset), event frames of 80k events with 60 %
// overlap, 7 % of the pixels as event points, one more pyramid level for the frame alignment, and
// twice the back-end points per keyframe. Sizes in between scale the event count with the pixels.
// `eds run` starts from these, then applies --config, then the command line.
OdometryConfig defaultOdometryConfig(int width, int height);

// Overrides the parameters the YAML file names; InputError naming the file and the key for an unknown
// key or a value of the wrong type.
void loadOdometryConfig(const std::filesystem::path& file, OdometryConfig& cfg);
void saveOdometryConfig(const std::filesystem::path& file, const OdometryConfig& cfg);
// Copies one parameter by its dotted name (std::invalid_argument if there is no such parameter).
void copyOdometryParameter(const OdometryConfig& from, OdometryConfig& to, const std::string& key);
// Sets one parameter from "KEY=VALUE" (a YAML value: 9, 0.5, true, dso); std::invalid_argument naming
// the key for an unknown key or a bad value.
void setOdometryParameter(OdometryConfig& cfg, const std::string& assignment);
// Every parameter's dotted name, sorted.
std::vector<std::string> odometryParameterNames();

// Values no run can work with (negative waits, a recovery that could never find a pose...) and an
// unknown sensor size: std::invalid_argument saying which.
void validateOdometryConfig(const OdometryConfig& cfg, const CameraModel& camera);

}  // namespace eds
