// Bad input to the evaluator: every error is an InputError that names the offending file.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "core/error.hpp"
#include "eval/rpg_folder.hpp"

namespace fs = std::filesystem;
using namespace eds;
using namespace eds::eval;

namespace {

class EvalInputTest : public testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(testing::TempDir()) /
           ("eds_eval_" + std::string(testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p;
  }
  // Three poses along x at the given start time, 0.1 s apart.
  fs::path writeTraj(const std::string& name, double t0) {
    std::string text;
    for (int i = 0; i < 3; ++i)
      text += std::to_string(t0 + 0.1 * i) + " " + std::to_string(i) + " 0 " + std::to_string(i * i) +
              " 0 0 0 1\n";
    return write(name, text);
  }

  fs::path dir_;
};

// Expects an InputError whose message contains every given fragment.
template <class F>
void expectInputError(F&& f, std::initializer_list<std::string> fragments) {
  try {
    f();
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    for (const std::string& s : fragments)
      EXPECT_NE(std::string(e.what()).find(s), std::string::npos) << e.what();
  }
}

}  // namespace

TEST_F(EvalInputTest, MissingFile) {
  const fs::path gt = writeTraj("gt.txt", 1.0);
  expectInputError([&] { evaluateAteFiles(gt, dir_ / "nope.txt", EvalConfig{}); }, {"nope.txt"});
}

TEST_F(EvalInputTest, ZeroMatchesNamesBothFiles) {
  const fs::path gt = writeTraj("gt.txt", 1.0);
  const fs::path est = writeTraj("est.txt", 5.0);
  expectInputError([&] { evaluateAteFiles(gt, est, EvalConfig{}); }, {"gt.txt", "est.txt"});
  // Matches exist but none inside the window.
  EvalConfig cfg;
  cfg.window = TimeWindow{fromSeconds(3.0), fromSeconds(4.0)};
  expectInputError([&] { evaluateAteFiles(gt, gt, cfg); }, {"gt.txt", "window"});
}

TEST_F(EvalInputTest, FolderDefaultsToSim3OverAll) {
  writeTraj("stamped_groundtruth.txt", 1.0);
  writeTraj("stamped_traj_estimate.txt", 1.0);
  const EvalConfig cfg = loadRpgConfig(dir_);
  EXPECT_EQ(cfg.alignment, Alignment::kSim3);
  EXPECT_EQ(cfg.align_frames, -1);
  EXPECT_FALSE(cfg.window.has_value());
  const AteResult r = evaluateRpgFolder(dir_);
  EXPECT_EQ(r.pairs.size(), 3u);
  EXPECT_LT(r.trans.rmse, 1e-9);
}

TEST_F(EvalInputTest, ReadsFolderConfig) {
  write("eval_cfg.yaml", "align_type: posyaw\nalign_num_frames: 1\n");
  write("start_end_time.yaml", "start_time_sec: 1518195889.204480\nend_time_sec: 1518195999.5\n");
  const EvalConfig cfg = loadRpgConfig(dir_);
  EXPECT_EQ(cfg.alignment, Alignment::kPosYaw);
  EXPECT_EQ(cfg.align_frames, 1);
  ASSERT_TRUE(cfg.window.has_value());
  EXPECT_EQ(cfg.window->start, 1518195889204480000LL);  // exact: no double detour
  EXPECT_EQ(cfg.window->end, 1518195999500000000LL);
  // Only one bound given: the other side is open.
  write("start_end_time.yaml", "end_time_sec: 3\n");
  EXPECT_EQ(loadRpgConfig(dir_).window->end, 3 * kNsPerSec);
  EXPECT_TRUE(loadRpgConfig(dir_).window->contains(-1));
}

TEST_F(EvalInputTest, BadYamlNamesTheFile) {
  write("eval_cfg.yaml", "align_type: [sim3\n");
  expectInputError([&] { loadRpgConfig(dir_); }, {"eval_cfg.yaml"});
  write("eval_cfg.yaml", "align_type: affine\n");
  expectInputError([&] { loadRpgConfig(dir_); }, {"eval_cfg.yaml", "affine"});
  write("eval_cfg.yaml", "align_type: se3\nalign_num_frames: 0\n");
  expectInputError([&] { loadRpgConfig(dir_); }, {"eval_cfg.yaml", "align_num_frames"});
  write("eval_cfg.yaml", "align_type: se3\nalign_num_frames: many\n");
  expectInputError([&] { loadRpgConfig(dir_); }, {"eval_cfg.yaml"});
  fs::remove(dir_ / "eval_cfg.yaml");
  write("start_end_time.yaml", "start_time_sec: 5\nend_time_sec: 4\n");
  expectInputError([&] { loadRpgConfig(dir_); }, {"start_end_time.yaml"});
  write("start_end_time.yaml", "start_time_sec: soon\n");
  expectInputError([&] { loadRpgConfig(dir_); }, {"start_end_time.yaml", "soon"});
  expectInputError([&] { readTimeWindowYaml(dir_ / "absent.yaml"); }, {"absent.yaml"});
}
