#include "io/rosbag1.hpp"

#include <bzlib.h>

#include <algorithm>
#include <cstring>
#include <unordered_map>

#include "io/ros_bag_formats.hpp"

namespace eds {

namespace {

constexpr char kMagic[] = "#ROSBAG V2.0\n";
constexpr std::size_t kMagicSize = sizeof(kMagic) - 1;
constexpr std::uint32_t kMaxRecordBytes = 1u << 30;  // a larger header or message is a corrupt length

// The record opcodes ("op" header field) of bag format 2.0 run consecutively from 0x02.
enum Op : std::uint8_t { kMessage = 0x02, kBagHeader, kIndexData, kChunk, kChunkInfo, kConnection };

// The `name=value` fields of a record header.
struct RecordHeader {
  std::unordered_map<std::string, ByteView> fields;

  static RecordHeader parse(ByteView v) {
    RecordHeader h;
    while (v.remaining() > 0) {
      const auto len = v.le<std::uint32_t>("header field length");
      ByteView field = v.take(len, "header field");
      const auto* begin = reinterpret_cast<const char*>(field.data());
      const auto* eq = static_cast<const char*>(std::memchr(begin, '=', len));
      if (!eq) throw field.error(0, "header field without '='");
      const auto name_len = static_cast<std::size_t>(eq - begin);
      field.seek(name_len + 1);
      h.fields.emplace(std::string(begin, name_len), field.take(len - name_len - 1, "field value"));
    }
    return h;
  }
  ByteView get(const char* name, const ByteView& where) const {
    const auto it = fields.find(name);
    if (it == fields.end()) throw where.error(0, std::string("record header lacks the '") + name + "' field");
    return it->second;
  }
  template <typename T>
  T value(const char* name, const ByteView& where) const {
    ByteView v = get(name, where);
    if (v.size() != sizeof(T)) throw v.error(0, std::string("field '") + name + "' has the wrong size");
    return v.le<T>(name);
  }
  std::string text(const char* name, const ByteView& where) const {
    const ByteView v = get(name, where);
    return std::string(reinterpret_cast<const char*>(v.data()), v.size());
  }
};

TimeNs rosTime(std::uint64_t packed) {  // sec in the low 32 bits, nsec in the high
  return static_cast<TimeNs>(packed & 0xFFFFFFFFu) * kNsPerSec + static_cast<TimeNs>(packed >> 32);
}

void decompressBz2(std::vector<std::uint8_t>& in, std::vector<std::uint8_t>& out, const std::string& file,
                   std::uint64_t offset) {
  auto n = static_cast<unsigned>(out.size());
  const int rc =
      BZ2_bzBuffToBuffDecompress(reinterpret_cast<char*>(out.data()), &n, reinterpret_cast<char*>(in.data()),
                                 static_cast<unsigned>(in.size()), 0, 0);
  if (rc != BZ_OK) throw errorAt(file, offset, "corrupt bz2 chunk (bzip2 error " + std::to_string(rc) + ")");
  if (n != out.size())
    throw errorAt(file, offset,
                  "bz2 chunk decompresses to " + std::to_string(n) + " bytes, not the " +
                      std::to_string(out.size()) + " its header says");
}

}  // namespace

struct RosBag1Reader::Impl {
  BinaryFile file;
  std::vector<BagConnection> connections;
  std::unordered_map<std::uint32_t, std::size_t> by_id;
  std::uint64_t index_pos = 0, data_start = 0;
  // The record being read: its header and data.
  std::vector<std::uint8_t> header_bytes, data_bytes, chunk;
  std::uint64_t record_offset = 0;
  // Inside a chunk: the decompressed records and the position in them.
  bool in_chunk = false;
  std::size_t chunk_pos = 0;
  std::uint64_t chunk_offset = 0;
  std::uint64_t message_index = 0;

