// AEDAT 4.0 files written by an independent writer (tests/tools/write_aedat4.py: Debian's
// python3-flatbuffers Builder, the lz4 and zstd command-line tools) from the ESIM sequence: eds's reader
// gives back the events, frames, IMU samples and triggers as written, in all three compressions.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <string>

#include "core/error.hpp"
#include "io/aedat4.hpp"
#include "io/read_events.hpp"
#include "io/sequence.hpp"
#include "test_data.hpp"

namespace eds {
namespace {

namespace fs = std::filesystem;

bool flatbuffersAvailable() {
  return std::system("/usr/bin/python3 -c 'import flatbuffers, PIL' > /dev/null 2>&1") == 0 &&
         std::system("lz4 --version > /dev/null 2>&1 && zstd --version > /dev/null 2>&1") == 0;
}

fs::path writeAedat(const fs::path& esim, const std::string& compression, double until_s) {
  const fs::path out = test::tempDir("aedat_" + compression) / ("esim_" + compression + ".aedat4");
  const std::string cmd = "/usr/bin/python3 " EDS_SOURCE_DIR "/tests/tools/write_aedat4.py " + esim.string() +
                          " " + out.string() + " " + compression + " " + std::to_string(until_s);
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
  return out;
}

TEST(WrittenAedat4, EventsFramesImuAndTriggersComeOutAsWritten) {
  EDS_REQUIRE_SHARED(esim, "esim_poster6dof_planar");
  EDS_REQUIRE_AVAILABLE(flatbuffersAvailable(), "Debian python3-flatbuffers, python3-pil, lz4, zstd");
  const Sequence folder(esim);
  const EventArray truth = test::readAll(*folder.openEvents(), 100'000);
  for (const std::string compression : {"none", "lz4", "zstd"}) {
    SCOPED_TRACE(compression);
    const Sequence aedat(writeAedat(esim, compression, 0.5));
    EXPECT_EQ(aedat.format(), "AEDAT 4.0");
    EXPECT_EQ(aedat.width(), 240);
    EXPECT_EQ(aedat.height(), 180);
    const auto src = aedat.openEvents();
    const EventArray ev = test::readAll(*src, 7777);
    ASSERT_EQ(src->triggers().size(), 2u);
    EXPECT_EQ(src->triggers()[0].t,
              1000 * kNsPerUs);  // written: falling edge (2) at 1000 µs, pulse (3) at 2000
    EXPECT_EQ(src->triggers()[0].channel, 2);
    EXPECT_FALSE(src->triggers()[0].rising);
    EXPECT_EQ(src->triggers()[1].t, 2000 * kNsPerUs);
    EXPECT_TRUE(src->triggers()[1].rising);
    std::size_t n = 0;
    while (n < truth.size() && truth.t[n] <= 500'000'000) ++n;
    ASSERT_EQ(ev.size(), n);
    for (std::size_t i = 0; i < n; ++i) {
      ASSERT_EQ(ev.t[i], truth.t[i] / 1000 * 1000) << i;  // microseconds, as AEDAT stores them
      ASSERT_EQ(ev.x[i], truth.x[i]) << i;
      ASSERT_EQ(ev.y[i], truth.y[i]) << i;
      ASSERT_EQ(ev.p[i], truth.p[i]) << i;
    }
    ASSERT_EQ(aedat.frames().size(), 13u);  // 0 .. 0.48 s at 25 Hz
    for (std::size_t i = 0; i < aedat.frames().size(); ++i) {
      ASSERT_EQ(aedat.frames()[i].t, folder.frames()[i].t);
      // Written for every frame but the first: 1, 2 or 3 ms.
      EXPECT_EQ(aedat.frames()[i].exposure, i == 0 ? 0 : static_cast<TimeNs>(1 + i % 3) * 1'000'000) << i;
      ASSERT_EQ(cv::norm(aedat.loadFrame(i), folder.loadFrame(i), cv::NORM_INF), 0.0) << i;
    }
    ASSERT_EQ(aedat.imu().size(), 101u);  // 200 Hz, k = 0 .. 100
    constexpr double kG = 9.80665, kRad = 3.14159265358979323846 / 180.0;
    for (std::size_t k = 0; k < aedat.imu().size(); ++k) {
      const ImuSample& s = aedat.imu()[k];
      const double kd = static_cast<double>(k);
      ASSERT_EQ(s.t, static_cast<TimeNs>(k) * 5'000'000);
      EXPECT_NEAR(s.gyro[0], kd * kRad, 1e-6);
      EXPECT_NEAR(s.gyro[1], -2 * kd * kRad, 1e-6);
      EXPECT_NEAR(s.gyro[2], 50 * kRad, 1e-6);
      EXPECT_NEAR(s.acc[1], kG, 1e-5);
      EXPECT_NEAR(s.acc[2], -0.02 * kd * kG, 1e-5);
    }
  }
}

// Found by the fuzz target of the AEDAT reader: stream names and sizes that are no int.
TEST(WrittenAedat4, HeaderNumbersThatAreNoIntAreRefusedOrLeftUnknown) {
  EDS_REQUIRE_AVAILABLE(flatbuffersAvailable(), "Debian python3-flatbuffers, python3-pil, lz4, zstd");
  const fs::path dir = test::tempDir("aedat_header");
  const auto header = [&](const std::string& name, const std::string& xml) {
    const fs::path f = dir / name;
    const std::string cmd = "/usr/bin/python3 " EDS_SOURCE_DIR "/tests/tools/write_aedat4.py --header-only " +
                            f.string() + " '" + xml + "'";
    EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
    return f;
  };
  const fs::path huge =
      header("huge.aedat4", R"(<node name="99999999999"><attr key="typeIdentifier">EVTS</attr></node>)");
  try {
    scanAedat4(huge);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(huge.string()), std::string::npos) << what;
    EXPECT_NE(what.find("byte 18: the header describes no streams"), std::string::npos) << what;
  }
  const fs::path size =
      header("size.aedat4", R"(<node name="0"><attr key="typeIdentifier">EVTS</attr>)"
                            R"(<attr key="sizeX">4294967296</attr><attr key="sizeY">-3</attr></node>)");
  const Aedat4Counts c = scanAedat4(size);
  EXPECT_EQ(c.width, 0);  // unknown, as when absent
  EXPECT_EQ(c.height, 0);
  EXPECT_EQ(c.events, 0u);
}

}  // namespace
}  // namespace eds
