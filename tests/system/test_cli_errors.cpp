// Bad options and bad parameter values given to the `eds` program: each must end with exit code 2 and
// a message that names what is wrong (and the file, where there is one), before any processing.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include "test_data.hpp"

namespace eds {
namespace {

namespace fs = std::filesystem;

struct Outcome {
  int code = -1;
  std::string output;  // stdout and stderr
};

Outcome runEds(const std::string& args) {
  const std::string cmd = (fs::path(EDS_BINARY_DIR) / "eds").string() + " " + args + " 2>&1";
  Outcome o;
  std::FILE* p = popen(cmd.c_str(), "r");
  if (p == nullptr) return o;
  char buf[4096];
  for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, p)) > 0;) o.output.append(buf, n);
  const int status = pclose(p);
  o.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return o;
}

class CliErrors : public ::testing::Test {
 protected:
  void SetUp() override {
    EDS_REQUIRE_AVAILABLE(fs::exists(fs::path(EDS_BINARY_DIR) / "eds"), "the eds program");
    out_ = test::tempDir("cli_errors");
  }
  // Expects exit code `code`, the message fragment, and no run output folder content.
  void expectError(const std::string& args, const std::string& fragment, int code = 2) {
    const Outcome o = runEds(args);
    EXPECT_EQ(o.code, code) << args << "\n" << o.output;
    EXPECT_NE(o.output.find(fragment), std::string::npos) << args << "\n" << o.output;
    EXPECT_FALSE(fs::exists(out_ / "run" / "summary.json")) << args;
  }
  std::string esim() const { return (test::sharedDataDir() / "esim_poster6dof_planar").string(); }
  std::string runOut() const { return " --out " + (out_ / "run").string(); }
  fs::path out_;
};

TEST_F(CliErrors, SimulateFaultWindowsMustBeWellFormed) {
  const std::string sim = "simulate --duration 0.2 --out " + (out_ / "sim").string();
  expectError(sim + " --frame-gain 3:2:0.5", "--frame-gain '3:2:0.5': expected FROM:TO:VALUE with FROM < TO");
  expectError(sim + " --flicker abc", "--flicker 'abc': expected FROM:TO:VALUE");
  expectError(sim + " --noise-burst 0:0.1:-5", "--noise-burst '0:0.1:-5'");
  expectError(sim + " --event-gap 1:1", "--event-gap '1:1': expected FROM:TO with FROM < TO");
  expectError(sim + " --event-gap 0:0.1:7", "--event-gap '0:0.1:7'");
}

TEST_F(CliErrors, RealtimeOptionsMustBePositive) {
  EDS_REQUIRE_SHARED(dir, "esim_poster6dof_planar");
  const std::string positive = "speed, max_latency_s, min_frame_rate_hz and max_queued_frames must be > 0";
  expectError("run " + esim() + runOut() + " --realtime --speed 0", positive);
  expectError("run " + esim() + runOut() + " --realtime --max-latency -1", positive);
  expectError("run " + esim() + runOut() + " --realtime --min-frame-rate 0", positive);
}

TEST_F(CliErrors, ParameterValuesOutOfRange) {
  EDS_REQUIRE_SHARED(dir, "esim_poster6dof_planar");
  expectError("run " + esim() + runOut() + " --set flicker_filter.leak_ms=0",
              "leak_ms and score must be > 0");
  expectError("run " + esim() + runOut() + " --set frame_quality.max_saturated=1.5",
              "max_saturated and max_dark must be in (0, 1]");
  expectError("run " + esim() + runOut() + " --set frame_quality.history=0", "history >= 1");
  expectError("run " + esim() + runOut() + " --set frame_quality.history=many", "frame_quality.history");
  expectError("run " + esim() + runOut() + " --set no_such.parameter=1", "no_such.parameter");
  expectError("run " + esim() + runOut() + " --set recovery.gap_s=0",
              "recovery.gap_s and max_refinement must be > 0");
  expectError("run " + esim() + runOut() + " --set recovery.backfill_s=-1",
              "new_map_after_s and backfill_s >= 0");
  expectError("run " + esim() + runOut() + " --set recovery.relocalizer.min_inliers=3",
              "min_inliers >= 4 (a pose needs 4 points)");
  expectError("run " + esim() + runOut() + " --frame-rate -1", "must not be negative");
  expectError("run " + esim() + runOut() + " --set frame_tracker.min_step=-1e-5",
              "the frame trackers' min_step must not be negative");
  expectError("run " + esim() + runOut() + " --set bootstrap.tracker.min_gain=0",
              "the frame trackers' min_gain must be > 0");
  expectError("run " + esim() + runOut() + " --set frame_cv_min_distance=-0.01",
              "frame_cv_min_distance and the frame trackers' min_step must not be negative");
  expectError("run " + esim() + runOut() + " --set feature_start.max_rmse_ratio=1.5",
              "max_rmse_ratio must be in (0, 1]");
  expectError("run " + esim() + runOut() + " --set feature_start.min_interval_s=-1",
              "feature_start.min_interval_s must not be negative");
  expectError("run " + esim() + runOut() + " --set buffered_max_mb=0", "buffered_max_mb must be > 0");
  expectError("run " + esim() + runOut() + " --set buffered_before_reference_s=-1",
              "buffered_before_reference_s must not be negative");
  expectError("run " + esim() + runOut() + " --start 100", "no frame in the requested time range");
}

TEST_F(CliErrors, MissingFilesAreNamed) {
  EDS_REQUIRE_SHARED(dir, "esim_poster6dof_planar");
  const std::string missing = (out_ / "missing.yaml").string();
  expectError("run " + esim() + runOut() + " --config " + missing, missing);
  expectError("run " + esim() + runOut() + " --calib " + missing, missing);
  expectError("run " + (out_ / "no_sequence").string() + runOut(), (out_ / "no_sequence").string());
  expectError("info " + (out_ / "no_sequence").string(), (out_ / "no_sequence").string());
  expectError("eval --gt " + missing + " --est " + missing, missing);
  expectError("convert " + (out_ / "no_sequence").string() + " --out " + (out_ / "x.h5").string(),
              (out_ / "no_sequence").string());
  const fs::path aedat = test::sharedDataDir() / "real/aedat4/davis346_indoor.aedat4";
  if (fs::exists(aedat))  // a recording is a sequence for calibrate too; this one has no calibration
    expectError("calibrate " + aedat.string() + " --out " + (out_ / "cal").string(),
                "the recording holds no calibration: give one with --calib FILE");
  const std::string no_dir = (out_ / "no_dir" / "x.h5").string();
  expectError("convert " + esim() + " --out " + no_dir, "cannot create the HDF5 file");
  EXPECT_FALSE(fs::exists(no_dir));
}

TEST_F(CliErrors, TrackNeedsADepthSource) {
  EDS_REQUIRE_SHARED(dir, "esim_poster6dof_planar");
  expectError("track " + esim() + " --out " + (out_ / "track").string(),
              "eds track needs one of --depth-from-gt");
}

}  // namespace
}  // namespace eds
