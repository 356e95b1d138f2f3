#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "core/error.hpp"
#include "io/kalibr.hpp"

namespace eds {
namespace {

namespace fs = std::filesystem;

class KalibrTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("eds_kalibr_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string write(const std::string& name, const std::string& text) const {
    const std::string path = (dir_ / name).string();
    std::ofstream(path) << text;
    return path;
  }
  // Expects an InputError naming the file, with `part` in the message and, when line > 0, that
  // line.
  static void expectError(const std::string& path, const std::string& part, std::size_t line = 0,
                          const std::string& camera = "cam0") {
    try {
      readKalibrCamera(path, camera);
      ADD_FAILURE() << "no error for " << part;
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_EQ(e.file(), path);
      EXPECT_NE(msg.find(path), std::string::npos) << msg;
      EXPECT_NE(msg.find(part), std::string::npos) << msg;
      if (line > 0) EXPECT_EQ(e.line(), line) << msg;
    }
  }

  fs::path dir_;
};

// Laid out as Kalibr writes it (two DAVIS cameras of a stereo rig).
constexpr const char* kCamchain = R"(cam0:
  T_cam_imu:
  - [0.9999, -0.0094, 0.0102, 0.0021]
  - [0.0094, 0.9999, -0.0006, -0.0003]
  - [-0.0102, 0.0005, 0.9999, -0.0315]
  - [0.0, 0.0, 0.0, 1.0]
  cam_overlaps: [1]
  camera_model: pinhole
  distortion_coeffs: [-0.3367, 0.1149, -0.00034, 0.00051]
  distortion_model: radtan
  intrinsics: [226.38, 226.15, 173.64, 133.73]
  resolution: [346, 260]
  rostopic: /davis/left/image_raw
cam1:
  T_cn_cnm1:
  - [0.99997, 0.00353, -0.00659, -0.05999]
  - [-0.00352, 0.99999, 0.00175, 0.00020]
  - [0.00660, -0.00173, 0.99998, 0.00036]
  - [0.0, 0.0, 0.0, 1.0]
  camera_model: pinhole
  distortion_coeffs: [-0.048, 0.0093, -0.0035, 0.0005]
  distortion_model: equidistant
  intrinsics: [226.0, 225.9, 174.5, 131.2]
  resolution: [346, 260]
  rostopic: /davis/right/image_raw
)";

TEST_F(KalibrTest, ReadsRadtanCamera) {
  const std::string path = write("camchain.yaml", kCamchain);
  const KalibrCamera cam = readKalibrCamera(path);
  EXPECT_EQ(cam.name, "cam0");
  EXPECT_EQ(cam.width, 346);
  EXPECT_EQ(cam.height, 260);
  EXPECT_DOUBLE_EQ(cam.fx, 226.38);
  EXPECT_DOUBLE_EQ(cam.fy, 226.15);
  EXPECT_DOUBLE_EQ(cam.cx, 173.64);
  EXPECT_DOUBLE_EQ(cam.cy, 133.73);
  EXPECT_EQ(cam.distortion_model, "radtan");
  EXPECT_EQ(cam.distortion_coeffs, (std::vector<double>{-0.3367, 0.1149, -0.00034, 0.00051}));
  EXPECT_FALSE(cam.T_cn_cnm1.has_value());
  ASSERT_TRUE(cam.T_cam_imu.has_value());
  EXPECT_DOUBLE_EQ((*cam.T_cam_imu)(2, 3), -0.0315);
  EXPECT_DOUBLE_EQ((*cam.T_cam_imu)(0, 1), -0.0094);  // rows are rows, not columns
}

TEST_F(KalibrTest, ReadsEquidistantCameraAndChain) {
  const std::string path = write("camchain.yaml", kCamchain);
  const KalibrCamera cam = readKalibrCamera(path, "cam1");
  EXPECT_EQ(cam.distortion_model, "equidistant");
  EXPECT_EQ(cam.distortion_coeffs, (std::vector<double>{-0.048, 0.0093, -0.0035, 0.0005}));
  EXPECT_DOUBLE_EQ(cam.cx, 174.5);
  ASSERT_TRUE(cam.T_cn_cnm1.has_value());
  EXPECT_DOUBLE_EQ((*cam.T_cn_cnm1)(0, 3), -0.05999);
  EXPECT_DOUBLE_EQ((*cam.T_cn_cnm1)(3, 3), 1.0);
  EXPECT_FALSE(cam.T_cam_imu.has_value());

  const auto all = readKalibrCamchain(path);
  ASSERT_EQ(all.size(), 2u);
  EXPECT_EQ(all[0].name, "cam0");
  EXPECT_EQ(all[1].name, "cam1");
}

