// Bad input must give an InputError naming the file (and the line where there is one): never a crash,
// a hang or a silently wrong result. The asan preset runs these too.
#include <gtest/gtest.h>
#include <zlib.h>

#include <fstream>

#include "core/error.hpp"
#include "io/binary_file.hpp"
#include "io/ecd_events.hpp"
#include "io/sequence.hpp"
#include "io/trajectory_io.hpp"
#include "test_data.hpp"

namespace eds {
namespace {

namespace fs = std::filesystem;

class BadInput : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::tempDir(::testing::UnitTest::GetInstance()->current_test_info()->name());
  }
  fs::path write(const std::string& name, const std::string& content) {
    const fs::path p = dir_ / name;
    std::ofstream(p, std::ios::binary) << content;
    return p;
  }
  // Reads every event and expects an InputError naming the file and, if line > 0, that line.
  void expectEventsError(const fs::path& file, std::size_t line, const std::string& fragment,
                         EcdEventOptions opts = {}) {
    try {
      EcdEventSource src(file, opts);
      EventArray ev;
      while (src.read(ev, 3) > 0) {
      }
      FAIL() << "no error for " << file;
    } catch (const InputError& e) {
      expectNames(e, file, line, fragment);
    }
  }
  static void expectNames(const InputError& e, const fs::path& file, std::size_t line,
                          const std::string& fragment) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(file.string()), std::string::npos) << msg;
    EXPECT_EQ(e.line(), line) << msg;
    if (line > 0) EXPECT_NE(msg.find(":" + std::to_string(line) + ":"), std::string::npos) << msg;
    EXPECT_NE(msg.find(fragment), std::string::npos) << "'" << msg << "' lacks '" << fragment << "'";
  }
  template <typename F>
  void expectError(F&& f, const fs::path& file, std::size_t line, const std::string& fragment) {
    try {
      f();
      FAIL() << "no error for " << file;
    } catch (const InputError& e) {
      expectNames(e, file, line, fragment);
    }
  }
  fs::path dir_;
};

// --- events.txt ---
TEST_F(BadInput, MissingEventsFile) { expectEventsError(dir_ / "events.txt", 0, "not found"); }
TEST_F(BadInput, EventsPathIsADirectory) { expectEventsError(dir_, 0, "directory"); }
TEST_F(BadInput, NonNumericTimestamp) {
  expectEventsError(write("events.txt", "0.1 1 2 1\nabc 1 2 1\n"), 2, "malformed timestamp");
}
TEST_F(BadInput, TruncatedLineMissingPolarity) {
  expectEventsError(write("events.txt", "0.1 1 2 1\n0.2 1 2\n"), 2, "missing polarity");
}
TEST_F(BadInput, TruncatedLineMissingY) {
  expectEventsError(write("events.txt", "0.1 1 2 1\n0.2 1"), 2, "missing y");
}
TEST_F(BadInput, NonNumericX) { expectEventsError(write("events.txt", "0.1 1x 2 1\n"), 1, "malformed x"); }
TEST_F(BadInput, ExtraField) {
  expectEventsError(write("events.txt", "0.1 1 2 1\n0.2 1 2 1 7\n"), 2, "more than 4 fields");
}
TEST_F(BadInput, NegativeTimestamp) {
  expectEventsError(write("events.txt", "-0.1 1 2 1\n"), 1, "negative timestamp");
}
TEST_F(BadInput, DecreasingTimestamp) {
  expectEventsError(write("events.txt", "0.1 1 2 1\n0.3 1 2 1\n0.2 1 2 1\n"), 3, "decreases");
}
TEST_F(BadInput, PixelOutsideTheSensor) {
  expectEventsError(write("events.txt", "0.1 1 2 1\n0.2 240 2 1\n"), 2, "outside the 240x180 sensor",
                    {240, 180});
}
TEST_F(BadInput, NegativePixel) { expectEventsError(write("events.txt", "0.1 -1 2 1\n"), 1, "malformed x"); }
TEST_F(BadInput, PolarityTwo) {
  expectEventsError(write("events.txt", "0.1 1 2 1\n0.2 1 2 2\n"), 2, "polarity must be 0/1 or -1/+1");
}
TEST_F(BadInput, PolarityTen) {
  expectEventsError(write("events.txt", "0.1 1 2 10\n"), 1, "polarity must be 0/1 or -1/+1");
}
TEST_F(BadInput, ExponentTimestampIsRejectedNotMisread) {
  expectEventsError(write("events.txt", "1e-3 1 2 1\n"), 1, "malformed timestamp");
}
TEST_F(BadInput, TruncatedGzip) {
  std::string content;
  for (int i = 0; i < 50000; ++i) content += "0." + std::to_string(100000000 + i) + " 1 2 1\n";
  const fs::path full = dir_ / "full.gz";
  gzFile gz = gzopen(full.c_str(), "wb");
  gzwrite(gz, content.data(), static_cast<unsigned>(content.size()));
  gzclose(gz);
  std::ifstream in(full, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), {});
  const fs::path cut = write("events.txt.gz", bytes.substr(0, bytes.size() / 2));
  try {
    EcdEventSource src(cut);
    EventArray ev;
    while (src.read(ev, 1000) > 0) {
    }
    FAIL() << "truncated gzip read without error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(cut.string()), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
  }
}

