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
#include "io/ros_bag.hpp"
#include "io/ros_events.hpp"
#include "io/sequence.hpp"
#include "test_data.hpp"

namespace eds {
namespace {

namespace fs = std::filesystem;

constexpr std::size_t kEvents = 60000;

EventArray readAll(EventSource& src) {
  EventArray all, part;
  while (true) {
    part.clear();
    if (src.read(part, 4096) == 0) break;
    appendRange(all, part, 0, part.size());
  }
  return all;
}

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
  readAll(src);
}

void readRaw(const fs::path& path, PropheseeOptions o = {}) {
  PropheseeRawSource src(path, o);
  readAll(src);
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
    const EventArray got = readAll(src);
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
    const EventArray e = readAll(src);
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
  readAll(src);
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
