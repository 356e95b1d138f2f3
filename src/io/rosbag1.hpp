#pragma once
// ROS 1 bag files (format 2.0), read without ROS: records of `header_len header data_len data`, messages
// grouped in chunks that are stored plain, bz2- or lz4-compressed. Messages come in file order (the
// order they were recorded), one decompressed chunk in memory at a time.
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/time.hpp"
#include "io/binary_file.hpp"

namespace eds {

struct BagConnection {
  std::uint32_t id = 0;
  std::string topic, type, md5sum, message_definition;
  std::uint64_t messages = 0;  // from the bag's index; 0 when the bag has none
};

struct BagMessage {
  std::uint32_t connection = 0;
  TimeNs t_record = 0;        // when the recorder received it
  std::uint64_t index = 0;    // 0-based position among all messages of the bag
  std::uint64_t file_offset;  // the chunk (or record) it was read from, for error messages
  ByteView data{nullptr, 0, nullptr, 0};
};

class RosBag1Reader {
 public:
  // Reads the bag header and the index at its end (connections, message counts). InputError naming
  // the file and byte offset on anything malformed.
  explicit RosBag1Reader(const std::filesystem::path& file);
  ~RosBag1Reader();

  const std::string& path() const;
  const std::vector<BagConnection>& connections() const;
  const BagConnection& connection(std::uint32_t id) const;
  // The next message in file order (on any connection); false at the end. `msg.data` stays valid until
  // the next call.
  bool next(BagMessage& msg);
  // Back to the first message.
  void rewind();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace eds
