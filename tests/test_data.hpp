#pragma once
// Locating ../shared/data for tests. Tests that need it skip when it is absent (a user's clone),
// but fail in CI (env CI set), where it must be present.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

namespace eds::test {

inline std::filesystem::path sharedDataDir() {
  if (const char* env = std::getenv("EDS_SHARED_DATA")) return env;
  return std::filesystem::path(EDS_SOURCE_DIR) / ".." / "shared" / "data";
}

// A fresh, empty temporary folder for one test; removed when the test program exits (kept when
// EDS_KEEP_TEST_DIRS is set, to look at what a test wrote).
inline std::filesystem::path tempDir(const std::string& name) {
  struct Registry {
    std::vector<std::filesystem::path> dirs;
    ~Registry() {
      if (std::getenv("EDS_KEEP_TEST_DIRS")) return;
      std::error_code ec;  // best effort: a leftover folder is no reason to fail at exit
      for (const auto& d : dirs) std::filesystem::remove_all(d, ec);
    }
  };
  static Registry registry;
  const auto dir =
      std::filesystem::temp_directory_path() / ("eds_test_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  registry.dirs.push_back(dir);
  return dir;
}

}  // namespace eds::test

// Skips (or fails under CI) when the shared data item `rel` is absent; else sets `var` to its path.
#define EDS_REQUIRE_SHARED(var, rel)                                              \
  const std::filesystem::path var = eds::test::sharedDataDir() / (rel);           \
  if (!std::filesystem::exists(var)) {                                            \
    if (std::getenv("CI")) FAIL() << "shared data missing in CI: " << var;        \
    GTEST_SKIP() << "shared data not found: " << var << " (set EDS_SHARED_DATA)"; \
  }
