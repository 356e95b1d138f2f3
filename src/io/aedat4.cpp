#include "io/aedat4.hpp"

#include <algorithm>
#include <charconv>
#include <cstring>
#include <opencv2/imgproc.hpp>
#include <system_error>

#include "io/decompress.hpp"
#include "io/flatbuffer_view.hpp"
#include "io/prophesee.hpp"

namespace eds {

namespace {

constexpr char kMagic[] = "#!AER-DAT4.0\r\n";
constexpr std::size_t kMagicSize = sizeof(kMagic) - 1;
constexpr std::size_t kEventBytes = 16;   // struct Event { int64 t; int16 x, y; bool on; } padded
constexpr std::size_t kTriggerBytes = 4;  // triggers are tables: a vector of offsets

// The value of `<attr key="KEY" ...>VALUE</attr>` within text.
std::string xmlAttr(const std::string& text, const std::string& key) {
  const std::size_t k = text.find("key=\"" + key + "\"");
  if (k == std::string::npos) return {};
  const std::size_t open = text.find('>', k), close = text.find('<', k);
  return open == std::string::npos || close == std::string::npos || close < open
             ? std::string()
             : text.substr(open + 1, close - open - 1);
}

// A non-negative int written in decimal; -1 when the text is anything else (or too large).
int smallInt(const std::string& text) {
  int v = -1;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  return ec == std::errc() && end == text.data() + text.size() && v >= 0 ? v : -1;
}

// The output streams the XML names: <node name="N" path=".../outInfo/N/"> ... </node>.
std::vector<Aedat4Stream> parseStreams(const std::string& xml) {
  std::vector<Aedat4Stream> streams;
  for (std::size_t p = xml.find("<node name=\""); p != std::string::npos;
       p = xml.find("<node name=\"", p + 1)) {
    const std::size_t name_end = xml.find('"', p + 12);
    const std::string name = xml.substr(p + 12, name_end - p - 12);
    if (smallInt(name) < 0) continue;
    const std::size_t end = xml.find("</node>", p);
    const std::string body = xml.substr(p, end == std::string::npos ? std::string::npos : end - p);
    Aedat4Stream s;
    s.id = smallInt(name);
    s.type = xmlAttr(body, "typeIdentifier");
    // A size that is not a number leaves it unknown (0), as an absent one does.
    s.width = std::max(smallInt(xmlAttr(body, "sizeX")), 0);
    s.height = std::max(smallInt(xmlAttr(body, "sizeY")), 0);
    streams.push_back(s);
  }
  return streams;
}

// A packet's time in µs as ns; an error naming the packet when it is beyond int64 ns.
TimeNs packetTimeNs(std::int64_t us, const std::string& file, std::uint64_t packet_offset, const char* what) {
  if (!microsecondsFitNs(us))
    throw errorAt(file, packet_offset,
                  std::string(what) + " time " + std::to_string(us) + " us is beyond int64 ns");
  return us * kNsPerUs;
}

// DV's IMU samples are tables: timestamp (int64 µs), temperature, accelerometer xyz (g), gyroscope xyz
// (deg/s), magnetometer xyz (floats).
void appendImu(const FlatTable& packet, const std::string& file, std::uint64_t packet_offset,
               std::vector<ImuSample>& out) {
  constexpr double kG = 9.80665, kDegToRad = 3.14159265358979323846 / 180.0;
  for (const FlatTable& imu : packet.tables(0)) {
    ImuSample s;
    s.t = packetTimeNs(imu.scalar<std::int64_t>(0, 0), file, packet_offset, "IMU sample");
    for (int k = 0; k < 3; ++k) {
      s.acc[k] = imu.scalar<float>(2 + k, 0.0f) * kG;
      s.gyro[k] = imu.scalar<float>(5 + k, 0.0f) * kDegToRad;
    }
    out.push_back(s);
  }
}

// DV's Trigger tables: timestamp (int64 µs) 0, type (int8) 1.
void appendTriggers(const FlatTable& root, const std::string& path, std::uint64_t offset,
                    std::vector<TriggerEvent>& out) {
  for (const FlatTable& t : root.tables(0)) {
    const auto type = t.scalar<std::int8_t>(1, 0);
    const TimeNs ns = packetTimeNs(t.scalar<std::int64_t>(0, 0), path, offset, "trigger");
    if (!out.empty() && ns < out.back().t) throw errorAt(path, offset, "trigger times go back");
    const bool rising = type == 1 || type == 3 || type == 4 || type == 6 || type == 8;
    out.push_back({ns, static_cast<std::uint8_t>(type), rising});
  }
}

}  // namespace

struct Aedat4Reader::Impl {
  BinaryFile file;
  std::vector<Aedat4Stream> streams;
  std::string compression = "none";
  std::uint64_t data_start = 0, data_end = 0;
  std::vector<std::uint8_t> raw, packet;