  explicit Impl(const std::filesystem::path& path) : file(path) {
    char magic[kMagicSize];
    file.readExact(magic, kMagicSize, "bag magic");
    if (std::memcmp(magic, kMagic, kMagicSize) != 0)
      throw errorAt(file.path(), 0, "not a ROS 1 bag (no '#ROSBAG V2.0' line)");
    ByteView header = readRecord();
    const RecordHeader h = RecordHeader::parse(header);
    if (h.value<std::uint8_t>("op", header) != kBagHeader)
      throw errorAt(file.path(), record_offset, "the first record is not a bag header");
    index_pos = h.value<std::uint64_t>("index_pos", header);
    data_start = file.offset();
    if (index_pos != 0)
      readIndex();
    else
      scanUnindexed();
    file.seek(data_start);
  }

  // Reads the record at the file position into header_bytes / data_bytes; returns the header's view.
  ByteView readRecord() {
    record_offset = file.offset();
    const auto header_len = file.readLe<std::uint32_t>("record header length");
    if (header_len > kMaxRecordBytes)
      throw errorAt(file.path(), record_offset, "record header length too large");
    file.readExact(header_bytes, header_len, "record header");
    const auto data_len = file.readLe<std::uint32_t>("record data length");
    if (data_len > kMaxRecordBytes) throw errorAt(file.path(), record_offset, "record data length too large");
    file.readExact(data_bytes, data_len, "record data");
    return ByteView(header_bytes.data(), header_bytes.size(), &file.path(), record_offset + 4);
  }

  // A bag whose recorder stopped before writing the index: its connections and counts come from one
  // pass over the chunks (as `rosbag reindex` would find them).
  void scanUnindexed() {
    std::unordered_map<std::uint32_t, std::uint64_t> counts;
    BagMessage m;
    while (next(m)) ++counts[m.connection];
    for (auto& c : connections) c.messages = counts[c.id];
    in_chunk = false;
    message_index = 0;
  }

  // Connections and chunk infos after index_pos: the topics, types and per-connection counts.
  void readIndex() {
    if (index_pos > file.size())
      throw errorAt(file.path(), 0,
                    "truncated: the bag's index should start at byte " + std::to_string(index_pos) +
                        ", past the end of the file");
    file.seek(index_pos);
    while (!file.atEnd()) {
      ByteView header = readRecord();
      const RecordHeader h = RecordHeader::parse(header);
      const auto op = h.value<std::uint8_t>("op", header);
      if (op == kConnection) {
        addConnection(h, header, dataView());
      } else if (op == kChunkInfo) {
        countChunkInfo();
      } else {
        throw errorAt(file.path(), record_offset,
                      "unexpected record (op " + std::to_string(op) + ") in the index");
      }
    }
  }

  ByteView dataView() const {
    return ByteView(data_bytes.data(), data_bytes.size(), &file.path(),
                    record_offset + 8 + header_bytes.size());
  }

  void addConnection(const RecordHeader& h, const ByteView& header, ByteView data) {
    const auto id = h.value<std::uint32_t>("conn", header);
    if (by_id.count(id)) return;
    const RecordHeader d = RecordHeader::parse(data);
    BagConnection c;
    c.id = id;
    c.topic = h.text("topic", header);
    c.type = d.text("type", data);
    c.md5sum = d.text("md5sum", data);
    if (d.fields.count("message_definition")) c.message_definition = d.text("message_definition", data);
    by_id[id] = connections.size();
    connections.push_back(std::move(c));
  }

  // A chunk info's data: (conn, count) pairs.
  void countChunkInfo() {
    ByteView data = dataView();
    while (data.remaining() > 0) {
      const auto conn = data.le<std::uint32_t>("chunk info connection");
      const auto count = data.le<std::uint32_t>("chunk info count");
      pending_counts[conn] += count;
    }
    for (auto& c : connections) c.messages = pending_counts[c.id];
  }
  std::unordered_map<std::uint32_t, std::uint64_t> pending_counts;

