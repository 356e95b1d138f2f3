// Reproduces rpg_trajectory_evaluation's own results on the reference trajectories in
// ../shared/data/eval_reference (DESIGN.md section 5): trans.rmse and rot.rmse to 1e-6 relative.
#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "eval/rpe.hpp"
#include "eval/rpg_folder.hpp"
#include "test_data.hpp"

namespace fs = std::filesystem;

namespace {

constexpr int kExpectedCases = 7;
constexpr double kRelTol = 1e-6;

fs::path sharedData() { return eds::test::sharedDataDir(); }

#define EDS_REQUIRE_REFERENCE_DATA(dir) EDS_REQUIRE_AVAILABLE(fs::is_directory(dir), dir)

struct Case {
  fs::path dir;
  fs::path stats_yaml;
  std::string align;
};

std::vector<Case> findCases(const fs::path& root) {
  std::vector<Case> cases;
  for (const auto& entry : fs::recursive_directory_iterator(root)) {
    if (!entry.is_directory() || entry.path().filename() != "traj_est") continue;
    if (entry.path().parent_path().filename() != "saved_results") continue;
    for (const auto& f : fs::directory_iterator(entry.path())) {
      const std::string name = f.path().filename().string();
      const std::string prefix = "absolute_err_statistics_", suffix = "_-1.yaml";
      if (name.size() <= prefix.size() + suffix.size() || name.rfind(prefix, 0) != 0 ||
          name.substr(name.size() - suffix.size()) != suffix)
        continue;
      const std::string align = name.substr(prefix.size(), name.size() - prefix.size() - suffix.size());
      cases.push_back({entry.path().parent_path().parent_path(), f.path(), align});
    }
  }
  std::sort(cases.begin(), cases.end(), [](const Case& a, const Case& b) { return a.dir < b.dir; });
  return cases;
}

void expectRel(double expected, double actual, const char* what) {
  EXPECT_NEAR(actual, expected, kRelTol * std::abs(expected)) << what;
}

}  // namespace

TEST(EvalReference, ReproducesRpgTrajectoryEvaluation) {
  const fs::path root = sharedData() / "eval_reference";
  EDS_REQUIRE_REFERENCE_DATA(root);
  int ran = 0;
  for (const Case& c : findCases(root)) {
    SCOPED_TRACE(c.dir.string());
    const eds::eval::EvalConfig cfg = eds::eval::loadRpgConfig(c.dir);
    EXPECT_EQ(eds::eval::toString(cfg.alignment), c.align);
    const eds::eval::AteResult r = eds::eval::evaluateRpgFolder(c.dir);
    const YAML::Node ref = YAML::LoadFile(c.stats_yaml.string());
    for (const char* key : {"trans", "rot"}) {
      const YAML::Node s = ref[key];
      const eds::eval::ErrorStats& got = std::string(key) == "trans" ? r.trans : r.rot;
      EXPECT_EQ(got.num_samples, s["num_samples"].as<std::size_t>()) << key;
      expectRel(s["rmse"].as<double>(), got.rmse, "rmse");
      expectRel(s["mean"].as<double>(), got.mean, "mean");
      expectRel(s["median"].as<double>(), got.median, "median");
      expectRel(s["std"].as<double>(), got.std, "std");
      expectRel(s["min"].as<double>(), got.min, "min");
      expectRel(s["max"].as<double>(), got.max, "max");
    }
    std::printf(
        "  %-40s %-6s n=%4zu trans.rmse %.12g (ref %.12g)  rot.rmse %.12g (ref %.12g)  "
        "coverage %.3f\n",
        fs::relative(c.dir, root).string().c_str(), c.align.c_str(), r.pairs.size(), r.trans.rmse,
        ref["trans"]["rmse"].as<double>(), r.rot.rmse, ref["rot"]["rmse"].as<double>(), r.coverage);
    ++ran;
  }
  EXPECT_EQ(ran, kExpectedCases);
}

