// Stopping a run early: the driver's stop flag, and `eds run` under SIGINT (clean stop with complete
// outputs, exit code 130; a second signal exits at once), and an output folder that cannot be written.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "eval/ate.hpp"
#include "io/trajectory_io.hpp"
#include "system/odometry.hpp"
#include "system/odometry_config_io.hpp"
#include "test_data.hpp"

extern char** environ;

namespace eds {
namespace {

namespace fs = std::filesystem;

// No temporary ".NAME.partial-PID" file may be left anywhere in the output folder.
std::size_t hiddenFiles(const fs::path& dir) {
  std::size_t n = 0;
  for (const auto& e : fs::recursive_directory_iterator(dir))
    n += e.path().filename().string().rfind('.', 0) == 0;
  return n;
}

// Every output of a run is complete: parseable JSON and trajectories with the counts of the summary.
nlohmann::json expectCompleteOutputs(const fs::path& out) {
  const nlohmann::json j = nlohmann::json::parse(test::fileText(out / "summary.json"));
  EXPECT_EQ(readTum(out / "trajectory_frames.txt").size(), j["counts"]["poses"].get<std::size_t>());
  EXPECT_EQ(readTum(out / "trajectory_events.txt").size(), j["counts"]["event_poses"].get<std::size_t>());
  EXPECT_EQ(readTum(out / "keyframes.txt").size(), j["counts"]["keyframes"].get<std::size_t>());
  EXPECT_EQ(hiddenFiles(out), 0u);
  return j;
}

TEST(Interrupt, StopFlagEndsTheRunWithWhatWasComputed) {
  EDS_REQUIRE_SHARED(dir, "esim_poster6dof_planar");
  const Sequence seq(dir);
  OdometryConfig cfg = defaultOdometryConfig(seq.width(), seq.height());
  std::atomic<bool> stop{false};
  const OdometryResult r = runOdometry(
      seq, cfg, [&](double done_s, double) { stop = stop || done_s >= 2.0; }, &stop);
  ASSERT_TRUE(r.interrupted);
  const double stopped_s = toSeconds(r.interrupted_t - r.first_t);
  EXPECT_GE(stopped_s, 2.0);
  EXPECT_LE(stopped_s, 2.2);  // within a chunk of input of the request
  ASSERT_TRUE(r.initialized);
  ASSERT_GT(r.frames.size(), 30u);
  EXPECT_LE(r.frames.back().t, r.interrupted_t);
  EXPECT_LE(r.events.back().t, r.interrupted_t);
  const eval::AteResult a = eval::evaluateAte(r.events_refined, seq.groundTruth(), eval::EvalConfig{});
  std::printf("[ stopped at %.2f s ] %zu frame poses, %zu event poses, ATE %.3f cm\n", stopped_s,
              r.frames.size(), r.events.size(), a.trans.rmse * 100);
  EXPECT_LT(a.trans.rmse * 100, 1.0);
  const fs::path out = test::tempDir("interrupt_flag");
  writeOdometryOutputs(out, r, cfg);
  const nlohmann::json j = expectCompleteOutputs(out);
  EXPECT_TRUE(j["interrupted"].get<bool>());
  EXPECT_NEAR(j["interrupted_at_s"].get<double>(), toSeconds(r.interrupted_t), 1e-6);
}

// `eds run` as a child process, its stderr in a file.
struct Child {
  pid_t pid = -1;
  fs::path log;
};

Child spawnEds(const std::vector<std::string>& args, const fs::path& log) {
  const std::string program = (fs::path(EDS_BINARY_DIR) / "eds").string();
  std::vector<std::string> all{program};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  Child c;
  c.log = log;
  EXPECT_EQ(posix_spawn(&c.pid, program.c_str(), &actions, nullptr, argv.data(), environ), 0);
  posix_spawn_file_actions_destroy(&actions);
  return c;
}

// Waits until the run listens for signals (its "running on" line), up to a few minutes for sanitizers.
bool waitUntilRunning(const Child& c) {
  for (int i = 0; i < 3000; ++i) {
    if (test::fileText(c.log).find("running on") != std::string::npos) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return false;
}

int exitCode(pid_t pid) {
  int status = 0;
  EXPECT_EQ(waitpid(pid, &status, 0), pid);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
}

TEST(Interrupt, SigintMidRunLeavesCompleteOutputs) {
  EDS_REQUIRE_SHARED(dir, "esim_poster6dof_planar");
  const fs::path out = test::tempDir("interrupt_sigint");
  const Child c = spawnEds({"--log-level", "info", "run", dir.string(), "--out", out.string()}, out / "log");
  ASSERT_TRUE(waitUntilRunning(c)) << test::fileText(c.log);
  std::this_thread::sleep_for(std::chrono::milliseconds(800));
  kill(c.pid, SIGINT);
  EXPECT_EQ(exitCode(c.pid), 130) << test::fileText(c.log);
  EXPECT_NE(test::fileText(c.log).find("interrupted: finishing"), std::string::npos);
  const nlohmann::json j = expectCompleteOutputs(out);
  EXPECT_TRUE(fs::exists(out / "config_used.yaml"));
  EXPECT_TRUE(j["interrupted"].get<bool>());
  EXPECT_LT(j["interrupted_at_s"].get<double>(), 5.5);  // before the end of the 6 s sequence
}

TEST(Interrupt, SecondSignalExitsAtOnce) {
  EDS_REQUIRE_SHARED(dir, "esim_poster6dof_planar");
  const fs::path out = test::tempDir("interrupt_twice");
  const Child c = spawnEds({"--log-level", "info", "run", dir.string(), "--out", out.string()}, out / "log");
  ASSERT_TRUE(waitUntilRunning(c)) << test::fileText(c.log);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  // The second signal once the first is being handled (two pending signals would merge into one);
  // the clean finish it cuts short takes ~150 ms in release.
  kill(c.pid, SIGTERM);
  for (int i = 0; i < 5000 && test::fileText(c.log).find("interrupted: finishing") == std::string::npos; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  kill(c.pid, SIGTERM);
  EXPECT_EQ(exitCode(c.pid), 130);
  EXPECT_FALSE(fs::exists(out / "summary.json"));  // left before writing anything
  EXPECT_EQ(hiddenFiles(out), 0u);
}

TEST(Interrupt, UnwritableOutputFolderFailsBeforeProcessing) {
  EDS_REQUIRE_SHARED(dir, "esim_poster6dof_planar");
  const fs::path tmp = test::tempDir("interrupt_unwritable");
  std::ofstream(tmp / "a_file") << "x";
  for (const fs::path& out : {tmp / "a_file", tmp / "a_file" / "sub"}) {
    const Child c = spawnEds({"run", dir.string(), "--out", out.string()}, tmp / "log");
    const auto t0 = std::chrono::steady_clock::now();
    EXPECT_EQ(exitCode(c.pid), 2);
    const std::string log = test::fileText(tmp / "log");
    EXPECT_NE(log.find("error: " + out.string()), std::string::npos) << log;
    EXPECT_NE(log.find("output"), std::string::npos) << log;
    std::printf("[ --out %s ] %s", out.c_str(), log.c_str());
    // No odometry ran: a run of the sequence takes seconds, the refusal well under one even under ASan.
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 5.0);
  }
}

}  // namespace
}  // namespace eds
