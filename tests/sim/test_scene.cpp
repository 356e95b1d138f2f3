// Scene description: YAML round trip and validation, the shared ESIM scene.txt, texture loading and
// the procedural textures.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "core/error.hpp"
#include "sim/scene.hpp"
#include "sim/textures.hpp"
#include "test_data.hpp"

namespace eds::sim {
namespace {

Scene sampleScene(const std::filesystem::path& image) {
  Scene s;
  s.mirror_outside = true;
  s.texture_specs.push_back({"procedural:noise:42", 256, 128, 0.75, 0.05, 0.95});
  s.texture_specs.push_back({image.string(), 0, 0, 0.0, 0.1, 0.9});
  Plane a;
  a.name = "back wall";
  a.center = Vec3(0.1, -0.2, 5.123456789012345);
  const double c = std::cos(0.3), sn = std::sin(0.3);
  a.u = Vec3(c, sn, 0);
  a.v = Vec3(-sn, c, 0);
  a.size_u = 4.5, a.size_v = 2.75;
  a.texel = 0.0123;
  a.texture = 1;
  Plane b;
  b.name = "floor";
  b.center = Vec3(1e-7, 1.3, 2);
  b.u = Vec3::UnitX();
  b.v = Vec3::UnitZ();
  b.size_u = 3, b.size_v = 8;
  b.texel = 0.02;
  b.texture = 0;
  s.planes = {a, b};
  return s;
}

TEST(SceneYaml, RoundTripsEveryField) {
  const auto dir = test::tempDir("scene_yaml_rt");
  const Scene s = sampleScene(dir / "tex.png");
  writeSceneYaml(dir / "scene.yaml", s);
  const Scene r = readSceneYaml(dir / "scene.yaml");
  EXPECT_EQ(r.mirror_outside, s.mirror_outside);
  ASSERT_EQ(r.texture_specs.size(), s.texture_specs.size());
  for (std::size_t i = 0; i < s.texture_specs.size(); ++i) {
    const TextureSpec &a = s.texture_specs[i], &b = r.texture_specs[i];
    EXPECT_EQ(a.source, b.source);
    EXPECT_EQ(a.width, b.width);
    EXPECT_EQ(a.height, b.height);
    EXPECT_EQ(a.blur_sigma, b.blur_sigma);
    EXPECT_EQ(a.offset, b.offset);
    EXPECT_EQ(a.gain, b.gain);
  }
  ASSERT_EQ(r.planes.size(), s.planes.size());
  for (std::size_t i = 0; i < s.planes.size(); ++i) {
    const Plane &a = s.planes[i], &b = r.planes[i];
    EXPECT_EQ(a.name, b.name);
    EXPECT_EQ(a.center, b.center);  // exact: shortest round-trip decimals
    EXPECT_EQ(a.u, b.u);
    EXPECT_EQ(a.v, b.v);
    EXPECT_EQ(a.size_u, b.size_u);
    EXPECT_EQ(a.size_v, b.size_v);
    EXPECT_EQ(a.texel, b.texel);
    EXPECT_EQ(a.texture, b.texture);
  }
}

TEST(SceneYaml, RelativeTexturePathsAreRelativeToTheFile) {
  const auto dir = test::tempDir("scene_yaml_rel");
  std::filesystem::create_directories(dir / "sub" / "tex");
  cv::imwrite((dir / "sub" / "tex" / "t.png").string(), cv::Mat(20, 30, CV_8U, cv::Scalar(255)));
  std::ofstream(dir / "sub" / "s.yaml")
      << "textures:\n  - source: tex/t.png\n"
         "planes:\n  - center: [0, 0, 1]\n    u: [1, 0, 0]\n    v: [0, 1, 0]\n"
         "    size: [1, 1]\n    texel: 0.01\n    texture: 0\n";
  Scene s = readSceneYaml(dir / "sub" / "s.yaml");
  EXPECT_EQ(std::filesystem::path(s.texture_specs[0].source),
            (dir / "sub" / "tex" / "t.png").lexically_normal());
  EXPECT_EQ(s.planes[0].name, "plane0");
  EXPECT_FALSE(s.mirror_outside);
  s.loadTextures();
  ASSERT_EQ(s.textures.size(), 1u);
  EXPECT_EQ(s.textures[0].cols, 30);
  EXPECT_NEAR(s.textures[0].at<float>(3, 3), 1.0f, 1e-6);  // 0.1 + 0.9 * 255 / 255
}

// Writes `text` as a scene file and expects an InputError naming the file and line `line` (0: any).
void expectBad(const std::string& name, const std::string& text, int line, const std::string& what) {
  const auto dir = test::tempDir("scene_yaml_bad");
  const auto file = dir / (name + ".yaml");
  std::ofstream(file) << text;
  try {
    readSceneYaml(file);
    FAIL() << name << ": no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    if (line > 0) EXPECT_EQ(e.line(), static_cast<std::size_t>(line)) << e.what();
  }
}

const char* kTex = "textures:\n  - source: procedural:checker:1\n";  // lines 1-2
std::string plane(const std::string& center, const std::string& u, const std::string& v,
                  const std::string& tex) {
  return "planes:\n  - name: p\n    center: " + center + "\n    u: " + u + "\n    v: " + v +
         "\n    size: [1, 2]\n    texel: 0.01\n    texture: " + tex + "\n";  // lines 3-10
}

TEST(SceneYaml, BadInputNamesFileAndLine) {
  expectBad("missing_key",
            std::string(kTex) +
                "planes:\n  - center: [0, 0, 1]\n    u: [1, 0, 0]\n    v: [0, 1, 0]\n"
                "    texel: 0.01\n    texture: 0\n",
            4, "missing key 'size'");
  expectBad("no_planes", kTex, 0, "missing key 'planes'");
  expectBad("not_orthogonal", kTex + plane("[0, 0, 1]", "[1, 0, 0]", "[0.1, 1, 0]", "0"), 7, "orthonormal");
  expectBad("not_unit", kTex + plane("[0, 0, 1]", "[2, 0, 0]", "[0, 1, 0]", "0"), 7, "orthonormal");
  expectBad("bad_index", kTex + plane("[0, 0, 1]", "[1, 0, 0]", "[0, 1, 0]", "1"), 10, "out of range");
  expectBad("negative_index", kTex + plane("[0, 0, 1]", "[1, 0, 0]", "[0, 1, 0]", "-1"), 10, "out of range");
  expectBad("nan", kTex + plane("[0, .nan, 1]", "[1, 0, 0]", "[0, 1, 0]", "0"), 5, "finite");
  expectBad("nan_word", kTex + plane("[0, nan, 1]", "[1, 0, 0]", "[0, 1, 0]", "0"), 5, "number");
  expectBad("short_vec", kTex + plane("[0, 1]", "[1, 0, 0]", "[0, 1, 0]", "0"), 5, "list of 3");
  expectBad("typo", std::string(kTex) + "    gian: 2\n" + plane("[0, 0, 1]", "[1, 0, 0]", "[0, 1, 0]", "0"),
            3, "unknown key 'gian'");
  expectBad("bad_procedural",
            "textures:\n  - source: procedural:wood\n" + plane("[0,0,1]", "[1,0,0]", "[0,1,0]", "0"), 2,
            "unknown procedural");
  expectBad("syntax", "textures: [\n", 0, "");
  std::string neg_size = kTex + plane("[0, 0, 1]", "[1, 0, 0]", "[0, 1, 0]", "0");
  neg_size.replace(neg_size.find("[1, 2]"), 6, "[1, -2]");
  expectBad("neg_size", neg_size, 8, "size must be positive");
  EXPECT_THROW(readSceneYaml("/nonexistent/scene.yaml"), InputError);
}

TEST(SceneYaml, NearlyOrthonormalAxesAreCleanedUp) {
  const auto dir = test::tempDir("scene_yaml_ortho");
  std::ofstream(dir / "s.yaml") << kTex << plane("[0, 0, 1]", "[1.0004, 0, 0]", "[0.0005, 1, 0]", "0");
  const Scene s = readSceneYaml(dir / "s.yaml");
  EXPECT_NEAR(s.planes[0].u.norm(), 1.0, 1e-12);
  EXPECT_NEAR(s.planes[0].v.norm(), 1.0, 1e-12);
  EXPECT_NEAR(s.planes[0].u.dot(s.planes[0].v), 0.0, 1e-12);
}

TEST(EsimSceneTxt, ParsesTheSharedScene) {
  EDS_REQUIRE_SHARED(file, "esim_poster6dof_planar/scene.txt");
  EsimParams esim;
  const Scene s = readEsimSceneTxt(file, "/textures", &esim);
  ASSERT_EQ(s.planes.size(), 1u);
  ASSERT_EQ(s.texture_specs.size(), 1u);
  const Plane& p = s.planes[0];
  EXPECT_NEAR((p.center - Vec3(5.406730940, -0.637314007, 1.438078782)).norm(), 0, 1e-9);
  EXPECT_NEAR((p.u - Vec3(-0.081848617, -0.993286145, 0.081752301)).norm(), 0, 1e-6);
  EXPECT_NEAR((p.v - Vec3(-0.057310830, -0.077201047, -0.995367001)).norm(), 0, 1e-6);
  // The file's n points to the camera: -(u x v).
  EXPECT_NEAR((p.normal() + Vec3(-0.994995614, 0.086154705, 0.050607254)).norm(), 0, 1e-6);
  EXPECT_DOUBLE_EQ(p.texel, 0.0025);
  EXPECT_DOUBLE_EQ(p.size_u, 4.0);
  EXPECT_DOUBLE_EQ(p.size_v, 3.0);
  EXPECT_TRUE(s.mirror_outside);
  const TextureSpec& t = s.texture_specs[0];
  EXPECT_EQ(std::filesystem::path(t.source), std::filesystem::path("/textures/office.jpg"));
  EXPECT_EQ(t.width, 1600);
  EXPECT_EQ(t.height, 1200);
  EXPECT_DOUBLE_EQ(t.blur_sigma, 1.0);
  EXPECT_DOUBLE_EQ(t.offset, 0.1);
  EXPECT_DOUBLE_EQ(t.gain, 0.9);
  EXPECT_DOUBLE_EQ(esim.C_pos, 0.2);
  EXPECT_DOUBLE_EQ(esim.C_neg, 0.2);
  EXPECT_DOUBLE_EQ(esim.log_eps, 1e-3);
  EXPECT_DOUBLE_EQ(esim.render_hz, 1000);
}

TEST(EsimSceneTxt, LoadsTheSharedTexture) {
  EDS_REQUIRE_SHARED(file, "esim_poster6dof_planar/scene.txt");
  EDS_REQUIRE_SHARED(textures, "textures");
  Scene s = readEsimSceneTxt(file, textures);
  s.loadTextures();
  ASSERT_EQ(s.textures.size(), 1u);
  const cv::Mat& t = s.textures[0];
  EXPECT_EQ(t.type(), CV_32F);
  EXPECT_EQ(t.cols, 1600);
  EXPECT_EQ(t.rows, 1200);
  double lo, hi;
  cv::minMaxLoc(t, &lo, &hi);
  EXPECT_GE(lo, 0.1 - 1e-6);
  EXPECT_LE(hi, 1.0 + 1e-6);
}

TEST(EsimSceneTxt, BadFilesNameFileAndLine) {
  const auto dir = test::tempDir("esim_bad");
  const std::string good_tex = "texture t.png 16 12 0.01\n";
  auto expectLine = [&](const std::string& text, std::size_t line) {
    std::ofstream(dir / "scene.txt") << text;
    try {
      readEsimSceneTxt(dir / "scene.txt", dir);
      FAIL() << "no error for:\n" << text;
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), (dir / "scene.txt").string());
      EXPECT_EQ(e.line(), line) << e.what();
    }
  };
  expectLine("P0 0 0 1\nu 1 0 0\nv 0.1 1 0\n" + good_tex, 3);         // not orthogonal
  expectLine("P0 0 0 1\nn 1 0 0\nu 1 0 0\nv 0 1 0\n" + good_tex, 2);  // n is not +-u x v
  expectLine("P0 0 0 x\n", 1);
  expectLine("P0 0 0 1\nu 1 0 0\nv 0 1 0\ntexture t.png 16 12 -1\n", 4);
  expectLine("P0 0 0 1\nu 1 0 0\nv 0 1 0\n", 0);  // no texture
}