// Relative errors: every relative_error_statistics_<distance>.yaml of every case, all six metrics.
TEST(EvalReference, ReproducesRelativeErrors) {
  const fs::path root = sharedData() / "eval_reference";
  EDS_REQUIRE_REFERENCE_DATA(root);
  int compared = 0;
  for (const Case& c : findCases(root)) {
    SCOPED_TRACE(c.dir.string());
    const eds::eval::EvalConfig cfg = eds::eval::loadRpgConfig(c.dir);
    const eds::Trajectory gt = eds::readTum(c.dir / eds::eval::kRpgGroundTruthFile, true);
    const eds::Trajectory est = eds::readTum(c.dir / eds::eval::kRpgEstimateFile, true);
    const eds::eval::AteResult ate = eds::eval::evaluateAte(est, gt, cfg);
    const std::vector<eds::eval::RpeResult> rpe = eds::eval::evaluateRpe(est, gt, ate, cfg);
    int found = 0;
    for (const eds::eval::RpeResult& r : rpe) {
      const fs::path yaml = c.stats_yaml.parent_path() /
                            ("relative_error_statistics_" + eds::eval::rpeDistanceTag(r.distance) + ".yaml");
      if (!fs::exists(yaml)) {
        ADD_FAILURE() << "no reference for distance " << r.distance << ": " << yaml;
        continue;
      }
      SCOPED_TRACE(yaml.filename().string());
      const YAML::Node ref = YAML::LoadFile(yaml.string());
      const std::pair<const char*, const eds::eval::ErrorStats*> metrics[] = {
          {"trans", &r.trans}, {"trans_perc", &r.trans_perc}, {"rot", &r.rot},
          {"yaw", &r.yaw},     {"gravity", &r.gravity},       {"rot_deg_per_m", &r.rot_deg_per_m}};
      for (const auto& [key, got] : metrics) {
        EXPECT_EQ(got->num_samples, ref[key]["num_samples"].as<std::size_t>()) << key;
        expectRel(ref[key]["rmse"].as<double>(), got->rmse, key);
        expectRel(ref[key]["median"].as<double>(), got->median, key);
        expectRel(ref[key]["max"].as<double>(), got->max, key);
      }
      std::printf("  %-40s rpe %6.2f m n=%4zu trans.rmse %.10g (ref %.10g)\n",
                  fs::relative(c.dir, root).string().c_str(), r.distance, r.trans.num_samples, r.trans.rmse,
                  ref["trans"]["rmse"].as<double>());
      ++found;
      ++compared;
    }
    EXPECT_EQ(found, 5);
  }
  EXPECT_EQ(compared, 5 * kExpectedCases);
}

// Runs the built program once on one reference folder and checks its JSON output.
TEST(EvalReference, ProgramWritesJson) {
  const fs::path dir = sharedData() / "eval_reference" / "mvsec" / "flying1";
  EDS_REQUIRE_REFERENCE_DATA(dir);
  const fs::path program = fs::path(EDS_BINARY_DIR) / "eds";
  EDS_REQUIRE_AVAILABLE(fs::exists(program), program);
  const fs::path out = fs::path(testing::TempDir()) / "eds_eval_flying1.json";
  fs::remove(out);
  const std::string cmd = "\"" + program.string() + "\" eval --dir \"" + dir.string() + "\" --json \"" +
                          out.string() + "\" > /dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  std::ifstream f(out);
  ASSERT_TRUE(f) << out;
  const nlohmann::json j = nlohmann::json::parse(f);
  const YAML::Node ref =
      YAML::LoadFile((dir / "saved_results/traj_est/absolute_err_statistics_sim3_-1.yaml").string());
  expectRel(ref["trans"]["rmse"].as<double>(), j.at("trans").at("rmse").get<double>(), "trans.rmse");
  expectRel(ref["rot"]["rmse"].as<double>(), j.at("rot").at("rmse").get<double>(), "rot.rmse");
  EXPECT_EQ(j.at("alignment").get<std::string>(), "sim3");
  EXPECT_EQ(j.at("matched_pairs").get<std::size_t>(), ref["trans"]["num_samples"].as<std::size_t>());
  EXPECT_GT(j.at("coverage").get<double>(), 0.0);
  EXPECT_LE(j.at("coverage").get<double>(), 1.0);
  fs::remove(out);
}
