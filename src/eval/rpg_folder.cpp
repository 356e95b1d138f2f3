#include "eval/rpg_folder.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "core/error.hpp"
#include "io/text_parse.hpp"

namespace eds::eval {
namespace {

YAML::Node loadYaml(const std::filesystem::path& file) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(file, ec)) throw InputError(file.string(), "cannot read file");
  try {
    const YAML::Node root = YAML::LoadFile(file.string());
    // An empty file loads as null: treat it as "no keys", like the toolbox's yaml.load would.
    if (!root.IsNull() && !root.IsMap()) throw InputError(file.string(), "expected a yaml mapping");
    return root;
  } catch (const YAML::Exception& e) {
    throw InputError(file.string(), "invalid yaml: " + std::string(e.what()));
  }
}

// Seconds to nanoseconds from the scalar's text, exactly: a double cannot hold 1.5e9 s to 1 ns.
TimeNs secondsScalar(const YAML::Node& node, const std::filesystem::path& file, const char* key) {
  const std::string text = node.Scalar();
  const char* begin = text.data();
  const char* end = begin + text.size();
  TimeNs t = 0;
  const char* p = text::parseSecondsNs(begin, end, t);
  if (p == end && p != begin) return t;
  try {
    std::size_t used = 0;
    const double s = std::stod(text, &used);
    if (used == text.size() && std::isfinite(s)) return fromSeconds(s);
  } catch (const std::exception&) {
  }
  throw InputError(file.string(), std::string(key) + ": expected seconds, got '" + text + "'");
}

}  // namespace

void applyEvalCfgYaml(const std::filesystem::path& file, EvalConfig& cfg) {
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) return;
  const YAML::Node root = loadYaml(file);
  if (root.IsNull()) return;
  try {
    if (const YAML::Node t = root["align_type"]) cfg.alignment = parseAlignment(t.as<std::string>());
    if (const YAML::Node k = root["align_num_frames"]) {
      const int frames = k.as<int>();
      if (frames == 0 || frames < -1)
        throw InputError(file.string(),
                         "align_num_frames must be -1 (all) or positive, got " + std::to_string(frames));
      cfg.align_frames = frames;
    }
  } catch (const YAML::Exception& e) {
    throw InputError(file.string(), "invalid value: " + std::string(e.what()));
  } catch (const std::invalid_argument& e) {
    throw InputError(file.string(), e.what());
  }
}

TimeWindow readTimeWindowYaml(const std::filesystem::path& file) {
  const YAML::Node root = loadYaml(file);
  TimeWindow w{std::numeric_limits<TimeNs>::min(), std::numeric_limits<TimeNs>::max()};
  if (root.IsNull()) return w;
  try {
    if (const YAML::Node s = root["start_time_sec"]) w.start = secondsScalar(s, file, "start_time_sec");
    if (const YAML::Node e = root["end_time_sec"]) w.end = secondsScalar(e, file, "end_time_sec");
  } catch (const YAML::Exception& e) {
    throw InputError(file.string(), "invalid value: " + std::string(e.what()));
  }
  if (w.start > w.end) throw InputError(file.string(), "start_time_sec is after end_time_sec");
  return w;
}

EvalConfig loadRpgConfig(const std::filesystem::path& dir) {
  EvalConfig cfg;
  applyEvalCfgYaml(dir / kRpgEvalCfgFile, cfg);
  std::error_code ec;
  if (std::filesystem::exists(dir / kRpgTimeWindowFile, ec))
    cfg.window = readTimeWindowYaml(dir / kRpgTimeWindowFile);
  return cfg;
}

AteResult evaluateRpgFolder(const std::filesystem::path& dir) {
  return evaluateAteFiles(dir / kRpgGroundTruthFile, dir / kRpgEstimateFile, loadRpgConfig(dir));
}

}  // namespace eds::eval
