// Same seed, same bytes; different seed, different noise. Bad arguments give clear errors.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "core/error.hpp"
#include "sim/presets.hpp"
#include "sim/simulator.hpp"
#include "sim/writer.hpp"
#include "test_data.hpp"

namespace eds::sim {
namespace {

namespace fs = std::filesystem;

std::string slurp(const fs::path& f) {
  std::ifstream in(f, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

CameraModel camera() {
  CameraModel cam;
  cam.width = 120, cam.height = 90;
  cam.fx = cam.fy = 100;
  cam.cx = 59.5, cam.cy = 44.5;
  return cam;
}

std::string simulate(const fs::path& dir, std::uint64_t seed) {
  const Motion motion(handheldMotion(0.3, 7));  // same motion and scene: only the noise seed varies
  Scene scene = makePreset("desk", motion, 7);
  scene.loadTextures();
  SimConfig cfg;
  cfg.events.seed = seed;
  cfg.events.sigma_C = 0.03;
  cfg.events.noise_rate_hz = 0.5;
  cfg.events.hot_pixel_fraction = 0.001;
  cfg.events.refractory_s = 1e-4;
  cfg.fps = 10;
  {
    EcdWriter writer(dir, false, true);
    Simulator(scene, camera(), motion, cfg).run(motion.start(), motion.end(), writer);
    writer.finish();
  }
  return slurp(dir / "events.txt");
}

TEST(SimulatorDeterminism, SameSeedSameBytesDifferentSeedDifferentNoise) {
  const auto base = test::tempDir("sim_seed");
  const std::string a = simulate(base / "a", 11), b = simulate(base / "b", 11), c = simulate(base / "c", 12);
  ASSERT_GT(a.size(), 10000u);
  EXPECT_EQ(a, b);
  EXPECT_NE(a, c);
  EXPECT_EQ(slurp(base / "a" / "images" / "frame_00000002.png"),
            slurp(base / "c" / "images" / "frame_00000002.png"))
      << "frames do not depend on the event noise seed";
  // The noise changes the events but not their overall amount much.
  const double ratio = static_cast<double>(c.size()) / static_cast<double>(a.size());
  EXPECT_NEAR(ratio, 1.0, 0.1);
}

TEST(SimulatorArguments, BadValuesGiveClearErrors) {
  const Motion motion(handheldMotion(0.2, 1));
  EXPECT_THROW(makePreset("kitchen", motion, 1), std::invalid_argument);
  try {
    makePreset("kitchen", motion, 1);
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("room"), std::string::npos) << e.what();
  }
  EventSimConfig bad;
  bad.C_pos = 0;
  EXPECT_THROW(EventGenerator(10, 10, bad), std::invalid_argument);
  bad = {};
  bad.C_neg = -0.1;
  EXPECT_THROW(EventGenerator(10, 10, bad), std::invalid_argument);
  // A texture that cannot be read names its file.
  Scene scene;
  scene.texture_specs.push_back({"/nonexistent/texture.png", 0, 0, 0.0, 0.1, 0.9});
  try {
    scene.loadTextures();
    FAIL() << "no error for a missing texture";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/texture.png"), std::string::npos);
  }
  // A trajectory shorter than the requested window.
  Trajectory traj = handheldMotion(1.0, 1);
  EXPECT_THROW(cutTrajectory(traj, 0.5, 1.0, "traj.txt"), InputError);
}

TEST(SimulatorArguments, CommandLineReportsErrorsWithoutCrashing) {
  const fs::path eds = fs::path(EDS_BINARY_DIR) / "eds";
  EDS_REQUIRE_AVAILABLE(fs::exists(eds), eds);
  const auto dir = test::tempDir("sim_cli");
  const auto run = [&](const std::string& args) {
    const std::string cmd = eds.string() + " simulate " + args + " --out " + (dir / "o").string() + " > " +
                            (dir / "log").string() + " 2>&1";
    const int rc = std::system(cmd.c_str());
    return std::make_pair(rc, slurp(dir / "log"));
  };
  auto [rc1, log1] = run("--preset kitchen --duration 0.1");
  EXPECT_NE(rc1, 0);
  EXPECT_NE(log1.find("kitchen"), std::string::npos) << log1;
  auto [rc2, log2] = run("--C 0 --duration 0.1");
  EXPECT_NE(rc2, 0);
  EXPECT_NE(log2.find("--C"), std::string::npos) << log2;
  std::ofstream(dir / "short.txt") << "0 0 0 0 0 0 0 1\n0.5 0 0 0 0 0 0 1\n";
  auto [rc3, log3] = run("--trajectory " + (dir / "short.txt").string() + " --duration 2");
  EXPECT_NE(rc3, 0);
  EXPECT_NE(log3.find("short.txt"), std::string::npos) << log3;
  auto [rc4, log4] = run("--resolution 240by180 --duration 0.1");
  EXPECT_NE(rc4, 0);
  EXPECT_NE(log4.find("resolution"), std::string::npos) << log4;
}

}  // namespace
}  // namespace eds::sim