TEST_F(BadInput, ErrorDeepInALongFileNamesTheRightLine) {
  // Long canonical files go through the fast parser; a bad line must still be found and named.
  std::string content;
  for (int i = 0; i < 5000; ++i) content += "0." + std::to_string(100000000 + i) + " 12 34 1\n";
  content += "0.200000000 12 34 2\n";
  for (int i = 0; i < 100; ++i) content += "0.3 1 2 0\n";
  expectEventsError(write("events.txt", content), 5001, "polarity must be 0/1 or -1/+1");
  content.replace(content.find("0.200000000 12 34 2"), 19, "0.200000000 12 3x 1");
  expectEventsError(write("events.txt", content), 5001, "malformed y");
}

// --- calib.txt ---
TEST_F(BadInput, CalibWithNaN) {
  const auto f = write("calib.txt", "200 200 120 90 nan 0 0 0 0\n");
  expectError([&] { readEcdCalib(f); }, f, 1, "non-finite");
}
TEST_F(BadInput, CalibWithWrongCount) {
  const auto f = write("calib.txt", "200 200 120 90 0.1\n");
  expectError([&] { readEcdCalib(f); }, f, 1, "got 5");
}
TEST_F(BadInput, CalibNonNumeric) {
  const auto f = write("calib.txt", "# header\n200 abc 120 90\n");
  expectError([&] { readEcdCalib(f); }, f, 2, "malformed number");
}
TEST_F(BadInput, CalibEmpty) {
  const auto f = write("calib.txt", "");
  expectError([&] { readEcdCalib(f); }, f, 0, "empty");
}
TEST_F(BadInput, CalibNegativeFocalLength) {
  const auto f = write("calib.txt", "-200 200 120 90\n");
  expectError([&] { readEcdCalib(f); }, f, 1, "positive");
}

// --- images.txt ---
TEST_F(BadInput, ImageListNamesMissingImage) {
  const auto f = write("images.txt", "0.0 images/frame_0.png\n");
  expectError([&] { readImageList(f); }, f, 1, "image file not found");
}
TEST_F(BadInput, ImageListMissingPath) {
  const auto f = write("images.txt", "0.0\n");
  expectError([&] { readImageList(f); }, f, 1, "missing image path");
}
TEST_F(BadInput, ImageListDecreasingTimestamps) {
  write("a.png", "x");
  const auto f = write("images.txt", "0.2 a.png\n0.1 a.png\n");
  expectError([&] { readImageList(f); }, f, 2, "must increase");
}
TEST_F(BadInput, UnreadableImage) {
  write("a.png", "not a png");
  write("images.txt", "0.1 a.png\n");
  expectError([&] { Sequence seq(dir_); }, dir_ / "a.png", 0, "cannot read image");
}

