// Inputs the fuzz targets (fuzz/, scripts/fuzz) found to crash a reader or overflow a number, each
// reduced to what triggers it: now an InputError naming the file (and line), or read correctly.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <string>

#include "core/error.hpp"
#include "io/ecd_events.hpp"
#include "io/kalibr.hpp"
#include "io/ply.hpp"
#include "io/prophesee.hpp"
#include "io/read_events.hpp"
#include "io/ros_events.hpp"
#include "io/ros_recording.hpp"
#include "system/odometry_config_io.hpp"
#include "test_data.hpp"

namespace eds {
namespace {

namespace fs = std::filesystem;

fs::path write(const std::string& name, const std::string& content) {
  const fs::path p = test::tempDir("fuzz_regressions_" + name) / name;
  std::ofstream(p, std::ios::binary) << content;
  return p;
}

// A folder holding the bag that tests/tools/write_bags.py writes with `option` (Debian's python3-rosbag).
fs::path writeBag(const std::string& option, const std::string& name) {
  const fs::path dir = test::tempDir("fuzz_regressions_" + name);
  const std::string cmd =
      "/usr/bin/python3 " EDS_SOURCE_DIR "/tests/tools/write_bags.py " + option + " " + dir.string();
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
  return dir;
}

template <typename F>
void expectInputError(F&& f, const fs::path& file, const std::string& fragment) {
  try {
    f();
    ADD_FAILURE() << "no error for " << file;
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(file.string()), std::string::npos) << what;
    EXPECT_NE(what.find(fragment), std::string::npos) << what;
  }
}

// A pixel coordinate of 11 digits overflowed the fast line parser's int.
TEST(FuzzRegressions, EcdPixelOfElevenDigits) {
  const fs::path f = write("events.txt", "0.000001000 10 20 1\n0.000002000 10200005001 1 0\n");
  expectInputError(
      [&] {
        EcdEventSource src(f);
        test::readAll(src, 1000);
      },
      f, ":2");
}

// Seconds beyond what int64 ns holds overflowed the fast parser's time.
TEST(FuzzRegressions, EcdTimeBeyondInt64Nanoseconds) {
  const fs::path f = write("events.txt", "9999999999.000000000 1 1 1\n");
  expectInputError(
      [&] {
        EcdEventSource src(f);
        test::readAll(src, 1000);
      },
      f, ":1");
}

// A header line that is a bare '%' read past the line's end.
TEST(FuzzRegressions, PropheseeHeaderLineOfOnePercentSign) {
  std::string raw = "% evt 3.0\n%\n% format EVT3;height=720;width=1280\n% end\n";
  for (const std::uint16_t w : {0x8000, 0x6010, 0x0005, 0x2000 | 0x800 | 10})
    raw.append(reinterpret_cast<const char*>(&w), 2);
  const fs::path f = write("bare.raw", raw);
  const PropheseeHeader h = readPropheseeHeader(f);
  EXPECT_EQ(h.width, 1280);
  EXPECT_EQ(h.height, 720);
  PropheseeRawSource src(f);
  EXPECT_EQ(test::readAll(src, 100).size(), 1u);
}

// A configuration key that is a list (YAML's "? [a, b]") escaped as a yaml-cpp conversion error.
TEST(FuzzRegressions, ConfigKeyThatIsNotAName) {
  const fs::path f = write("config.yaml", "backend:\n  ? [a, b]\n  : 1\n");
  OdometryConfig cfg;
  expectInputError([&] { loadOdometryConfig(f, cfg); }, f, "line ");
}

// A DSEC camera entry that is a scalar escaped as a yaml-cpp subscript error.
TEST(FuzzRegressions, DsecCameraThatIsNotAMap) {
  const fs::path f = write("cam_to_cam.yaml", "intrinsics:\n  cam0: 5\n");
  expectInputError([&] { readDsecCamera(f.string()); }, f, "camera 'cam0' is not a map");
}

// A PLY header claiming more vertices than memory holds: allocated before the data was checked.
TEST(FuzzRegressions, PlyVertexCountBeyondTheFile) {
  const std::string header =
      "ply\nformat binary_little_endian 1.0\nelement vertex 4611686018427387904\nproperty float x\n"
      "property float y\nproperty float z\nend_header\n";
  const fs::path f = write("map.ply", header + std::string(24, '\0'));
  expectInputError([&] { readPly(f); }, f, "the header says 4611686018427387904 vertices, the file holds 2");
}

// An EventPacket with an empty payload: memcpy from a null pointer (UndefinedBehaviorSanitizer).
TEST(FuzzRegressions, EventPacketWithNoPayload) {
  EDS_REQUIRE_AVAILABLE(std::system("/usr/bin/python3 -c 'import rosbag, genpy' > /dev/null 2>&1") == 0,
                        "Debian python3-rosbag, python3-genpy");
  const fs::path dir = writeBag("--empty-packet", "packet");
  RosEventSource src(dir / "empty_packet.bag");
  const EventArray e = test::readAll(src, 100);
  ASSERT_EQ(e.size(), 1u);
  EXPECT_EQ(e.x[0], 10);
  EXPECT_EQ(e.y[0], 5);
  EXPECT_EQ(e.p[0], 1);
}

// A mono16 image whose rows are an odd number of bytes apart: OpenCV refused the view of it with an
// exception of its own (cv::Exception), which escaped the reader.
TEST(FuzzRegressions, Mono16ImageWithAnOddStep) {
  EDS_REQUIRE_AVAILABLE(std::system("/usr/bin/python3 -c 'import rosbag, genpy' > /dev/null 2>&1") == 0,
                        "Debian python3-rosbag, python3-genpy");
  RosFrameLoader loader(writeBag("--odd-step", "odd_step") / "odd_step.bag");
  const cv::Mat img = loader.load(0);
  ASSERT_EQ(img.type(), CV_8UC1);
  ASSERT_EQ(img.cols, 4);
  ASSERT_EQ(img.rows, 3);
  // 16-bit values 256 * (10 y + x + 1) + 7 scale to 10 y + x + 1 (the 7 rounds away).
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 4; ++x) EXPECT_EQ(img.at<std::uint8_t>(y, x), 10 * y + x + 1) << x << "," << y;
}

}  // namespace
}  // namespace eds
