// ROS bags written by Debian's python3-rosbag (tests/tools/write_bags.py: genpy message classes, not
// eds code) must give exactly the events they were written from; damaged recordings of every kind must
// give an InputError that names the file and the place, never a crash.
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <vector>

#include "io/aedat4.hpp"
#include "io/ecd_events.hpp"
#include "io/prophesee.hpp"
#include "io/read_events.hpp"
#include "io/ros_bag.hpp"
#include "io/ros_events.hpp"
#include "io/sequence.hpp"
#include "test_data.hpp"

namespace eds {
namespace {

namespace fs = std::filesystem;

constexpr std::size_t kEvents = 60000;

bool pythonRosbagAvailable() {
  return std::system("/usr/bin/python3 -c 'import rosbag, genpy, roslz4' > /dev/null 2>&1") == 0;
}

// The bags written once per test program: events_{none,bz2,lz4}.bag from the ESIM sequence.
const fs::path& writtenBags() {
  static const fs::path dir = [] {
    const fs::path out = test::tempDir("bags");
    const std::string cmd = "/usr/bin/python3 " EDS_SOURCE_DIR "/tests/tools/write_bags.py " +
                            (test::sharedDataDir() / "esim_poster6dof_planar").string() + " " + out.string() +
                            " " + std::to_string(kEvents) + " 2500";
    return std::system(cmd.c_str()) == 0 ? out : fs::path();
  }();
  return dir;
}

#define EDS_REQUIRE_WRITTEN_BAGS(dir)                                                                     \
  EDS_REQUIRE_SHARED(esim_, "esim_poster6dof_planar");                                                    \
  EDS_REQUIRE_AVAILABLE(pythonRosbagAvailable(), "Debian python3-rosbag, python3-roslz4, python3-genpy"); \
  const fs::path dir = writtenBags();                                                                     \
  ASSERT_FALSE(dir.empty()) << "tests/tools/write_bags.py failed"

std::vector<std::uint8_t> readBytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

fs::path writeBytes(const fs::path& file, const std::vector<std::uint8_t>& bytes) {
  std::ofstream(file, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  return file;
}

// Reads every event of `path`; expects an InputError naming `named` and containing `phrase`.
void expectReadError(const std::function<void()>& read, const fs::path& named, const std::string& phrase) {
  try {
    read();
    ADD_FAILURE() << "no error for " << named;
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(named.string()), std::string::npos) << what;
    EXPECT_NE(what.find(phrase), std::string::npos) << what;
  }
}

void readBag(const fs::path& path, const std::string& topic = "") {
  RosEventSource src(path, topic);
  test::readAll(src, 4096);
}

void readRaw(const fs::path& path, PropheseeOptions o = {}) {
  PropheseeRawSource src(path, o);
  test::readAll(src, 4096);
}

TEST(WrittenBags, EveryChunkCompressionGivesExactlyTheTextEvents) {
  EDS_REQUIRE_WRITTEN_BAGS(dir);
  EcdEventSource text(test::sharedDataDir() / "esim_poster6dof_planar/events.txt.gz");
  EventArray expected;
  text.read(expected, kEvents);
  for (const char* c : {"none", "bz2", "lz4"}) {
    SCOPED_TRACE(c);
    RosEventSource src(dir / (std::string("events_") + c + ".bag"));
    EXPECT_EQ(src.topic().name, "/dvs/events");
    EXPECT_EQ(src.topic().type, "dvs_msgs/EventArray");
    EXPECT_EQ(src.topic().messages, kEvents / 2500);
    const EventArray got = test::readAll(src, 4096);
    ASSERT_EQ(got.size(), kEvents);
    EXPECT_EQ(got.t, expected.t);
    EXPECT_EQ(got.x, expected.x);
    EXPECT_EQ(got.y, expected.y);
    EXPECT_EQ(got.p, expected.p);
    EXPECT_EQ(src.stats().width, 240u);
    EXPECT_EQ(src.stats().height, 180u);
  }
}

TEST(BadRecordings, DamagedBagsNameTheFileAndPlace) {
  EDS_REQUIRE_WRITTEN_BAGS(dir);
  const fs::path out = test::tempDir("bad_bags");
  const auto plain = readBytes(dir / "events_none.bag");
  // Cut in the middle of a chunk.
  auto cut = plain;
  cut.resize(cut.size() / 2);
  expectReadError([&] { readBag(writeBytes(out / "cut.bag", cut)); }, out / "cut.bag", "truncated");
  // The bag header record's op code changed.
  auto op = plain;
  const std::string op_field = "op=\x03";
  const auto at = std::search(op.begin(), op.end(), op_field.begin(), op_field.end()) - op.begin();
  op[static_cast<std::size_t>(at) + 3] = 0x09;
  expectReadError([&] { readBag(writeBytes(out / "op.bag", op)); }, out / "op.bag", "not a bag header");
  // Bytes of compressed chunks overwritten.
  for (const char* c : {"lz4", "bz2"}) {
    auto bytes = readBytes(dir / (std::string("events_") + c + ".bag"));
    for (std::size_t i = 6000; i < 6064; ++i) bytes[i] ^= 0x5A;
    const fs::path f = out / (std::string("corrupt_") + c + ".bag");
    expectReadError([&] { readBag(writeBytes(f, bytes)); }, f, std::string("corrupt ") + c);
  }
  // A topic the bag does not have.
  expectReadError([&] { readBag(dir / "events_none.bag", "/davis/left/events"); }, dir / "events_none.bag",
                  "no topic /davis/left/events (event topics: /dvs/events (dvs_msgs/EventArray))");
  // Not a bag at all, and no file.
  const fs::path text = writeBytes(out / "notes.bag", {'h', 'e', 'l', 'l', 'o', '\n'});
  expectReadError([&] { readBag(text); }, text, "not a ROS bag");
  expectReadError([&] { readBag(out / "missing.bag"); }, out / "missing.bag", "file not found");
}

TEST(BadRecordings, AnSqliteFileThatIsNotARosbag2IsRefused) {
  const fs::path f = test::tempDir("bad_db3") / "other.db3";
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(f.c_str(), &db), SQLITE_OK);
  ASSERT_EQ(sqlite3_exec(db, "CREATE TABLE notes (id INTEGER, text TEXT)", nullptr, nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(db);
  expectReadError([&] { readBag(f); }, f, "not a rosbag2 database");
}

TEST(BadRecordings, DamagedEvtFilesNameTheFileAndByte) {
  const fs::path out = test::tempDir("bad_raw");
  const std::string header = "% evt 3.0\n% geometry 64x48\n% end\n";
  auto raw = [&](const std::string& head, const std::vector<std::uint16_t>& words) {
    std::vector<std::uint8_t> b(head.begin(), head.end());
    const auto* w = reinterpret_cast<const std::uint8_t*>(words.data());
    b.insert(b.end(), w, w + 2 * words.size());
    return b;
  };
  // TIME_HIGH 5, TIME_LOW 0, ADDR_Y 3, ADDR_X 7 (ON): one good event.
  const std::vector<std::uint16_t> good = {0x8005, 0x6000, 0x0003, 0x2807};
  {
    const fs::path f = writeBytes(out / "good.raw", raw(header, good));
    PropheseeRawSource src(f);
    const EventArray e = test::readAll(src, 4096);
    ASSERT_EQ(e.size(), 1u);
    EXPECT_EQ(e.t[0], (5 << 12) * 1000);
    EXPECT_EQ(e.x[0], 7);
    EXPECT_EQ(e.y[0], 3);
    EXPECT_EQ(e.p[0], 1);
  }
  auto undefined = good;
  undefined.push_back(0x1234);  // type 1 is not an EVT 3.0 word
  const fs::path f1 = writeBytes(out / "undefined.raw", raw(header, undefined));
  expectReadError([&] { readRaw(f1); }, f1,
                  "byte " + std::to_string(header.size() + 8) + ": word of undefined type 1");
  auto odd = raw(header, good);
  odd.push_back(0x42);
  const fs::path f2 = writeBytes(out / "odd.raw", odd);
  expectReadError([&] { readRaw(f2); }, f2, "ends inside a word");
  auto back = good;
  back.insert(back.end(), {0x8003, 0x6000, 0x2807});  // TIME_HIGH 3 after 5: 8 ms back
  const fs::path f3 = writeBytes(out / "back.raw", raw(header, back));
  expectReadError([&] { readRaw(f3); }, f3, "events out of order: event 1");
  auto outside = good;
  outside.push_back(0x2840);  // x = 64 on a 64-wide sensor
  const fs::path f4 = writeBytes(out / "outside.raw", raw(header, outside));
  expectReadError([&] { readRaw(f4); }, f4, "pixel (64, 3) outside the 64x48 sensor");
  const fs::path f5 = writeBytes(out / "evt4.raw", raw("% evt 4.0\n", good));
  expectReadError([&] { readRaw(f5); }, f5, "unsupported event encoding 'evt 4.0'");
  const fs::path f6 = writeBytes(out / "noformat.raw", raw("% date today\n", good));
  expectReadError([&] { readRaw(f6); }, f6, "names no event encoding");
}

TEST(BadRecordings, EvtPixelsOutsideAGivenResolutionAreRefused) {
  EDS_REQUIRE_SHARED(file, "real/prophesee/evt2_gen3_640x480.raw");
  expectReadError([&] { readRaw(file, PropheseeOptions{320, 240}); }, file, "outside the 320x240 sensor");
}

void readAedat(const fs::path& path) {
  Aedat4EventSource src(path);
  test::readAll(src, 4096);
  scanAedat4(path);
}

TEST(BadRecordings, DamagedAedat4FilesNameTheFileAndByte) {
  EDS_REQUIRE_SHARED(file, "real/aedat4/davis346_street.aedat4");
  const fs::path out = test::tempDir("bad_aedat");
  const auto bytes = readBytes(file);
  // The first packet starts right after the IOHeader: 14 bytes of magic, its int32 size, its bytes.
  std::int32_t header_size;
  std::memcpy(&header_size, bytes.data() + 14, 4);
  const std::size_t first = 18 + static_cast<std::size_t>(header_size);
  auto cut = bytes;
  cut.resize(first + 100);
  expectReadError([&] { readAedat(writeBytes(out / "cut.aedat4", cut)); }, out / "cut.aedat4",
                  "byte " + std::to_string(first) + ": packet size");
  auto stream = bytes;
  stream[first] = 9;  // a stream the header does not describe
  expectReadError([&] { readAedat(writeBytes(out / "stream.aedat4", stream)); }, out / "stream.aedat4",
                  "byte " + std::to_string(first) + ": packet of stream 9");
  auto corrupt = bytes;
  for (std::size_t i = first + 20; i < first + 80; ++i) corrupt[i] ^= 0xA5;
  expectReadError([&] { readAedat(writeBytes(out / "corrupt.aedat4", corrupt)); }, out / "corrupt.aedat4",
                  "byte " + std::to_string(first + 8) + ": corrupt lz4");
  auto header = bytes;
  header[14] = 0xFF, header[15] = 0xFF, header[16] = 0xFF, header[17] = 0x7F;
  expectReadError([&] { readAedat(writeBytes(out / "header.aedat4", header)); }, out / "header.aedat4",
                  "IOHeader size");
}

TEST(BadRecordings, AFileOfNoKnownFormatIsNotASequence) {
  const fs::path f = writeBytes(test::tempDir("unknown") / "data.bin", {1, 2, 3, 4, 5, 6, 7, 8});
  expectReadError([&] { Sequence seq(f); }, f, "not a recording eds reads");
}

}  // namespace
}  // namespace eds

namespace eds {
namespace {

// A copy of the real rosbag2 SQLite file with one SQL change applied.
fs::path editedDb3(const fs::path& dir, const std::string& name, const std::string& sql) {
  const fs::path f = dir / (name + ".db3");
  fs::copy_file(
      test::sharedDataDir() / "real/ros2_and_ros1_event_camera_msgs/test_events_1/test_events_1.db3", f,
      fs::copy_options::overwrite_existing);
  sqlite3* db = nullptr;
  EXPECT_EQ(sqlite3_open(f.c_str(), &db), SQLITE_OK);
  EXPECT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK) << sql;
  sqlite3_close(db);
  return f;
}

TEST(BadRecordings, DamagedRosbag2FilesNameTheMessage) {
  EDS_REQUIRE_SHARED(real, "real/ros2_and_ros1_event_camera_msgs/test_events_1/test_events_1.db3");
  const fs::path out = test::tempDir("bad_rosbag2");
  const fs::path topic = editedDb3(out, "topic", "UPDATE messages SET topic_id = 7 WHERE id = 3");
  expectReadError([&] { readBag(topic); }, topic,
                  "message 2 is on topic id 7, which the topics table does not hold");
  const fs::path json = editedDb3(out, "json", "UPDATE topics SET serialization_format = 'json'");
  expectReadError([&] { readBag(json); }, json, "uses serialization 'json' (only cdr is read)");
  const fs::path big =
      editedDb3(out, "big", "UPDATE messages SET data = X'0000' || substr(data, 3) WHERE id = 1");
  expectReadError([&] { readBag(big); }, big, "not little-endian CDR");
  const fs::path cut = editedDb3(out, "cut", "UPDATE messages SET data = substr(data, 1, 60) WHERE id = 2");
  expectReadError([&] { readBag(cut); }, cut, "cut.db3, message 1: byte 56: encoding: length past the end");
  const fs::path evt4 = editedDb3(out, "evt4",
                                  "UPDATE messages SET data = replace(data, CAST('evt3' AS BLOB), "
                                  "CAST('evt4' AS BLOB)) WHERE id = 1");
  expectReadError([&] { readBag(evt4); }, evt4,
                  "message 0 on /event_camera/events: event encoding 'evt4' is not read");
  const fs::path type = editedDb3(out, "type", "UPDATE topics SET type = 'std_msgs/msg/String'");
  expectReadError([&] { readBag(type); }, type, "no event topic");
  expectReadError([&] { readBag(real, "/event_camera/events_left"); }, real,
                  "no topic /event_camera/events_left");
}

TEST(BadRecordings, DamagedMcapFilesNameTheFileAndByte) {
  EDS_REQUIRE_SHARED(file, "real/ros2_and_ros1_event_camera_msgs/test_events_2/test_events_2_0.mcap");
  const fs::path out = test::tempDir("bad_mcap");
  const auto bytes = readBytes(file);
  auto cut = bytes;
  cut.resize(400000);  // inside the first chunk (bytes 555..808146)
  const auto readAllMessages = [](const fs::path& f) {
    auto bag = openRosBag(f);
    RosMessage m;
    while (bag->next(m)) {
    }
  };
  expectReadError([&] { readAllMessages(writeBytes(out / "cut.mcap", cut)); }, out / "cut.mcap",
                  "byte 555: record length 807582 runs past the end of the file");
  auto length = bytes;
  length[556 + 7] = 0x10;  // the first chunk's length becomes huge
  expectReadError([&] { readAllMessages(writeBytes(out / "length.mcap", length)); }, out / "length.mcap",
                  "byte 555: record length");
  auto magic = bytes;
  magic[1] = 'N';
  expectReadError([&] { readAllMessages(writeBytes(out / "magic.mcap", magic)); }, out / "magic.mcap",
                  "not a ROS bag");
}

TEST(BadRecordings, DamagedFramesCalibrationAndPosesInABagNameTheMessage) {
  EDS_REQUIRE_WRITTEN_BAGS(dir);
  const fs::path out = test::tempDir("bad_frames");
  const std::string cmd = "/usr/bin/python3 " EDS_SOURCE_DIR "/tests/tools/write_bags.py " +
                          (test::sharedDataDir() / "esim_poster6dof_planar").string() + " " + out.string() +
                          " 1000 2500 0.2 none";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const auto bytes = readBytes(out / "recording.bag");
  const auto edited = [&](const std::string& name, const std::string& from, const std::string& to) {
    auto b = bytes;
    const auto at = std::search(b.begin(), b.end(), from.begin(), from.end());
    EXPECT_NE(at, b.end()) << from;
    std::copy(to.begin(), to.end(), at);
    return writeBytes(out / name, b);
  };
  const fs::path yuv = edited("yuv.bag", "mono8", "yuv42");
  expectReadError([&] { Sequence s(yuv); }, yuv, "image encoding 'yuv42' is not read");
  const fs::path model = edited("model.bag", "plumb_bob", "fisheye_x");
  expectReadError([&] { Sequence s(model); }, model, "distortion model 'fisheye_x' is not supported");
  // Frames without events, and events without frames: what eds run needs is named.
  const Sequence events_only(dir / "events_none.bag");
  EXPECT_FALSE(events_only.hasFrames());
  EXPECT_TRUE(events_only.hasEvents());
  expectReadError([&] { Sequence(dir / "events_none.bag").camera(); }, dir / "events_none.bag",
                  "holds no calibration: give one with --calib FILE");
}

TEST(BadRecordings, MoreDamagedAedat4AndEvtFiles) {
  EDS_REQUIRE_SHARED(aedat, "real/aedat4/davis346_street.aedat4");
  const fs::path out = test::tempDir("bad_more");
  auto bytes = readBytes(aedat);
  std::int32_t header_size;
  std::memcpy(&header_size, bytes.data() + 14, 4);
  const std::size_t first = 18 + static_cast<std::size_t>(header_size);  // an EVTS packet on stream 0
  bytes[first] = 3;                                                      // stream 3 carries TRIG
  const fs::path type = writeBytes(out / "type.aedat4", bytes);
  expectReadError([&] { readAedat(type); }, type,
                  "packet of type 'EVTS' on stream 3, which the header says carries TRIG");
  auto header = readBytes(aedat);
  header.resize(200);
  const fs::path short_header = writeBytes(out / "header.aedat4", header);
  expectReadError([&] { readAedat(short_header); }, short_header, "runs past the end of the file");
  // EVT 2.0: a word of type 5 is not defined.
  const std::string head = "% evt 2.0\n% geometry 64x48\n";
  std::vector<std::uint8_t> evt2(head.begin(), head.end());
  for (std::uint32_t w : {0x80000001u, 0x10000803u, 0x50000000u}) {
    const auto* p = reinterpret_cast<const std::uint8_t*>(&w);
    evt2.insert(evt2.end(), p, p + 4);
  }
  const fs::path f = writeBytes(out / "evt2.raw", evt2);
  expectReadError([&] { readRaw(f); }, f,
                  "byte " + std::to_string(head.size() + 8) + ": word of undefined type 5");
}

TEST(BadRecordings, UnknownChunkCompressionAndAnUnindexedBag) {
  EDS_REQUIRE_WRITTEN_BAGS(dir);
  const fs::path out = test::tempDir("bag_header");
  auto lz4 = readBytes(dir / "events_lz4.bag");
  const std::string field = "compression=lz4";
  std::replace_if(
      std::search(lz4.begin(), lz4.end(), field.begin(), field.end()) + 14,
      std::search(lz4.begin(), lz4.end(), field.begin(), field.end()) + 15, [](auto) { return true; }, '5');
  const fs::path lz5 = writeBytes(out / "lz5.bag", lz4);
  expectReadError([&] { readBag(lz5); }, lz5, "unknown chunk compression 'lz5'");
  // A bag whose recorder died before writing its index (index_pos 0) is read from its chunks alone.
  auto plain = readBytes(dir / "events_none.bag");
  const std::string index_field = "index_pos=";
  const auto at = std::search(plain.begin(), plain.end(), index_field.begin(), index_field.end());
  std::fill(at + 10, at + 18, 0);
  const fs::path unindexed = writeBytes(out / "unindexed.bag", plain);
  RosEventSource a(unindexed), b(dir / "events_none.bag");
  const EventArray ea = test::readAll(a, 4096), eb = test::readAll(b, 4096);
  EXPECT_EQ(ea.size(), kEvents);
  EXPECT_EQ(ea.t, eb.t);
}

}  // namespace
}  // namespace eds

