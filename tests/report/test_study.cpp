// `eds study`: a small depth-noise study through the program, checked for its runs, its numbers and
// its page (a box per level in both plots, the medians table).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "report/study_report.hpp"
#include "test_data.hpp"

namespace eds {
namespace {

namespace fs = std::filesystem;

TEST(Study, DepthNoiseRunsEveryLevelOnEverySeedAndDrawsABoxForEach) {
  const fs::path eds = fs::path(EDS_BINARY_DIR) / "eds";
  EDS_REQUIRE_AVAILABLE(fs::exists(eds), "the eds program");
  const fs::path out = test::tempDir("study");
  const std::string cmd = eds.string() +
                          " study depth-noise --levels 0.01 0.5 --seeds 4 5 --duration 1 --out " +
                          out.string() + " > " + (out / "log.txt").string() + " 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << test::fileText(out / "log.txt");
  std::ifstream in(out / "study.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  ASSERT_EQ(j["runs"].size(), 4u);  // 2 levels x 2 seeds, level-major
  EXPECT_EQ(j["runs"][0]["level"], 0.01);
  EXPECT_EQ(j["runs"][1]["level"], 0.01);
  EXPECT_EQ(j["runs"][2]["level"], 0.5);
  EXPECT_GT(j["median_scene_depth_m"].get<double>(), 3.0);  // building-like: several metres
  for (const auto& run : j["runs"]) {
    EXPECT_GT(run["coverage"].get<double>(), 0.9) << run.dump();
    EXPECT_EQ(run["trans_cm"].size(), run["rot_deg"].size());
    EXPECT_GT(run["trans_cm"].size(), 50u);
  }
  // With near-exact depth the tracker holds a few centimetres over metres of depth.
  EXPECT_LT(j["runs"][0]["ate_cm"].get<double>(), 4.0);
  EXPECT_LT(j["runs"][0]["rot_rmse_deg"].get<double>(), 0.5);
  EXPECT_FALSE(fs::exists(out / "sequences"));  // simulated sequences are removed
  const std::string html = test::fileText(out / "report.html");
  std::size_t boxes = 0;
  for (std::size_t at = html.find("<g class='box'"); at != std::string::npos;
       at = html.find("<g class='box'", at + 1))
    ++boxes;
  EXPECT_EQ(boxes, 4u);  // 2 levels in each of the two plots
  EXPECT_NE(html.find("<td>50 %</td>"), std::string::npos);
}

TEST(Study, ReportTableHasTheMediansOfEachLevel) {
  study::StudyResult r;
  r.kind = study::Kind::kContrastNoise;
  r.title = "contrast-threshold noise", r.level_label = "sigma_C";
  for (double level : {0.05, 0.25})
    for (int seed = 1; seed <= 3; ++seed) {
      study::StudyRun run;
      run.level = level, run.seed = static_cast<std::uint64_t>(seed);
      run.trans_cm = {level * 10 * seed, level * 20 * seed};
      run.rot_deg = {level, level};
      run.ate_cm = level * seed, run.coverage = 1;
      r.runs.push_back(run);
    }
  const std::string html = report::buildStudyReport(r);
  // sigma_C 0.25: pooled translation errors 2.5, 5, 5, 7.5, 10, 15 -> median 6.25; ATE median 0.5.
  EXPECT_NE(html.find("<td>0.25</td><td>3</td><td>6.250</td><td>0.250</td><td>0.500</td>"), std::string::npos)
      << html;
}

}  // namespace
}  // namespace eds
