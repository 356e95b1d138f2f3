#pragma once
// Recorded ROS topics, whatever the container: a ROS 1 bag (v2.0), a rosbag2 SQLite3 `.db3` file, an
// MCAP file, or a rosbag2 folder (metadata.yaml beside its storage files). The container is told by
// the file's first bytes, not its name.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/time.hpp"
#include "io/binary_file.hpp"
#include "io/ros_message.hpp"

namespace eds {

struct RosTopic {
  std::string name;
  std::string type;  // as ROS 1 writes it: "dvs_msgs/EventArray" (ROS 2's "/msg/" is dropped)
  RosSerialization serialization = RosSerialization::kRos1;
  std::uint64_t messages = 0;  // from the container's index or statistics (0 when it has none)
};

struct RosMessage {
  std::size_t topic = 0;                  // index into topics()
  TimeNs t_record = 0;                    // when the recorder received it
  std::uint64_t index = 0;                // 0-based position among all messages read
  ByteView data{nullptr, 0, nullptr, 0};  // valid until the next call to next()
};

class RosBagReader {
 public:
  virtual ~RosBagReader() = default;
  virtual const std::string& path() const = 0;
  virtual const char* format() const = 0;  // "rosbag1", "rosbag2-sqlite3", "mcap"
  virtual const std::vector<RosTopic>& topics() const = 0;
  // The next message in storage order (the order they were recorded); false at the end.
  virtual bool next(RosMessage& msg) = 0;
  virtual void rewind() = 0;
};

// A message's bytes, named "FILE, message N" (in `where`, which must outlive the view) so that an
// error while decoding it points at the message.
inline ByteView messageView(const std::uint8_t* data, std::size_t size, std::string& where,
                            const std::string& path, std::uint64_t index) {
  where = path + ", message " + std::to_string(index);
  return ByteView(data, size, &where, 0);
}

enum class RosContainer { kNone, kRosBag1, kSqlite, kMcap };
// What a file is, by its first bytes; a folder is looked into for its storage file.
RosContainer detectRosContainer(const std::filesystem::path& path);
// Opens any of the containers; InputError naming the path if it is none of them.
std::unique_ptr<RosBagReader> openRosBag(const std::filesystem::path& path);

// The topic whose type is one of `types`: `wanted` if given, else the only one; nullopt when the bag has
// none. `kind` names the types in messages ("event"), `option` is the flag that chooses among several.
std::optional<std::size_t> chooseTopic(const RosBagReader& bag, const std::vector<std::string>& types,
                                       const std::string& wanted, const std::string& kind,
                                       const char* option);

// Normalizes a ROS 2 type name ("pkg/msg/Type") to the ROS 1 form ("pkg/Type").
std::string normalizeRosType(const std::string& type);

}  // namespace eds
