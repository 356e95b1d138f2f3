#include "system/odometry_config_io.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <functional>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "core/error.hpp"
#include "core/reflect.hpp"
#include "io/output_file.hpp"

namespace eds {

namespace {

// One parameter, type-erased: read from and written to YAML.
struct Field {
  std::function<void(const YAML::Node&)> read;  // throws YAML::Exception or std::invalid_argument
  std::function<YAML::Node()> write;
};

// Collects every field of a configuration under its dotted name, through the structs' visitFields.
class Collect {
 public:
  Collect(std::map<std::string, Field>& out, std::string prefix) : out_(out), prefix_(std::move(prefix)) {}

  template <class T>
  void operator()(const char* name, T& field) {
    const std::string key = prefix_.empty() ? name : prefix_ + "." + name;
    if constexpr (requires(Collect & c) { visitFields(c, field); }) {
      Collect nested(out_, key);
      visitFields(nested, field);
    } else if constexpr (NamedEnum<T>) {
      out_[key] = {[&field, key](const YAML::Node& n) { field = enumValue<T>(n.as<std::string>(), key); },
                   [&field] { return YAML::Node(std::string(enumName(field))); }};
    } else {
      out_[key] = {[&field](const YAML::Node& n) { field = n.as<T>(); }, [&field] { return node(field); }};
    }
  }