  explicit Impl(const std::filesystem::path& path) : file(path) {
    char magic[kMagicSize];
    file.readExact(magic, kMagicSize, "AEDAT 4.0 magic");
    if (std::memcmp(magic, kMagic, kMagicSize) != 0)
      throw errorAt(file.path(), 0, "not an AEDAT 4.0 file (no '#!AER-DAT4.0' line)");
    const auto size = file.readLe<std::int32_t>("IOHeader size");
    if (size <= 0 || static_cast<std::uint64_t>(size) > file.size() - file.offset())
      throw errorAt(file.path(), kMagicSize,
                    "IOHeader size " + std::to_string(size) + " runs past the end of the file");
    std::vector<std::uint8_t> header;
    file.readExact(header, static_cast<std::size_t>(size), "IOHeader");
    const ByteView view(header.data(), header.size(), &file.path(), kMagicSize + 4);
    const FlatTable h = FlatTable::root(view);
    static const char* kCompressions[] = {"none", "lz4", "lz4", "zstd", "zstd"};
    const auto c = h.scalar<std::int32_t>(0, 0);
    if (c < 0 || c > 4)
      throw errorAt(file.path(), kMagicSize + 4, "unknown compression " + std::to_string(c));
    compression = kCompressions[c];
    const auto table = h.scalar<std::int64_t>(1, -1);
    data_start = file.offset();
    data_end = table > 0 && static_cast<std::uint64_t>(table) <= file.size()
                   ? static_cast<std::uint64_t>(table)
                   : file.size();
    streams = parseStreams(h.string(2));
    if (streams.empty()) throw errorAt(file.path(), kMagicSize + 4, "the header describes no streams");
  }

  const Aedat4Stream* stream(int id) const {
    for (const auto& s : streams)
      if (s.id == id) return &s;
    return nullptr;
  }

