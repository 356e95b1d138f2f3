#pragma once
// AEDAT 4.0 files (iniVation DV): a "#!AER-DAT4.0\r\n" line, a FlatBuffers IOHeader (compression, the
// position of the data table, an XML description of the streams), then packets `int32 stream, int32
// size, bytes` (each a size-prefixed FlatBuffer, LZ4- or Zstd-compressed as the header says), then
// the data table. Packets are read one at a time; frames are found by a scan and decoded on demand.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "core/events.hpp"
#include "io/binary_file.hpp"
#include "io/event_source.hpp"

namespace eds {

struct Aedat4Stream {
  int id = -1;
  std::string type;  // the FlatBuffers identifier: EVTS, FRME, IMUS, TRIG
  int width = 0, height = 0;
};

struct Aedat4Packet {
  int stream = -1;
  std::string type;
  std::uint64_t offset = 0;               // of the packet header in the file
  ByteView root{nullptr, 0, nullptr, 0};  // the FlatBuffer (after its size prefix), valid until next()
};

struct Aedat4Frame {
  TimeNs t = 0;
  std::uint64_t packet_offset = 0;
  TimeNs exposure = 0;  // end minus start of the exposure as the camera recorded them; 0: not recorded
};

class Aedat4Reader {
 public:
  // Reads the magic line and the IOHeader; InputError naming the file and byte offset when malformed.
  explicit Aedat4Reader(const std::filesystem::path& file);
  ~Aedat4Reader();
  // The streams the header's XML describes, in its order.
  const std::vector<Aedat4Stream>& streams() const;
  const std::string& path() const;
  // The next packet in file order, decompressed; false at the end of the packets.
  bool next(Aedat4Packet& packet);
  // Back to a packet found by an earlier scan (a frame's `packet_offset`), or to the first one.
  void seekPacket(std::uint64_t offset);
  void rewind();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Counts of a whole file, in one pass over its packets.
struct Aedat4Counts {
  std::uint64_t events = 0, events_on = 0, triggers = 0;
  int width = 0, height = 0;           // of the event stream, as the header gives it
  std::vector<ImuSample> imu_samples;  // DV's g and deg/s converted to m/s^2 and rad/s
  std::vector<Aedat4Frame> frames;
};
Aedat4Counts scanAedat4(const std::filesystem::path& file);

// The 8-bit gray image of the frame packet at `packet_offset` (colour frames are converted).
cv::Mat readAedat4Frame(const std::filesystem::path& file, std::uint64_t packet_offset);

class Aedat4EventSource : public BlockEventSource {
 public:
  explicit Aedat4EventSource(const std::filesystem::path& file);
  ~Aedat4EventSource() override;
  int width() const;
  int height() const;
  // DV's trigger types as channels (1 external rising, 2 falling, 3 pulse, 6-9 APS frame and exposure
  // start/end...); rising: an edge up, a pulse, a start.
  const std::vector<TriggerEvent>& triggers() const override { return triggers_; }

 private:
  bool decodeNextBlock(EventArray& block) override;
  std::unique_ptr<Aedat4Reader> reader_;
  int width_ = 0, height_ = 0;
  TimeNs last_t_ = 0;
  std::vector<TriggerEvent> triggers_;
};

}  // namespace eds