 private:
  template <class E>
  static E enumValue(const std::string& text, const std::string& key) {
    std::string names;
    for (const auto& [v, name] : enumNames(E{})) {
      if (name == text) return v;
      names += (names.empty() ? "" : " | ") + std::string(name);
    }
    throw std::invalid_argument("'" + key + "' must be one of " + names + ", not '" + text + "'");
  }
  template <class T>
  static YAML::Node node(const T& v) {
    if constexpr (std::is_floating_point_v<T>) {
      // The shortest text that reads back as the same double (0.2, not 0.20000000000000001).
      char buf[32];
      const auto r = std::to_chars(buf, buf + sizeof buf, v);
      return YAML::Node(std::string(buf, r.ptr));
    } else {
      return YAML::Node(v);
    }
  }
  std::map<std::string, Field>& out_;
  std::string prefix_;
};

// The one list of parameters: the reader, the writer and the overrides all walk it.
std::map<std::string, Field> fields(OdometryConfig& c) {
  std::map<std::string, Field> f;
  Collect collect(f, "");
  visitFields(collect, c);
  return f;
}

// Leaves of a YAML map as dotted names.
void flatten(const YAML::Node& n, const std::string& prefix, std::map<std::string, YAML::Node>& out) {
  if (n.IsMap()) {
    for (const auto& kv : n)
      flatten(kv.second,
              prefix.empty() ? kv.first.as<std::string>() : prefix + "." + kv.first.as<std::string>(), out);
  } else {
    out[prefix] = n;
  }
}

}  // namespace

void loadOdometryConfig(const std::filesystem::path& file, OdometryConfig& cfg) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(file.string());
  } catch (const YAML::BadFile&) {
    throw InputError(file.string(), "cannot read the configuration file");
  } catch (const YAML::Exception& e) {
    throw InputError(file.string(), "line " + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  if (root.IsNull()) return;
  if (!root.IsMap()) throw InputError(file.string(), "expected a map of parameters");
  std::map<std::string, YAML::Node> leaves;
  try {
    flatten(root, "", leaves);
  } catch (const YAML::Exception& e) {  // a key that is not a name (a list, a map)
    throw InputError(file.string(), "line " + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  auto f = fields(cfg);
  for (const auto& [key, node] : leaves) {
    const auto it = f.find(key);
    const std::string where = "line " + std::to_string(node.Mark().line + 1) + ": ";
    if (it == f.end()) throw InputError(file.string(), where + "unknown parameter '" + key + "'");
    try {
      it->second.read(node);
    } catch (const YAML::Exception&) {
      throw InputError(file.string(), where + "bad value for '" + key + "'");
    } catch (const std::invalid_argument& e) {
      throw InputError(file.string(), where + e.what());
    }
  }
}

void saveOdometryConfig(const std::filesystem::path& file, const OdometryConfig& cfg) {
  OdometryConfig copy = cfg;
  YAML::Node root(YAML::NodeType::Map);
  for (const auto& [key, field] : fields(copy)) {
    std::vector<std::string> parts;
    std::stringstream ss(key);
    for (std::string part; std::getline(ss, part, '.');) parts.push_back(part);
    // Down the dotted path, creating maps on the way (yaml-cpp nodes are handles into the tree).
    YAML::Node node = root;
    for (std::size_t i = 0; i + 1 < parts.size(); ++i) {
      if (!node[parts[i]]) node[parts[i]] = YAML::Node(YAML::NodeType::Map);
      node.reset(node[parts[i]]);
    }
    node[parts.back()] = field.write();
  }
  std::ostringstream out;
  out << "# eds run: every parameter of this run (load with --config)\n" << root << "\n";
  writeTextFile(file, out.str());
}

void copyOdometryParameter(const OdometryConfig& from, OdometryConfig& to, const std::string& key) {
  OdometryConfig src = from;
  const auto f_from = fields(src);
  auto f_to = fields(to);
  const auto a = f_from.find(key);
  const auto b = f_to.find(key);
  if (a == f_from.end() || b == f_to.end()) throw std::invalid_argument("unknown parameter '" + key + "'");
  b->second.read(a->second.write());
}

void setOdometryParameter(OdometryConfig& cfg, const std::string& assignment) {
  const std::size_t eq = assignment.find('=');
  if (eq == std::string::npos || eq == 0)
    throw std::invalid_argument("expected KEY=VALUE (for example backend.window=9), not '" + assignment +
                                "'");
  const std::string key = assignment.substr(0, eq), value = assignment.substr(eq + 1);
  auto f = fields(cfg);
  const auto it = f.find(key);
  if (it == f.end())
    throw std::invalid_argument("unknown parameter '" + key + "' (config_used.yaml lists them)");
  try {
    it->second.read(YAML::Load(value));
  } catch (const YAML::Exception&) {
    throw std::invalid_argument("bad value '" + value + "' for '" + key + "'");
  }
}

std::vector<std::string> odometryParameterNames() {
  OdometryConfig c;
  std::vector<std::string> names;
  for (const auto& kv : fields(c)) names.push_back(kv.first);
  return names;
}

OdometryConfig defaultOdometryConfig(int width, int height) {
  OdometryConfig c;
  if (width <= 0 || height <= 0)
    throw std::invalid_argument("defaultOdometryConfig: sensor size must be positive");
  constexpr double kSmall = 240.0 * 180.0, kLarge = 640.0 * 480.0;
  const double px = static_cast<double>(width) * height;
  if (px <= kSmall) return c;
  // 0 at 240x180, 1 from 640x480 on.
  const double f = std::min(1.0, (px - kSmall) / (kLarge - kSmall));
  c.event_frame.num_events = static_cast<int>(std::lround(20000 + f * (80000 - 20000)));
  c.event_frame.overlap = 0.5 + f * 0.1;
  c.events.points.fraction = 0.12 + f * (0.07 - 0.12);
  if (f >= 0.5) c.frame_tracker.levels += 1, c.bootstrap.tracker.levels += 1;
  // Corner tracks are as many pixels off on a larger sensor, where the scene's texture is spread over
  // more of them: 1 / 2 px kept 123 essential-matrix inliers at 640x480, 2 / 4 px 400.
  c.bootstrap.geometric_init.ransac_px *= 1 + f;
  c.bootstrap.geometric_init.max_reproj_px *= 1 + f;
  // Five views in the bundle adjustment that completes the initialization (docs/experiments.md).
  if (f >= 1) c.bootstrap.final_views = 5;
  // The back-end keeps 300 points per keyframe at every size: twice that at 640x480 was no more accurate
  // and 11-19 % slower (docs/experiments.md).
  // From 640x480 on, event rates of 10 M/s and more would make 400 event frames a second and more:
  // at most 100 keep the work and the memory bounded for a small loss (docs/experiments.md).
  if (f >= 1) c.event_frame.max_rate_hz = 100;
  // At these rates the reversal compensation's per-event pass is half of the event-frame building and,
  // on three 640x480 scenes, bought no accuracy (docs/experiments.md).
  if (f >= 1) c.event_frame.reversal_compensation = false;
  return c;
}

}  // namespace eds