  void openChunk(const RecordHeader& h, const ByteView& header) {
    const std::string compression = h.text("compression", header);
    const auto size = h.value<std::uint32_t>("size", header);
    if (size > kMaxRecordBytes) throw errorAt(file.path(), record_offset, "chunk size too large");
    chunk.resize(size);
    if (compression == "none") {
      if (data_bytes.size() != size)
        throw errorAt(file.path(), record_offset,
                      "uncompressed chunk's data length differs from its size field");
      chunk.swap(data_bytes);
    } else if (compression == "lz4") {
      lz4FrameDecompress(data_bytes.data(), data_bytes.size(), chunk, file.path(), record_offset);
    } else if (compression == "bz2") {
      decompressBz2(data_bytes, chunk, file.path(), record_offset);
    } else {
      throw errorAt(file.path(), record_offset, "unknown chunk compression '" + compression + "'");
    }
    in_chunk = true;
    chunk_pos = 0;
    chunk_offset = record_offset;
  }

  bool nextInChunk(BagMessage& msg);
  bool next(BagMessage& msg);
};

bool RosBag1Reader::Impl::nextInChunk(BagMessage& msg) {
  // Chunk positions are relative to its uncompressed data; errors name the chunk's own offset.
  const std::string where =
      file.path() + " (chunk at byte " + std::to_string(chunk_offset) + ", uncompressed)";
  while (chunk_pos < chunk.size()) {
    ByteView v(chunk.data(), chunk.size(), &where, 0);
    v.seek(chunk_pos);
    const ByteView header = v.take(v.le<std::uint32_t>("record header length"), "record header");
    const ByteView data = v.take(v.le<std::uint32_t>("record data length"), "record data");
    chunk_pos = v.pos();
    const RecordHeader h = RecordHeader::parse(header);
    const auto op = h.value<std::uint8_t>("op", header);
    if (op == kConnection) {
      addConnection(h, header, data);
    } else if (op == kMessage) {
      const auto conn = h.value<std::uint32_t>("conn", header);
      if (!by_id.count(conn))
        throw header.error(0,
                           "message on connection " + std::to_string(conn) + ", which the bag never defines");
      msg.connection = conn;
      msg.t_record = rosTime(h.value<std::uint64_t>("time", header));
      msg.index = message_index++;
      msg.file_offset = chunk_offset;
      msg.data =
          ByteView(chunk.data() + (data.data() - chunk.data()), data.size(), &file.path(), chunk_offset);
      return true;
    } else {
      throw header.error(0, "unexpected record (op " + std::to_string(op) + ") inside a chunk");
    }
  }
  in_chunk = false;
  return false;
}

bool RosBag1Reader::Impl::next(BagMessage& msg) {
  for (;;) {
    if (in_chunk && nextInChunk(msg)) return true;
    const std::uint64_t end = index_pos != 0 ? index_pos : file.size();
    if (file.offset() >= end) return false;
    ByteView header = readRecord();
    const RecordHeader h = RecordHeader::parse(header);
    const auto op = h.value<std::uint8_t>("op", header);
    if (op == kChunk) {
      openChunk(h, header);
    } else if (op == kConnection) {
      addConnection(h, header, dataView());
    } else if (op == kMessage) {
      const auto conn = h.value<std::uint32_t>("conn", header);
      if (!by_id.count(conn)) throw errorAt(file.path(), record_offset, "message on an undefined connection");
      msg.connection = conn;
      msg.t_record = rosTime(h.value<std::uint64_t>("time", header));
      msg.index = message_index++;
      msg.file_offset = record_offset;
      msg.data = dataView();
      return true;
    } else if (op != kIndexData && op != kChunkInfo) {
      throw errorAt(file.path(), record_offset, "unknown record op code " + std::to_string(op));
    }
  }
}

RosBag1Reader::RosBag1Reader(const std::filesystem::path& file) : impl_(std::make_unique<Impl>(file)) {}
RosBag1Reader::~RosBag1Reader() = default;
const std::string& RosBag1Reader::path() const { return impl_->file.path(); }
const std::vector<BagConnection>& RosBag1Reader::connections() const { return impl_->connections; }
const BagConnection& RosBag1Reader::connection(std::uint32_t id) const {
  return impl_->connections.at(impl_->by_id.at(id));
}
bool RosBag1Reader::next(BagMessage& msg) { return impl_->next(msg); }
void RosBag1Reader::rewind() {
  impl_->file.seek(impl_->data_start);
  impl_->in_chunk = false;
  impl_->message_index = 0;
}

}  // namespace eds