TEST(LoadTextures, ResizesBlursAndMapsIntensity) {
  const auto dir = test::tempDir("load_tex");
  cv::Mat img(40, 60, CV_8U, cv::Scalar(0));
  img(cv::Rect(0, 0, 30, 40)).setTo(255);
  cv::imwrite((dir / "half.png").string(), img);
  Scene s;
  s.texture_specs.push_back({"half.png", 30, 20, 0.0, 0.2, 0.5});
  s.texture_specs.push_back({"half.png", 30, 20, 2.0, 0.2, 0.5});
  s.texture_specs.push_back({"procedural:stripes:3", 64, 32, 0.0, 0.1, 0.9});
  s.loadTextures(dir);
  ASSERT_EQ(s.textures.size(), 3u);
  const cv::Mat& sharp = s.textures[0];
  EXPECT_EQ(sharp.size(), cv::Size(30, 20));
  EXPECT_NEAR(sharp.at<float>(10, 2), 0.7f, 1e-6);  // 0.2 + 0.5 * 255 / 255
  EXPECT_NEAR(sharp.at<float>(10, 27), 0.2f, 1e-6);
  const cv::Mat& blurred = s.textures[1];
  EXPECT_GT(blurred.at<float>(10, 15), 0.25f);  // the edge (columns 14 | 15) is smeared
  EXPECT_LT(blurred.at<float>(10, 14), 0.65f);
  EXPECT_EQ(s.textures[2].size(), cv::Size(64, 32));

  Scene bad;
  bad.texture_specs.push_back({"missing.png", 0, 0, 0.0, 0.1, 0.9});
  try {
    bad.loadTextures(dir);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("missing.png"), std::string::npos);
  }
  Scene bad_proc;
  bad_proc.texture_specs.push_back({"procedural:marble", 0, 0, 0.0, 0.1, 0.9});
  EXPECT_THROW(bad_proc.loadTextures(), InputError);
}

