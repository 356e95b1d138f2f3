// `eds report` end to end: a short simulated run written by the `eds` program, its report with and
// without ground truth and a comparison, checked for what they say (the accuracy `eds eval` computes,
// images, plots, no network reference) and opened in headless Chromium (tests/tools/check_report.py):
// no console error, plots drawn, images decoded, the 3D view drawn and redrawn when dragged.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>

#include "eval/ate.hpp"
#include "system/event_snapshots.hpp"
#include "test_data.hpp"

namespace eds {
namespace {

namespace fs = std::filesystem;

const fs::path kEds = fs::path(EDS_BINARY_DIR) / "eds";

int run(const std::string& cmd) { return std::system((cmd + " > /dev/null 2>&1").c_str()); }

// Runs `cmd`; on failure remembers it (with its output) in `failed`.
bool step(const std::string& cmd, std::string& failed) {
  if (!failed.empty()) return false;
  const fs::path log = fs::temp_directory_path() / "eds_test_report_step.log";
  if (std::system((cmd + " > " + log.string() + " 2>&1").c_str()) == 0) return true;
  failed = cmd + "\n" + test::fileText(log);
  return false;
}

// The simulated sequence and its two runs, written into `dir`.
void makeRuns(const fs::path& dir, std::string& failed) {
  const fs::path seq = dir / "seq";
  step(kEds.string() +
           " simulate --preset room --duration 3 --fps 20 --contrast-noise 0.03 --noise-rate 0.1 "
           "--seed 11 --out " +
           seq.string(),
       failed);
  step(kEds.string() + " run " + seq.string() + " --out " + (dir / "run").string() + " --report", failed);
  step(kEds.string() + " run " + seq.string() + " --frames-only --out " + (dir / "frames_only").string(),
       failed);
}

// The runs are made once per eds program and shared, read-only, by the suite's cases: ctest runs each
// case in its own process, and under the sanitizers the runs take a minute. The program's size and
// time stamp name the folder, so a rebuilt program makes new runs; the loser of a race uses the
// winner's folder.
fs::path sharedRuns(std::string& failed) {
  const fs::path cache = fs::path(EDS_BINARY_DIR) / "test_cache";
  const std::string key = "report_" + std::to_string(fs::last_write_time(kEds).time_since_epoch().count()) +
                          "_" + std::to_string(fs::file_size(kEds));
  if (fs::exists(cache / key / "complete")) return cache / key;
  const fs::path tmp = test::tempDir("report");
  makeRuns(tmp, failed);
  if (!failed.empty()) return tmp;
  std::ofstream(tmp / "complete") << "made by " << kEds.string() << "\n";
  std::error_code ec;
  fs::create_directories(cache, ec);
  for (const auto& old : fs::directory_iterator(cache, ec))  // an older program's runs
    if (old.path().filename().string().starts_with("report_") && old.path().filename() != key)
      fs::remove_all(old.path(), ec);
  fs::rename(tmp, cache / key, ec);  // fails when another process was first, or across file systems
  return fs::exists(cache / key / "complete") ? cache / key : tmp;
}

// Each case writes into its own folder; the runs are shared.
class Report : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    failed_ = new std::string;
    if (fs::exists(kEds)) runs_ = new fs::path(sharedRuns(*failed_));
  }
  void SetUp() override {
    EDS_REQUIRE_AVAILABLE(fs::exists(kEds), "the eds program");
    ASSERT_TRUE(failed_->empty()) << "failed: " << *failed_;
    out_ = test::tempDir("report_out");
  }
  static inline fs::path* runs_ = nullptr;
  static inline std::string* failed_ = nullptr;
  fs::path out_;
};

std::string reportOf(const std::string& args, const fs::path& out) {
  fs::remove(out);
  EXPECT_EQ(run(kEds.string() + " report " + args + " --out " + out.string()), 0) << args;
  return test::fileText(out);
}

TEST_F(Report, RunReportStatesTheAccuracyEdsEvalComputes) {
  const fs::path run_dir = *runs_ / "run";
  const std::string html = test::fileText(run_dir / "report.html");  // written by `eds run --report`
  ASSERT_FALSE(html.empty());
  const eval::AteResult ate = eval::evaluateAteFiles(run_dir / "groundtruth.txt",
                                                     run_dir / "trajectory_events.txt", eval::EvalConfig{});
  char ate_cm[32];
  std::snprintf(ate_cm, sizeof ate_cm, "<td>%.3f</td>", 100 * ate.trans.rmse);
  EXPECT_NE(html.find(std::string("<td>event-rate poses</td>")), std::string::npos);
  EXPECT_NE(html.find(ate_cm), std::string::npos) << "ATE " << ate_cm;
  EXPECT_LT(ate.trans.rmse, 0.02);  // the run itself is sound
  // Images: 2 per keyframe shown and 2 per event frame shown, all inlined.
  const auto count = [&](const std::string& what) {
    std::size_t n = 0;
    for (std::size_t at = html.find(what); at != std::string::npos; at = html.find(what, at + 1)) ++n;
    return n;
  };
  EXPECT_GE(count("<img "), 8u);
  EXPECT_EQ(count("<img "), count("src='data:image/"));
  EXPECT_FALSE(std::regex_search(html, std::regex("(src|href)=['\"](https?:)?//")));
  EXPECT_GE(readEventSnapshots(run_dir).size(), 2u);
  EXPECT_LT(html.size(), 5u << 20);
}