  bool next(Aedat4Packet& p) {
    if (file.offset() + 8 > data_end) return false;
    p.offset = file.offset();
    p.stream = file.readLe<std::int32_t>("packet stream id");
    const auto size = file.readLe<std::int32_t>("packet size");
    const Aedat4Stream* s = stream(p.stream);
    if (!s)
      throw errorAt(file.path(), p.offset,
                    "packet of stream " + std::to_string(p.stream) + ", which the header does not describe");
    if (size < 0 || static_cast<std::uint64_t>(size) > data_end - file.offset())
      throw errorAt(file.path(), p.offset,
                    "packet size " + std::to_string(size) + " runs past the end of the data");
    file.readExact(raw, static_cast<std::size_t>(size), "packet");
    const std::uint64_t at = p.offset + 8;
    if (compression == "lz4")
      lz4FrameDecompressAll(raw.data(), raw.size(), packet, file.path(), at);
    else if (compression == "zstd")
      zstdDecompressAll(raw.data(), raw.size(), packet, file.path(), at);
    else
      packet.swap(raw);
    // A size-prefixed FlatBuffer: uint32 size, then the root offset and the 4-character identifier.
    ByteView v(packet.data(), packet.size(), &file.path(), at);
    const auto fb_size = v.le<std::uint32_t>("packet flatbuffer size");
    if (fb_size != v.remaining())
      throw errorAt(file.path(), at, "packet flatbuffer size disagrees with the packet");
    p.root = v.take(fb_size, "packet flatbuffer");
    if (p.root.size() < 8) throw errorAt(file.path(), at, "packet too short for a flatbuffer");
    p.type.assign(reinterpret_cast<const char*>(p.root.data()) + 4, 4);
    if (p.type != s->type)
      throw errorAt(file.path(), p.offset,
                    "packet of type '" + p.type + "' on stream " + std::to_string(p.stream) +
                        ", which the header says carries " + s->type);
    return true;
  }
};

Aedat4Reader::Aedat4Reader(const std::filesystem::path& file) : impl_(std::make_unique<Impl>(file)) {}
Aedat4Reader::~Aedat4Reader() = default;
const std::string& Aedat4Reader::path() const { return impl_->file.path(); }
const std::vector<Aedat4Stream>& Aedat4Reader::streams() const { return impl_->streams; }
bool Aedat4Reader::next(Aedat4Packet& packet) { return impl_->next(packet); }
void Aedat4Reader::seekPacket(std::uint64_t offset) { impl_->file.seek(offset); }
void Aedat4Reader::rewind() { impl_->file.seek(impl_->data_start); }

namespace {

// The size the header gives the first event stream; stays 0 when there is none.
void eventSensorSize(const Aedat4Reader& reader, int& width, int& height) {
  for (const auto& s : reader.streams())
    if (s.type == "EVTS") {
      width = s.width;
      height = s.height;
      return;
    }
}

}  // namespace

Aedat4Counts scanAedat4(const std::filesystem::path& file) {
  Aedat4Reader reader(file);
  Aedat4Counts c;
  eventSensorSize(reader, c.width, c.height);
  Aedat4Packet p;
  std::size_t n = 0;
  while (reader.next(p)) {
    const FlatTable root = FlatTable::root(p.root);
    if (p.type == "EVTS") {
      const ByteView e = root.vector(0, kEventBytes, n);
      c.events += n;
      for (std::size_t i = 0; i < n; ++i) c.events_on += e.data()[i * kEventBytes + 12] != 0;
    } else if (p.type == "IMUS") {
      appendImu(root, reader.path(), p.offset, c.imu_samples);
    } else if (p.type == "TRIG") {
      root.vector(0, kTriggerBytes, n);
      c.triggers += n;
    } else if (p.type == "FRME") {
      // Fields 3 and 4: the exposure's start and end (us), written by DV next to the frame's time.
      const std::int64_t start = root.scalar<std::int64_t>(3, 0), stop = root.scalar<std::int64_t>(4, 0);
      c.frames.push_back({packetTimeNs(root.scalar<std::int64_t>(0, 0), reader.path(), p.offset, "frame"),
                          p.offset, start > 0 && stop > start ? (stop - start) * 1000 : 0});
    }
  }
  return c;
}

cv::Mat readAedat4Frame(const std::filesystem::path& file, std::uint64_t packet_offset) {
  Aedat4Reader reader(file);
  reader.seekPacket(packet_offset);
  Aedat4Packet p;
  if (!reader.next(p) || p.type != "FRME")
    throw errorAt(file.string(), packet_offset, "no frame packet here");
  const FlatTable f = FlatTable::root(p.root);
  const int w = f.scalar<std::int16_t>(6, 0), h = f.scalar<std::int16_t>(7, 0);
  const auto format = f.scalar<std::int8_t>(5, 0);  // 0: gray, 16: BGR, 24: BGRA
  const int channels = format == 0 ? 1 : format == 16 ? 3 : format == 24 ? 4 : 0;
  if (channels == 0)
    throw errorAt(file.string(), packet_offset, "frame of unknown pixel format " + std::to_string(format));
  std::size_t n = 0;
  const ByteView pixels = f.vector(10, 1, n);
  if (w <= 0 || h <= 0 || n != static_cast<std::size_t>(w) * h * channels)
    throw errorAt(file.string(), packet_offset,
                  "frame of " + std::to_string(n) + " bytes is not " + std::to_string(w) + "x" +
                      std::to_string(h) + "x" + std::to_string(channels));
  const cv::Mat view(h, w, CV_8UC(channels), const_cast<std::uint8_t*>(pixels.data()));
  cv::Mat gray;
  if (channels == 1)
    gray = view.clone();
  else
    cv::cvtColor(view, gray, channels == 3 ? cv::COLOR_BGR2GRAY : cv::COLOR_BGRA2GRAY);
  return gray;
}

Aedat4EventSource::Aedat4EventSource(const std::filesystem::path& file)
    : reader_(std::make_unique<Aedat4Reader>(file)) {
  eventSensorSize(*reader_, width_, height_);
}
Aedat4EventSource::~Aedat4EventSource() = default;
int Aedat4EventSource::width() const { return width_; }
int Aedat4EventSource::height() const { return height_; }

bool Aedat4EventSource::decodeNextBlock(EventArray& block) {
  Aedat4Packet p;
  std::size_t n = 0;
  do {
    if (!reader_->next(p)) return false;
    if (p.type == "TRIG") appendTriggers(FlatTable::root(p.root), reader_->path(), p.offset, triggers_);
  } while (p.type != "EVTS");
  const ByteView e = FlatTable::root(p.root).vector(0, kEventBytes, n);
  block.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint8_t* r = e.data() + i * kEventBytes;
    std::int64_t t;
    std::int16_t xy[2];
    std::memcpy(&t, r, 8);
    std::memcpy(xy, r + 8, 4);
    if (xy[0] < 0 || xy[1] < 0 || (width_ > 0 && (xy[0] >= width_ || xy[1] >= height_)))
      throw errorAt(reader_->path(), p.offset,
                    "event " + std::to_string(i) + " of the packet at pixel (" + std::to_string(xy[0]) +
                        ", " + std::to_string(xy[1]) + ") outside the " + std::to_string(width_) + "x" +
                        std::to_string(height_) + " sensor");
    if (!microsecondsFitNs(t))
      throw errorAt(reader_->path(), p.offset,
                    "event " + std::to_string(i) + " of the packet has time " + std::to_string(t) +
                        " us, beyond what int64 ns holds");
    if (t * kNsPerUs < last_t_)
      throw errorAt(reader_->path(), p.offset,
                    "events out of order: event " + std::to_string(i) + " of the packet at " +
                        std::to_string(t) + " us comes after one at " + std::to_string(last_t_ / kNsPerUs) +
                        " us");
    last_t_ = t * kNsPerUs;
    block.t[i] = last_t_;
    block.x[i] = static_cast<std::uint16_t>(xy[0]);
    block.y[i] = static_cast<std::uint16_t>(xy[1]);
    block.p[i] = r[12] ? 1 : -1;
  }
  return true;
}

}  // namespace eds
