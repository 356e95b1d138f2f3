// MCAP files (the rosbag2 default since ROS 2 Iron): `opcode u8, length u64, content` records after an
// 8-byte magic; messages sit in chunks stored plain, lz4- or zstd-compressed. Channels and message
// counts come from the summary section when the file has one, else as the records are read.
#include <cstring>

#include "io/ros_bag_formats.hpp"

namespace eds {

namespace {

constexpr std::uint8_t kMagic[8] = {0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'};
constexpr std::uint64_t kMaxRecordBytes = 1ull << 31;

enum Op : std::uint8_t {
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kStatistics = 0x0B,
  kDataEnd = 0x0F
};

std::string mcapString(ByteView& v, const char* what) {
  const auto len = v.le<std::uint32_t>(what);
  const ByteView s = v.take(len, what);
  return std::string(reinterpret_cast<const char*>(s.data()), s.size());
}

class McapBag : public RosBagReader {
 public:
  explicit McapBag(const std::filesystem::path& file) : file_(file) {
    std::uint8_t magic[8];
    file_.readExact(magic, 8, "MCAP magic");
    if (std::memcmp(magic, kMagic, 8) != 0) throw errorAt(file_.path(), 0, "not an MCAP file (bad magic)");
    if (!readSummary()) scanChannels();
    rewind();
  }

  const std::string& path() const override { return file_.path(); }
  const char* format() const override { return "mcap"; }
  const std::vector<RosTopic>& topics() const override { return topics_; }

  void rewind() override {
    file_.seek(8);
    in_chunk_ = false;
    index_ = 0;
    done_ = false;
  }

  bool next(RosMessage& msg) override {
    for (;;) {
      if (in_chunk_) {
        if (chunk_.remaining() > 0) {
          if (handle(readRecord(chunk_), msg)) return true;
          continue;
        }
        in_chunk_ = false;
      }
      if (done_ || file_.atEnd()) return false;
      ByteView v = readFileRecord();
      if (op_ == kDataEnd || op_ == kFooter) {
        done_ = true;
        return false;
      }
      if (op_ == kChunk) {
        openChunk(v);
      } else if (handle(v, msg)) {
        return true;
      }
    }
  }

 private:
  // Reads the record at the file position into record_; returns its content.
  ByteView readFileRecord() {
    const std::uint64_t at = file_.offset();
    op_ = file_.readLe<std::uint8_t>("record opcode");
    const auto len = file_.readLe<std::uint64_t>("record length");
    if (len > kMaxRecordBytes || len > file_.size() - file_.offset())
      throw errorAt(file_.path(), at,
                    "record length " + std::to_string(len) + " runs past the end of the file");
    file_.readExact(record_, static_cast<std::size_t>(len), "record");
    return ByteView(record_.data(), record_.size(), &file_.path(), at + 9);
  }
  // A record inside a chunk (or the summary): its content.
  ByteView readRecord(ByteView& v) {
    op_ = v.le<std::uint8_t>("record opcode");
    const auto len = v.le<std::uint64_t>("record length");
    return v.take(static_cast<std::size_t>(std::min<std::uint64_t>(len, kMaxRecordBytes)), "record");
  }

  void openChunk(ByteView v) {
    v.skip(16);  // message start and end times
    const auto size = v.le<std::uint64_t>("chunk uncompressed size");
    v.skip(4);  // crc
    const std::string compression = mcapString(v, "chunk compression");
    const auto len = v.le<std::uint64_t>("chunk records length");
    const ByteView data =
        v.take(static_cast<std::size_t>(std::min<std::uint64_t>(len, kMaxRecordBytes)), "chunk records");
    const std::uint64_t at = data.absolute(0);
    if (size > kMaxRecordBytes) throw errorAt(file_.path(), at, "chunk size too large");
    if (compression.empty()) {
      chunk_data_.assign(data.data(), data.data() + data.size());
    } else {
      chunk_data_.resize(static_cast<std::size_t>(size));
      if (compression == "lz4")
        lz4FrameDecompress(data.data(), data.size(), chunk_data_, file_.path(), at);
      else if (compression == "zstd")
        zstdDecompress(data.data(), data.size(), chunk_data_, file_.path(), at);
      else
        throw errorAt(file_.path(), at, "unknown chunk compression '" + compression + "'");
    }
    chunk_where_ = file_.path() + " (chunk at byte " + std::to_string(at) + ", uncompressed)";
    chunk_ = ByteView(chunk_data_.data(), chunk_data_.size(), &chunk_where_, 0);
    in_chunk_ = true;
  }

  // Schemas and channels are remembered; a message is returned (true).
  bool handle(ByteView v, RosMessage& msg) {
    if (op_ == kSchema) {
      const auto id = v.le<std::uint16_t>("schema id");
      schemas_[id] = mcapString(v, "schema name");
    } else if (op_ == kChannel) {
      addChannel(v);
    } else if (op_ == kMessage) {
      const auto channel = v.le<std::uint16_t>("message channel");
      v.skip(4);  // sequence
      msg.t_record = static_cast<TimeNs>(v.le<std::uint64_t>("message log time"));
      v.skip(8);  // publish time
      const auto it = channel_topic_.find(channel);
      if (it == channel_topic_.end())
        throw v.error(0,
                      "message on channel " + std::to_string(channel) + ", which is not defined before it");
      msg.topic = it->second;
      msg.index = index_++;
      const ByteView data = v.take(v.remaining(), "message data");
      msg.data = messageView(data.data(), data.size(), where_, file_.path(), msg.index);
      return true;
    }
    return false;
  }

  void addChannel(ByteView v) {
    const auto id = v.le<std::uint16_t>("channel id");
    const auto schema = v.le<std::uint16_t>("channel schema id");
    RosTopic t;
    t.name = mcapString(v, "channel topic");
    const std::string encoding = mcapString(v, "channel message encoding");
    if (channel_topic_.count(id)) return;
    if (encoding == "cdr")
      t.serialization = RosSerialization::kCdr;
    else if (encoding == "ros1")
      t.serialization = RosSerialization::kRos1;
    else
      throw v.error(0,
                    "channel " + t.name + " has message encoding '" + encoding + "' (cdr and ros1 are read)");
    const auto s = schemas_.find(schema);
    t.type = s == schemas_.end() ? std::string() : normalizeRosType(s->second);
    t.messages = channel_counts_.count(id) ? channel_counts_[id] : 0;
    channel_topic_[id] = topics_.size();
    topics_.push_back(std::move(t));
  }

  // A file without a summary (a recorder that stopped early): its channels and counts come from one
  // pass over the records.
  void scanChannels() {
    rewind();
    RosMessage m;
    std::vector<std::uint64_t> counts;
    while (next(m)) {
      counts.resize(std::max(counts.size(), m.topic + 1));
      ++counts[m.topic];
    }
    for (std::size_t i = 0; i < counts.size(); ++i) topics_[i].messages = counts[i];
  }

  // The footer points at the summary: schemas, channels and statistics. False when there is none.
  bool readSummary() {
    if (file_.size() < 8 + 9 + 20 + 8) return false;
    file_.seek(file_.size() - 8 - 20);
    const auto summary_start = file_.readLe<std::uint64_t>("footer summary start");
    if (summary_start == 0 || summary_start >= file_.size()) return false;
    file_.seek(summary_start);
    std::vector<std::uint8_t> summary;
    file_.readExact(summary, static_cast<std::size_t>(file_.size() - 8 - 29 - summary_start),
                    "summary section");
    ByteView s(summary.data(), summary.size(), &file_.path(), summary_start);
    std::vector<std::pair<std::uint8_t, ByteView>> records;
    while (s.remaining() > 0) {
      const ByteView r = readRecord(s);
      records.emplace_back(op_, r);
    }
    for (auto& [op, r] : records)
      if (op == kStatistics) readStatistics(r);
    RosMessage unused;
    for (auto& [op, r] : records) {
      op_ = op;
      if (op == kSchema || op == kChannel) handle(r, unused);
    }
    return true;
  }

  void readStatistics(ByteView v) {
    v.skip(8 + 2 + 4 + 4 + 4 + 4 + 8 + 8);
    ByteView counts = v.take(v.le<std::uint32_t>("channel message counts"), "channel message counts");
    while (counts.remaining() > 0) {
      const auto id = counts.le<std::uint16_t>("channel id");
      channel_counts_[id] = counts.le<std::uint64_t>("message count");
    }
  }

  BinaryFile file_;
  std::vector<RosTopic> topics_;
  std::unordered_map<std::uint16_t, std::string> schemas_;
  std::unordered_map<std::uint16_t, std::size_t> channel_topic_;
  std::unordered_map<std::uint16_t, std::uint64_t> channel_counts_;
  std::vector<std::uint8_t> record_, chunk_data_;
  std::string chunk_where_, where_;
  ByteView chunk_{nullptr, 0, nullptr, 0};
  std::uint8_t op_ = 0;
  bool in_chunk_ = false, done_ = false;
  std::uint64_t index_ = 0;
};

}  // namespace

std::unique_ptr<RosBagReader> openMcap(const std::filesystem::path& file) {
  return std::make_unique<McapBag>(file);
}

}  // namespace eds