TEST_F(Report, WithoutGroundTruthTheReportSaysSoAndDrawsTheEstimate) {
  fs::copy(*runs_ / "frames_only", out_ / "frames_only", fs::copy_options::recursive);
  fs::remove(out_ / "frames_only" / "groundtruth.txt");
  const std::string html = reportOf((out_ / "frames_only").string(), out_ / "no_gt.html");
  EXPECT_NE(html.find("No ground truth"), std::string::npos);
  EXPECT_EQ(html.find("ATE RMSE"), std::string::npos);
  EXPECT_NE(html.find("data-label='frame poses'"), std::string::npos);
  EXPECT_EQ(html.find("Event frames and the model"), std::string::npos);  // frames only: none
}

TEST_F(Report, CompareHasOneRowPerRunWithItsOwnAccuracy) {
  const fs::path gt = *runs_ / "seq" / "groundtruth.txt";
  const std::string html =
      reportOf("--compare " + (*runs_ / "run").string() + " " + (*runs_ / "frames_only").string() + " " +
                   (*runs_ / "frames_only" / "trajectory_frames.txt").string() + " --gt " + gt.string(),
               out_ / "compare.html");
  for (const char* name : {"<td>run</td>", "<td>frames_only</td>", "<td>trajectory_frames.txt</td>"})
    EXPECT_NE(html.find(name), std::string::npos) << name;
  const eval::AteResult fo =
      eval::evaluateAteFiles(gt, *runs_ / "frames_only" / "trajectory_frames.txt", eval::EvalConfig{});
  char cm[32];
  std::snprintf(cm, sizeof cm, "<td>%.3f</td>", 100 * fo.trans.rmse);
  EXPECT_NE(html.find(cm), std::string::npos);
}

TEST_F(Report, BadInputsAreNamed) {
  const std::string out = (out_ / "bad.html").string();
  EXPECT_NE(run(kEds.string() + " report " + (*runs_ / "seq").string() + " --out " + out), 0);  // not a run
  EXPECT_NE(run(kEds.string() + " report " + (*runs_ / "run").string() + " " +
                (*runs_ / "frames_only").string() + " --out " + out),
            0);  // several runs without --compare
  EXPECT_FALSE(fs::exists(out));
}

bool browserAvailable() {
  return fs::exists("/usr/bin/chromium") && fs::exists("/usr/bin/chromedriver") &&
         std::system("/usr/bin/python3 -c 'import selenium' > /dev/null 2>&1") == 0;
}

nlohmann::json openInBrowser(const fs::path& html, const fs::path& shot) {
  const std::string cmd = "/usr/bin/python3 " EDS_SOURCE_DIR "/tests/tools/check_report.py " + html.string() +
                          " " + shot.string() + " 2>/dev/null";
  std::FILE* p = popen(cmd.c_str(), "r");
  std::string out;
  char buf[4096];
  for (std::size_t n; p && (n = std::fread(buf, 1, sizeof buf, p)) > 0;) out.append(buf, n);
  if (p) pclose(p);
  return nlohmann::json::parse(out, nullptr, /*allow_exceptions=*/false);
}

TEST_F(Report, OpensInChromiumWithoutErrorsAndDrawsEverything) {
  EDS_REQUIRE_AVAILABLE(browserAvailable(), "Debian chromium, chromium-driver and python3-selenium");
  const char* keep = std::getenv("EDS_REPORT_SCREENSHOTS");  // a folder to keep the screenshots in
  const fs::path shots = keep ? fs::path(keep) : out_;
  fs::create_directories(shots);
  fs::copy(*runs_ / "frames_only", out_ / "frames_only", fs::copy_options::recursive);
  fs::remove(out_ / "frames_only" / "groundtruth.txt");
  reportOf((out_ / "frames_only").string(), out_ / "no_gt.html");
  reportOf("--compare " + (*runs_ / "run").string() + " " + (*runs_ / "frames_only").string() + " --gt " +
               (*runs_ / "seq" / "groundtruth.txt").string(),
           out_ / "compare.html");
  struct Page {
    fs::path html;
    int min_plots, min_images;
  };
  for (const Page& page : {Page{*runs_ / "run" / "report.html", 5, 8}, Page{out_ / "no_gt.html", 3, 4},
                           Page{out_ / "compare.html", 4, 0}}) {
    const fs::path shot =
        shots / (page.html.parent_path().filename().string() + "_" + page.html.stem().string() + ".png");
    const nlohmann::json s = openInBrowser(page.html, shot);
    ASSERT_TRUE(s.is_object()) << "check_report.py gave no result for " << page.html;
    SCOPED_TRACE(page.html.string() + ": " + s.dump());
    EXPECT_TRUE(s["console_errors"].empty());
    EXPECT_GE(s["plots"].get<int>(), page.min_plots);
    EXPECT_GE(s["series"].get<int>(), 2);
    EXPECT_GE(s["images"].get<int>(), page.min_images);
    EXPECT_EQ(s["images_decoded"], s["images"]);
    EXPECT_TRUE(s["canvas"].get<bool>());
    EXPECT_GT(s["points_drawn"].get<int>(), 100);
    EXPECT_GT(s["canvas_lit_pixels"].get<int>(), 500);
    EXPECT_NE(s["canvas_hash"], s["canvas_hash_after_drag"]);  // orbiting redraws
    EXPECT_EQ(s["external"].get<int>(), 0);
    EXPECT_GT(fs::file_size(shot), 20000u);
  }
}

}  // namespace
}  // namespace eds