namespace eds {
namespace {

// The real MCAP file with every chunk recompressed by Debian's `zstd` or `lz4` program (the frame
// formats MCAP names) and no summary section: the same messages must come out, byte for byte.
fs::path recompressedMcap(const fs::path& source, const fs::path& dir, const std::string& tool) {
  const auto in = readBytes(source);
  std::vector<std::uint8_t> out(in.begin(), in.begin() + 8);
  const auto put = [&](const void* p, std::size_t n) {
    const auto* b = static_cast<const std::uint8_t*>(p);
    out.insert(out.end(), b, b + n);
  };
  std::size_t pos = 8;
  while (pos + 9 <= in.size()) {
    const std::uint8_t op = in[pos];
    std::uint64_t len;
    std::memcpy(&len, &in[pos + 1], 8);
    const std::uint8_t* body = &in[pos + 9];
    pos += 9 + len;
    if (op == 0x0F) break;  // data end: the summary after it is left out
    if (op != 0x06) {
      out.insert(out.end(), body - 9, body + len);
      continue;
    }
    // Chunk: start, end, uncompressed size, crc, compression (string), records (u64 length + bytes).
    std::uint32_t comp_len;
    std::memcpy(&comp_len, body + 28, 4);
    const std::size_t records_at = 32 + comp_len + 8;
    writeBytes(dir / "records", std::vector<std::uint8_t>(body + records_at, body + len));
    const std::string cmd =
        tool + " -q -f -c " + (dir / "records").string() + " > " + (dir / "packed").string();
    EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
    const auto packed = readBytes(dir / "packed");
    const std::string name = tool == "zstd" ? "zstd" : "lz4";
    const std::uint32_t name_len = static_cast<std::uint32_t>(name.size());
    const std::uint64_t packed_len = packed.size(), new_len = 28 + 4 + name.size() + 8 + packed.size();
    out.push_back(0x06);
    put(&new_len, 8);
    put(body, 28);  // times, uncompressed size and crc unchanged
    put(&name_len, 4);
    put(name.data(), name.size());
    put(&packed_len, 8);
    put(packed.data(), packed.size());
  }
  const std::uint8_t data_end[] = {0x0F, 4, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
  put(data_end, sizeof(data_end));
  const std::uint8_t footer_head[] = {0x02, 20, 0, 0, 0, 0, 0, 0, 0};
  put(footer_head, sizeof(footer_head));
  out.insert(out.end(), 20, 0);  // no summary
  out.insert(out.end(), in.begin(), in.begin() + 8);
  return writeBytes(dir / ("recompressed_" + tool + ".mcap"), out);
}

TEST(Mcap, ChunksCompressedByZstdAndLz4ProgramsGiveTheSameMessages) {
  EDS_REQUIRE_SHARED(file, "real/ros2_and_ros1_event_camera_msgs/test_events_2/test_events_2_0.mcap");
  EDS_REQUIRE_AVAILABLE(std::system("zstd --version > /dev/null 2>&1 && lz4 --version > /dev/null 2>&1") == 0,
                        "Debian zstd and lz4 programs");
  const fs::path dir = test::tempDir("mcap_recompressed");
  struct Msg {
    std::string topic;
    TimeNs t;
    std::vector<std::uint8_t> data;
  };
  const auto messages = [](const fs::path& f) {
    auto bag = openRosBag(f);
    std::vector<Msg> all;
    RosMessage m;
    while (bag->next(m))
      all.push_back(
          {bag->topics()[m.topic].name, m.t_record, {m.data.data(), m.data.data() + m.data.size()}});
    EXPECT_EQ(bag->topics().size(), 1u);
    EXPECT_EQ(bag->topics().at(0).messages, 100u);  // counted by a pass when there is no summary
    return all;
  };
  const std::vector<Msg> original = messages(file);
  ASSERT_EQ(original.size(), 100u);
  for (const std::string tool : {"zstd", "lz4"}) {
    SCOPED_TRACE(tool);
    const std::vector<Msg> got = messages(recompressedMcap(file, dir, tool));
    ASSERT_EQ(got.size(), original.size());
    for (std::size_t i = 0; i < got.size(); ++i) {
      ASSERT_EQ(got[i].topic, original[i].topic);
      ASSERT_EQ(got[i].t, original[i].t);
      ASSERT_TRUE(got[i].data == original[i].data) << i;
    }
    // The same file with bytes of its first compressed chunk overwritten.
    auto bytes = readBytes(dir / ("recompressed_" + tool + ".mcap"));
    for (std::size_t i = 700; i < 760; ++i) bytes[i] ^= 0x3C;  // the first chunk starts at byte 555
    const fs::path corrupt = writeBytes(dir / ("corrupt_" + tool + ".mcap"), bytes);
    expectReadError([&] { messages(corrupt); }, corrupt, "corrupt " + tool + " block");
  }
}

}  // namespace
}  // namespace eds

namespace eds {
namespace {

TEST(WrittenBags, FramesCalibrationGroundTruthAndImuComeOutAsWritten) {
  EDS_REQUIRE_WRITTEN_BAGS(dir);
  const fs::path out = test::tempDir("recording_bag");
  const fs::path esim = test::sharedDataDir() / "esim_poster6dof_planar";
  const std::string cmd = "/usr/bin/python3 " EDS_SOURCE_DIR "/tests/tools/write_bags.py " + esim.string() +
                          " " + out.string() + " 1000 2500 0.3";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const Sequence bag(out / "recording.bag"), folder(esim);
  EXPECT_EQ(bag.camera().fx, folder.camera().fx);
  EXPECT_EQ(bag.camera().distortion, Distortion::kNone);
  ASSERT_EQ(bag.frames().size(), 8u);  // 0 .. 0.28 s at 25 Hz
  EXPECT_EQ(bag.frames().back().t, folder.frames()[7].t);
  ASSERT_EQ(bag.groundTruth().size(), 60u);  // 200 Hz up to 0.3 s (0.2950 s the last)
  ASSERT_EQ(bag.imu().size(), 61u);          // k = 0 .. 60
  for (std::size_t k = 0; k < bag.imu().size(); ++k) {
    const ImuSample& s = bag.imu()[k];
    ASSERT_EQ(s.t, static_cast<TimeNs>(k) * 5'000'000);
    EXPECT_EQ(s.gyro[0], 0.01 * static_cast<double>(k));
    EXPECT_EQ(s.gyro[1], -0.02 * static_cast<double>(k));
    EXPECT_EQ(s.gyro[2], 0.5);
    EXPECT_EQ(s.acc[1], 9.81);
    EXPECT_EQ(s.acc[2], -0.2 * static_cast<double>(k));
  }
}

// A stereo bag (two event, image and CameraInfo topics): the options choose the camera, each stream
// comes from the chosen one, and without a choice the error lists the topics to choose from.
TEST(WrittenBags, StereoBagReadsTheChosenCamera) {
  EDS_REQUIRE_WRITTEN_BAGS(dir);
  const fs::path out = test::tempDir("stereo_bag");
  const fs::path esim = test::sharedDataDir() / "esim_poster6dof_planar";
  const std::string cmd = "/usr/bin/python3 " EDS_SOURCE_DIR "/tests/tools/write_bags.py --stereo " +
                          esim.string() + " " + out.string() + " 0.2";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const fs::path bag = out / "stereo.bag";
  expectReadError([&] { Sequence s(bag); }, bag,
                  "several event topics: /davis/left/events (dvs_msgs/EventArray), /davis/right/events "
                  "(dvs_msgs/EventArray); choose one with --events-topic");
  expectReadError([&] { Sequence s(bag, {.events_topic = "/davis/left/events"}); }, bag,
                  "several image topics: /davis/left/image_raw (sensor_msgs/Image), /davis/right/image_raw "
                  "(sensor_msgs/Image); choose one with --image-topic");
  expectReadError([&] { Sequence s(bag, {.events_topic = "/davis/left/image_raw"}); }, bag,
                  "topic /davis/left/image_raw has type sensor_msgs/Image, not event");
  const Sequence folder(esim);
  const Sequence left(bag, {.events_topic = "/davis/left/events", .image_topic = "/davis/left/image_raw"});
  const Sequence right(bag, {.events_topic = "/davis/right/events", .image_topic = "/davis/right/image_raw"});
  EXPECT_EQ(left.camera().fx, folder.camera().fx);
  EXPECT_EQ(right.camera().fx, folder.camera().fx + 10.0);
  const EventArray el = test::readAll(*left.openEvents(), 4096),
                   er = test::readAll(*right.openEvents(), 4096);
  ASSERT_GT(el.size(), 1000u);
  ASSERT_EQ(er.size(), (el.size() + 1) / 2);
  for (std::size_t i = 0; i < er.size(); ++i) ASSERT_EQ(er.t[i], el.t[2 * i]) << i;
  ASSERT_EQ(left.frames().size(), right.frames().size());
  const cv::Mat fl = left.loadFrame(2), fr = right.loadFrame(2);
  cv::Mat sum;
  cv::add(fl, fr, sum, cv::noArray(), CV_32S);
  EXPECT_EQ(cv::countNonZero(sum != 255), 0);  // the right image is the left one inverted
  EXPECT_GT(cv::countNonZero(fl != fr), fl.total() / 2);
}

}  // namespace
}  // namespace eds

namespace eds {
namespace {

// libcaer EventPackets (written by tests/tools/write_bags.py with python3-rosbag, packed as
// libcaer_driver packs them, across a wrap of the sensor's 31-bit µs clock): every event at its ESIM
// pixel, polarity and time truncated to the µs, on the ROS clock of time_base.
TEST(WrittenBags, LibcaerPacketsGiveEveryEventToTheMicrosecond) {
  EDS_REQUIRE_WRITTEN_BAGS(dir);
  const fs::path out = test::tempDir("libcaer_bag");
  const fs::path esim = test::sharedDataDir() / "esim_poster6dof_planar";
  const std::string cmd = "/usr/bin/python3 " EDS_SOURCE_DIR "/tests/tools/write_bags.py --libcaer " +
                          esim.string() + " " + out.string() + " 0.3";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const Sequence folder(esim), bag(out / "libcaer.bag");
  EXPECT_EQ(bag.width(), 240);
  auto a = folder.openEvents();
  auto b = bag.openEvents();
  EventArray expected;
  const EventArray got = test::readAll(*b, 4096);
  while (a->read(expected, 1 << 16) > 0 && expected.t.back() <= 300'000'000) {
  }
  while (!expected.empty() && expected.t.back() > 300'000'000) expected.resize(expected.size() - 1);
  ASSERT_EQ(got.size(), expected.size());
  ASSERT_GT(got.size(), 20'000u);
  const std::string bad =
      "/usr/bin/python3 " EDS_SOURCE_DIR "/tests/tools/write_bags.py --libcaer-bad " + out.string();
  ASSERT_EQ(std::system(bad.c_str()), 0) << bad;
  expectReadError([&] { readBag(out / "odd.bag"); }, out / "odd.bag",
                  "message 0 on /events: libcaer payload of 7 bytes is not 8-byte events");
  expectReadError([&] { readBag(out / "negative.bag"); }, out / "negative.bag",
                  "libcaer event 0 has a negative time (payload byte 0)");
  expectReadError([&] { readBag(out / "code.bag"); }, out / "code.bag",
                  "libcaer_cmp token 4 has unknown code 7 (payload byte 8)");
  constexpr TimeNs kRosBase = 1'700'000'000'000'000'000, kSensorStartUs = (TimeNs{1} << 31) - 100'000;
  for (std::size_t i = 0; i < got.size(); ++i) {
    ASSERT_EQ(got.t[i], kRosBase + (expected.t[i] / 1000 + kSensorStartUs) * 1000) << i;
    ASSERT_EQ(got.x[i], expected.x[i]) << i;
    ASSERT_EQ(got.y[i], expected.y[i]) << i;
    ASSERT_EQ(got.p[i], expected.p[i]) << i;
  }
}

}  // namespace
}  // namespace eds
