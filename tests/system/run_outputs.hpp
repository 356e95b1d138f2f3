#pragma once
// What the push API's tests and the recording-format runs share: every event of a sequence, the
// deterministic configuration, and the byte-by-byte comparison of two runs' output folders.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "io/sequence.hpp"
#include "system/odometry.hpp"
#include "test_data.hpp"

namespace eds::test {

inline EventArray allEvents(const Sequence& seq) {
  EventArray ev;
  auto src = seq.openEvents();
  while (src->read(ev, 1 << 20) > 0) {
  }
  return ev;
}

inline OdometryConfig syncConfig() {
  OdometryConfig cfg;
  cfg.threaded_backend = false;  // deterministic
  return cfg;
}

// Every output file but summary.json and timings.json (wall times) compared byte by byte.
inline void expectSameOutputs(const std::filesystem::path& a, const std::filesystem::path& b) {
  for (const char* name : {"trajectory_frames.txt", "trajectory_frames_live.txt", "trajectory_events.txt",
                           "trajectory_events_live.txt", "keyframes.txt", "map.ply", "event_frames/index.txt",
                           "event_frames/ef_01_delta.png", "event_frames/ef_01_model.png"}) {
    const std::string ta = fileText(a / name), tb = fileText(b / name);
    EXPECT_FALSE(ta.empty()) << a / name;
    EXPECT_TRUE(ta == tb) << name << " differs between " << a << " and " << b;
  }
}

}  // namespace eds::test
