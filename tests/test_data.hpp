#pragma once
// Locating ../shared/data for tests. Tests that need it skip when it is absent (a user's clone), but
// fail when EDS_REQUIRE_DATA is set (CI exports it), so that a missing input cannot pass as a skip.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <system_error>
#include <vector>

namespace eds::test {

// True when every input a test needs must be present: EDS_REQUIRE_DATA set to anything but "0".
inline bool dataRequired() {
  const char* env = std::getenv("EDS_REQUIRE_DATA");
  return env != nullptr && std::string(env) != "0" && std::string(env) != "";
}

inline std::filesystem::path sharedDataDir() {
  if (const char* env = std::getenv("EDS_SHARED_DATA")) return env;
  return std::filesystem::path(EDS_SOURCE_DIR) / ".." / "shared" / "data";
}

// The whole content of a file (empty when it cannot be read).
inline std::string fileText(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
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

// Skips (or fails under EDS_REQUIRE_DATA) the current test when `what` is unavailable: the one place
// where a test may give up for want of an input (shared data, a built program, an HDF5 plugin).
#define EDS_REQUIRE_AVAILABLE(available, what)                                               \
  if (!(available)) {                                                                        \
    if (eds::test::dataRequired()) FAIL() << "required input missing: " << (what);           \
    GTEST_SKIP() << "input not found: " << (what) << " (set EDS_SHARED_DATA for ../shared)"; \
  }

// Sets `var` to the path of the shared data item `rel`, or skips / fails as EDS_REQUIRE_AVAILABLE.
#define EDS_REQUIRE_SHARED(var, rel)                                    \
  const std::filesystem::path var = eds::test::sharedDataDir() / (rel); \
  EDS_REQUIRE_AVAILABLE(std::filesystem::exists(var), var)