TEST_F(KalibrTest, RadtanWithK3) {
  const std::string path = write("k3.yaml", R"(cam0:
  camera_model: pinhole
  intrinsics: [300, 301, 160.5, 120.5]
  distortion_model: radtan
  distortion_coeffs: [0.1, -0.2, 0.001, 0.002, 0.05]
  resolution: [320, 240]
)");
  const KalibrCamera cam = readKalibrCamera(path);
  ASSERT_EQ(cam.distortion_coeffs.size(), 5u);
  EXPECT_DOUBLE_EQ(cam.distortion_coeffs[4], 0.05);
}

TEST_F(KalibrTest, MissingFile) { expectError((dir_ / "absent.yaml").string(), "does not exist"); }

TEST_F(KalibrTest, MalformedYamlReportsLine) {
  const std::string path = write("bad.yaml", "cam0:\n  intrinsics: [1, 2, 3, 4\n  resolution: [3\n");
  expectError(path, "malformed YAML");
  const std::string extra =
      write("extra.yaml", "cam0:\n  camera_model: pinhole\n  intrinsics: [1, 2, 3, 4]]\n");
  expectError(extra, "malformed YAML", 3);
}

TEST_F(KalibrTest, MissingKeyOrCamera) {
  const std::string path = write("nokey.yaml", R"(cam0:
  camera_model: pinhole
  distortion_model: radtan
  distortion_coeffs: [0, 0, 0, 0]
  resolution: [320, 240]
)");
  expectError(path, "cam0: missing key 'intrinsics'");
  expectError(write("cam.yaml", kCamchain), "no camera 'cam7'", 0, "cam7");
}

TEST_F(KalibrTest, NaNAndNonNumbers) {
  const std::string nan = write("nan.yaml", R"(cam0:
  camera_model: pinhole
  intrinsics: [300, .nan, 160, 120]
  distortion_model: radtan
  distortion_coeffs: [0, 0, 0, 0]
  resolution: [320, 240]
)");
  expectError(nan, "intrinsics[1] is not finite", 3);
  const std::string word = write("word.yaml", R"(cam0:
  camera_model: pinhole
  intrinsics: [300, 300, 160, 120]
  distortion_model: radtan
  distortion_coeffs: [0, zero, 0, 0]
  resolution: [320, 240]
)");
  expectError(word, "'zero' is not a number", 5);
}

TEST_F(KalibrTest, WrongCoefficientCount) {
  const std::string radtan = write("radtan.yaml", R"(cam0:
  camera_model: pinhole
  intrinsics: [300, 300, 160, 120]
  distortion_model: radtan
  distortion_coeffs: [0.1, 0.2, 0.3]
  resolution: [320, 240]
)");
  expectError(radtan, "radtan needs 4 or 5 distortion_coeffs", 5);
  const std::string equi = write("equi.yaml", R"(cam0:
  camera_model: pinhole
  intrinsics: [300, 300, 160, 120]
  distortion_model: equidistant
  distortion_coeffs: [0.1, 0.2, 0.3, 0.4, 0.5]
  resolution: [320, 240]
)");
  expectError(equi, "equidistant needs 4", 5);
  const std::string intr = write("intr.yaml", R"(cam0:
  camera_model: pinhole
  intrinsics: [300, 300, 160]
  distortion_model: radtan
  distortion_coeffs: [0, 0, 0, 0]
  resolution: [320, 240]
)");
  expectError(intr, "intrinsics must have 4 values", 3);
}

TEST_F(KalibrTest, UnknownModels) {
  const std::string dist = write("dist.yaml", R"(cam0:
  camera_model: pinhole
  intrinsics: [300, 300, 160, 120]
  distortion_model: fisheye62
  distortion_coeffs: [0, 0, 0, 0]
  resolution: [320, 240]
)");
  expectError(dist, "unknown distortion_model 'fisheye62'", 4);
  const std::string cam = write("omni.yaml", R"(cam0:
  camera_model: omni
  intrinsics: [0.8, 300, 300, 160, 120]
  distortion_model: radtan
  distortion_coeffs: [0, 0, 0, 0]
  resolution: [320, 240]
)");
  expectError(cam, "unsupported camera_model 'omni'", 2);
}

TEST_F(KalibrTest, BadTransformAndResolution) {
  const std::string tf = write("tf.yaml", R"(cam0:
  camera_model: pinhole
  intrinsics: [300, 300, 160, 120]
  distortion_model: radtan
  distortion_coeffs: [0, 0, 0, 0]
  resolution: [320, 240]
  T_cam_imu:
  - [1, 0, 0, 0]
  - [0, 1, 0, 0]
  - [0, 0, 1, 0]
)");
  expectError(tf, "T_cam_imu must have 4 rows", 8);
  const std::string res = write("res.yaml", R"(cam0:
  camera_model: pinhole
  intrinsics: [300, 300, 160, 120]
  distortion_model: radtan
  distortion_coeffs: [0, 0, 0, 0]
  resolution: [320, -240]
)");
  expectError(res, "resolution height must be positive", 6);
  expectError(write("empty.yaml", ""), "not a Kalibr camchain");
}

}  // namespace
}  // namespace eds
