#include "io/ros_bag.hpp"

#include <algorithm>
#include <cstring>
#include <unordered_map>

#include "io/ros_bag_formats.hpp"
#include "io/rosbag1.hpp"

namespace eds {

namespace {

// A ROS 1 bag seen as topics: connections that share a topic name become one topic.
class RosBag1Topics : public RosBagReader {
 public:
  explicit RosBag1Topics(const std::filesystem::path& file) : bag_(file) { indexTopics(); }
  const std::string& path() const override { return bag_.path(); }
  const char* format() const override { return "rosbag1"; }
  const std::vector<RosTopic>& topics() const override { return topics_; }
  void rewind() override { bag_.rewind(); }

  bool next(RosMessage& msg) override {
    BagMessage m;
    if (!bag_.next(m)) return false;
    if (bag_.connections().size() != known_connections_) indexTopics();  // defined inside a chunk
    msg.topic = topic_of_.at(m.connection);
    msg.t_record = m.t_record;
    msg.index = m.index;
    msg.data = messageView(m.data.data(), m.data.size(), where_, bag_.path(), m.index);
    return true;
  }

 private:
  void indexTopics() {
    for (const BagConnection& c : bag_.connections()) {
      if (topic_of_.count(c.id)) continue;
      std::size_t k = 0;
      while (k < topics_.size() && topics_[k].name != c.topic) ++k;
      if (k == topics_.size()) topics_.push_back({c.topic, c.type, RosSerialization::kRos1, 0});
      if (topics_[k].type != c.type)
        throw InputError(bag_.path(), "topic " + c.topic + " carries two message types (" + topics_[k].type +
                                          ", " + c.type + ")");
      topics_[k].messages += c.messages;
      topic_of_[c.id] = k;
    }
    known_connections_ = bag_.connections().size();
  }

  RosBag1Reader bag_;
  std::string where_;
  std::vector<RosTopic> topics_;
  std::unordered_map<std::uint32_t, std::size_t> topic_of_;
  std::size_t known_connections_ = 0;
};

// The storage file of a rosbag2 folder: the first .db3 or .mcap file in it (sorted by name).
std::filesystem::path storageFileOf(const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> files;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    if (e.path().extension() == ".db3" || e.path().extension() == ".mcap") files.push_back(e.path());
  if (files.empty()) return {};
  std::sort(files.begin(), files.end());
  return files.front();
}

}  // namespace

std::optional<std::size_t> chooseTopic(const RosBagReader& bag, const std::vector<std::string>& types,
                                       const std::string& wanted, const std::string& kind,
                                       const char* option) {
  const auto& topics = bag.topics();
  std::vector<std::size_t> found;
  std::string list;
  for (std::size_t i = 0; i < topics.size(); ++i)
    if (std::find(types.begin(), types.end(), topics[i].type) != types.end()) {
      found.push_back(i);
      list += (list.empty() ? "" : ", ") + topics[i].name + " (" + topics[i].type + ")";
    }
  if (!wanted.empty()) {
    for (std::size_t i = 0; i < topics.size(); ++i) {
      if (topics[i].name != wanted) continue;
      if (std::find(found.begin(), found.end(), i) == found.end())
        throw InputError(bag.path(), "topic " + wanted + " has type " + topics[i].type + ", not " + kind);
      return i;
    }
    throw InputError(bag.path(), "no topic " + wanted + " (" + kind +
                                     " topics: " + (list.empty() ? std::string("none") : list) + ")");
  }
  if (found.size() > 1)
    throw InputError(bag.path(),
                     "several " + kind + " topics: " + list + "; choose one with " + std::string(option));
  if (found.empty()) return std::nullopt;
  return found[0];
}

std::string normalizeRosType(const std::string& type) {
  const std::size_t p = type.find("/msg/");
  return p == std::string::npos ? type : type.substr(0, p) + "/" + type.substr(p + 5);
}

RosContainer detectRosContainer(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) {
    const auto file = storageFileOf(path);
    return file.empty() ? RosContainer::kNone : detectRosContainer(file);
  }
  switch (sniffFileFormat(path)) {
    case FileFormat::kRosBag1: return RosContainer::kRosBag1;
    case FileFormat::kSqlite: return RosContainer::kSqlite;
    case FileFormat::kMcap: return RosContainer::kMcap;
    default: return RosContainer::kNone;
  }
}

std::unique_ptr<RosBagReader> openRosBag(const std::filesystem::path& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(path.string(), "file not found");
  const std::filesystem::path file = std::filesystem::is_directory(path, ec) ? storageFileOf(path) : path;
  if (file.empty()) throw InputError(path.string(), "folder holds no rosbag2 storage file (.db3 or .mcap)");
  switch (detectRosContainer(file)) {
    case RosContainer::kRosBag1: return std::make_unique<RosBag1Topics>(file);
    case RosContainer::kSqlite: return openSqliteBag(file);
    case RosContainer::kMcap: return openMcap(file);
    case RosContainer::kNone: break;
  }
  throw InputError(file.string(), "not a ROS bag (neither ROS 1 bag v2.0, rosbag2 SQLite3 nor MCAP)");
}

}  // namespace eds