// --- groundtruth / TUM ---
TEST_F(BadInput, TumTooFewFields) {
  const auto f = write("groundtruth.txt", "0.0 1 2 3 0 0 0 1\n0.1 1 2 3 0 0 1\n");
  expectError([&] { readTum(f); }, f, 2, "expected 8 numbers");
}
TEST_F(BadInput, TumNaN) {
  const auto f = write("groundtruth.txt", "0.0 1 nan 3 0 0 0 1\n");
  expectError([&] { readTum(f); }, f, 1, "non-finite");
}
TEST_F(BadInput, TumZeroQuaternion) {
  const auto f = write("groundtruth.txt", "0.0 1 2 3 0 0 0 0\n");
  expectError([&] { readTum(f); }, f, 1, "zero quaternion");
}
TEST_F(BadInput, TumDecreasingTimestamps) {
  const auto f = write("groundtruth.txt", "1.0 1 2 3 0 0 0 1\n0.5 1 2 3 0 0 0 1\n");
  expectError([&] { readTum(f); }, f, 2, "decreases");
}

// --- sequence folders ---
TEST_F(BadInput, FormatsAreToldByTheirFirstBytesNotTheirNames) {
  const std::pair<std::string, FileFormat> cases[] = {
      {"#ROSBAG V2.0\nop=", FileFormat::kRosBag1},
      {std::string("SQLite format 3\0\x10", 17), FileFormat::kSqlite},
      {"\x89MCAP0\r\n\x01", FileFormat::kMcap},
      {"#!AER-DAT4.0\r\n\x20", FileFormat::kAedat4},
      {"\x89HDF\r\n\x1a\n\x00", FileFormat::kHdf5},
      {"% evt 3.0\n", FileFormat::kPropheseeRaw},
      {"#ROSBAG V1.2\n", FileFormat::kUnknown},                    // an older bag version eds does not read
      {std::string("SQLite format 3", 15), FileFormat::kUnknown},  // cut short before its NUL
      {"", FileFormat::kUnknown}};
  int i = 0;
  for (const auto& [content, format] : cases)
    EXPECT_EQ(sniffFileFormat(write("recording" + std::to_string(i++) + ".txt", content)), format) << content;
  EXPECT_EQ(sniffFileFormat(dir_ / "missing.bag"), FileFormat::kUnknown);
  EXPECT_EQ(sniffFileFormat(dir_), FileFormat::kUnknown);
}

TEST_F(BadInput, MissingSequenceFolder) {
  expectError([&] { Sequence seq(dir_ / "nope"); }, dir_ / "nope", 0, "not found");
}
TEST_F(BadInput, EmptySequenceFolder) {
  expectError([&] { Sequence seq(dir_); }, dir_, 0, "neither events");
}
TEST_F(BadInput, EmptyEventsFile) {
  const auto f = write("events.txt", "");
  expectError([&] { Sequence seq(dir_); }, f, 0, "empty");
}
TEST_F(BadInput, CalibrationMissingWhenAskedFor) {
  write("events.txt", "0.1 1 2 1\n");
  const Sequence seq(dir_);  // fine without calibration until someone needs it
  expectError([&] { seq.camera(); }, dir_ / "calib.txt", 0, "not found");
}

TEST_F(BadInput, CalibrationOverride) {
  write("events.txt", "0.1 1 2 1\n");
  Sequence seq(dir_);
  const auto f = write("other.txt", "200 200 120 90 -0.1 0.01 0 0 0\n");
  seq.setCamera(readCameraFile(f), f.string());
  EXPECT_DOUBLE_EQ(seq.camera().k[0], -0.1);
  CameraModel c = seq.camera();
  c.fx = -1;
  EXPECT_THROW(seq.setCamera(c, "neg"), std::invalid_argument);
  expectError([&] { readCameraFile(write("bad.txt", "200 200 x\n")); }, dir_ / "bad.txt", 1, "");
}

}  // namespace
}  // namespace eds
