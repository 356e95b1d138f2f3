// Calibrations in the layouts other datasets publish (TUM-VIE's Basalt JSON, DSEC's cam_to_cam.yaml),
// written by Python's json and python3-yaml (tests/tools/write_calibrations.py), read by readCameraFile.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/error.hpp"
#include "io/sequence.hpp"
#include "test_data.hpp"

namespace eds {
namespace {

namespace fs = std::filesystem;

fs::path writtenCalibrations() {
  static const fs::path dir = [] {
    const fs::path out = test::tempDir("calibrations");
    const std::string cmd = "/usr/bin/python3 " EDS_SOURCE_DIR "/tests/tools/write_calibrations.py " + out.string();
    return std::system(cmd.c_str()) == 0 ? out : fs::path();
  }();
  return dir;
}

#define EDS_REQUIRE_CALIBRATIONS(dir)                                                              \
  EDS_REQUIRE_AVAILABLE(std::system("/usr/bin/python3 -c 'import yaml' > /dev/null 2>&1") == 0, \
                        "Debian python3-yaml");                                                    \
  const fs::path dir = writtenCalibrations();                                                      \
  ASSERT_FALSE(dir.empty()) << "tests/tools/write_calibrations.py failed"

TEST(CalibrationFiles, BasaltKannalaBrandtBecomesTheEquidistantModel) {
  EDS_REQUIRE_CALIBRATIONS(dir);
  const CameraModel c = readCameraFile(dir / "basalt_calib.json");
  EXPECT_EQ(c.distortion, Distortion::kEquidistant);
  EXPECT_EQ(c.width, 1280);
  EXPECT_EQ(c.height, 720);
  EXPECT_EQ(c.fx, 1049.5);
  EXPECT_EQ(c.fy, 1049.4);
  EXPECT_EQ(c.cx, 634.8);
  EXPECT_EQ(c.cy, 361.2);
  EXPECT_EQ(c.k[0], 0.0033);
  EXPECT_EQ(c.k[1], -0.0056);
  EXPECT_EQ(c.k[2], 0.002);
  EXPECT_EQ(c.k[3], -0.0004);
  const CameraModel second = readBasaltCalibration(dir / "basalt_calib.json", 1);
  EXPECT_EQ(second.distortion, Distortion::kNone);
  EXPECT_EQ(second.width, 640);
  EXPECT_EQ(second.fy, 701.0);
}

TEST(CalibrationFiles, DsecCamToCamGivesTheLeftEventCamera) {
  EDS_REQUIRE_CALIBRATIONS(dir);
  const CameraModel c = readCameraFile(dir / "cam_to_cam.yaml");
  EXPECT_EQ(c.distortion, Distortion::kRadTan);
  EXPECT_EQ(c.width, 640);
  EXPECT_EQ(c.height, 480);
  EXPECT_EQ(c.fx, 553.47);
  EXPECT_EQ(c.cy, 216.52);
  EXPECT_EQ(c.k[0], -0.0931);
  EXPECT_EQ(c.k[3], -0.000377);
}

TEST(CalibrationFiles, UnsupportedOrMalformedCalibrationsNameTheFile) {
  EDS_REQUIRE_CALIBRATIONS(dir);
  const auto expectError = [](const fs::path& f, const std::string& phrase) {
    try {
      readCameraFile(f);
      ADD_FAILURE() << "no error for " << f;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(f.string()), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(phrase), std::string::npos) << e.what();
    }
  };
  expectError(dir / "basalt_ds.json", "camera_type 'ds' is not supported");
  std::ofstream(dir / "broken.json") << "{\"value0\": {\"intrinsics\": [";
  expectError(dir / "broken.json", "malformed JSON");
  std::ofstream(dir / "other.json") << "{\"cameras\": []}";
  expectError(dir / "other.json", "not a Basalt calibration");
}

}  // namespace
}  // namespace eds