class Procedural : public ::testing::TestWithParam<std::string> {};

TEST_P(Procedural, DeterministicWithContrast) {
  const std::string name = GetParam();
  const auto t0 = std::chrono::steady_clock::now();
  const cv::Mat a = proceduralTexture(name, 1024, 1024, 7);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const cv::Mat b = proceduralTexture(name, 1024, 1024, 7);
  const cv::Mat c = proceduralTexture(name, 1024, 1024, 8);
  ASSERT_EQ(a.type(), CV_8U);
  ASSERT_EQ(a.size(), cv::Size(1024, 1024));
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0) << "same seed, different bytes";
  EXPECT_GT(cv::norm(a, c, cv::NORM_L1) / a.total(), 5.0) << "different seed, (nearly) same texture";
  cv::Scalar mean, sd;
  cv::meanStdDev(a, mean, sd);
  EXPECT_GT(sd[0], 40.0) << name << ": low contrast";
  EXPECT_GT(mean[0], 60.0);
  EXPECT_LT(mean[0], 195.0);
  // Generous bound: sanitizer builds are several times slower than release (~0.1 s for "mix").
  EXPECT_LT(seconds, 2.0) << name;
  RecordProperty("seconds", std::to_string(seconds));
  // Non-square sizes work too.
  EXPECT_EQ(proceduralTexture(name, 100, 37, 1).size(), cv::Size(100, 37));
}

INSTANTIATE_TEST_SUITE_P(All, Procedural,
                         ::testing::Values("noise", "checker", "bricks", "blobs", "stripes", "mix"));

TEST(ProceduralSource, Parses) {
  EXPECT_FALSE(parseProceduralSource("office.jpg"));
  const auto p = parseProceduralSource("procedural:blobs:123");
  ASSERT_TRUE(p);
  EXPECT_EQ(p->name, "blobs");
  EXPECT_EQ(p->seed, 123u);
  EXPECT_EQ(parseProceduralSource("procedural:mix")->seed, 0u);
  EXPECT_THROW(parseProceduralSource("procedural:mix:x1"), std::invalid_argument);
  EXPECT_THROW(parseProceduralSource("procedural:mix:-1"), std::invalid_argument);
  EXPECT_THROW(parseProceduralSource("procedural:wood"), std::invalid_argument);
  EXPECT_THROW(proceduralTexture("wood", 10, 10, 1), std::invalid_argument);
}

}  // namespace
}  // namespace eds::sim
