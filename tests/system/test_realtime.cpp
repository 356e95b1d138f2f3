// `eds run --realtime`: the sequence fed on the wall clock by a producer thread. What holds on any
// machine, loaded or not, sanitizer or not: the input is paced by the clock, every event pose has its
// latency, a replay far faster than the processing sheds load (dropped chunks and frames, bounded
// queue) instead of falling behind, and a stop request ends the run. The accuracy at speeds 1 and 3 is
// a benchmark (docs/experiments.md), not a test.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>

#include "core/error.hpp"
#include "system/odometry.hpp"
#include "system/odometry_config_io.hpp"
#include "system/realtime_run.hpp"
#include "system/release_queue.hpp"
#include "test_data.hpp"

namespace eds {
namespace {

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

TEST(Realtime, PacedByTheClockWithALatencyPerEventPose) {
  EDS_REQUIRE_SHARED(dir, "esim_poster6dof_planar");
  const Sequence seq(dir);
  OdometryConfig cfg = defaultOdometryConfig(seq.width(), seq.height());
  cfg.duration_s = 1.5;
  cfg.wait_for_keyframe = false;
  const auto t0 = std::chrono::steady_clock::now();
  const OdometryResult r = runOdometryRealtime(seq, cfg, {.speed = 1.0});
  const double wall = secondsSince(t0);
  std::printf("[ ESIM 1.5 s at x1 ] %.2f s wall, %zu event poses, %zu events and %zu frames skipped\n", wall,
              r.events.size(), r.realtime.events_skipped, r.realtime.frames_skipped);
  EXPECT_GE(wall, 1.45);  // the last data is released 1.5 s after the first
  EXPECT_TRUE(r.realtime.on);
  ASSERT_EQ(r.realtime.latency_ms.size(), r.events.size());
  for (const double ms : r.realtime.latency_ms) EXPECT_GE(ms, 0.0);
  ASSERT_EQ(r.event_last_t.size(), r.events.size());
  for (std::size_t i = 0; i < r.events.size(); ++i) EXPECT_GE(r.event_last_t[i], r.events[i].t);
}

TEST(Realtime, FarFasterThanTheProcessingShedsLoad) {
  EDS_REQUIRE_SHARED(dir, "esim_poster6dof_planar");
  const Sequence seq(dir);
  OdometryConfig cfg = defaultOdometryConfig(seq.width(), seq.height());
  cfg.wait_for_keyframe = false;
  const auto t0 = std::chrono::steady_clock::now();
  const OdometryResult r = runOdometryRealtime(seq, cfg, {.speed = 50.0, .max_latency_s = 0.02});
  const double wall = secondsSince(t0);
  std::printf("[ ESIM at x50 ] %.2f s wall, %zu events and %zu frames skipped, %zu event poses\n", wall,
              r.realtime.events_skipped, r.realtime.frames_skipped, r.events.size());
  // 6 s of sequence released in 0.12 s: most of it cannot be processed in time and is dropped.
  EXPECT_GT(r.realtime.events_skipped, 1'000'000u);
  EXPECT_GT(r.realtime.frames_skipped, 50u);
  EXPECT_LT(r.frames_in, seq.frames().size());
  // Behind from the start, the stride of the tracked event frames goes up too.
  EXPECT_GE(r.realtime.max_event_frame_stride, 2);
}

// Twice as fast as this machine processes (whatever the build or the load), so that it initializes
// well before the replay ends: behind with fresh events coming, it keeps up by tracking only every k-th
// event frame. (At x50 everything released during the bootstrap is stale by its end, so how much is
// shed there depends on the machine.)
TEST(Realtime, TwiceFasterThanTheProcessingShedsEventFrames) {
  EDS_REQUIRE_SHARED(dir, "esim_poster6dof_planar");
  const Sequence seq(dir);
  OdometryConfig cfg = defaultOdometryConfig(seq.width(), seq.height());
  cfg.wait_for_keyframe = false;
  OdometryConfig first = cfg;
  first.duration_s = 2.0;
  const auto t0 = std::chrono::steady_clock::now();
  runOdometry(seq, first);
  const double speed = 2.0 * first.duration_s / secondsSince(t0);
  const OdometryResult r = runOdometryRealtime(seq, cfg, {.speed = speed, .max_latency_s = 0.02});
  std::printf(
      "[ ESIM at x%.2f ] %zu event poses, %zu event frames shed, stride up to %d, %zu events skipped\n",
      speed, r.events.size(), r.event_frames_shed, r.realtime.max_event_frame_stride,
      r.realtime.events_skipped);
  EXPECT_GT(r.events.size(), 0u);
  EXPECT_GE(r.realtime.max_event_frame_stride, 2);
  EXPECT_GT(r.event_frames_shed, 0u);
  // Behind, it drops frames for newer ones, but not below the minimum rate (sensor time); a stall
  // longer than the frame queue's bound may cost a few more.
  const double sensor_s = toSeconds(seq.frames().back().t - seq.frames().front().t);
  EXPECT_GE(static_cast<double>(r.frames_in), 0.9 * RealtimeOptions{}.min_frame_rate_hz * sensor_s)
      << r.realtime.frames_skipped << " frames skipped";
}

// Frames at 25 Hz, each with a newer one waiting (a consumer behind for good): the first taken, then
// the first frame 0.1 s or more after the last one taken, that is one every 0.12 s; with none
// waiting, every one.
TEST(Realtime, FramesBehindAreTakenAtTheMinimumRate) {
  FramePacer behind(10.0), keeping_up(10.0);
  std::vector<TimeNs> taken;
  for (int k = 0; k < 50; ++k) {
    const TimeNs t = k * 40'000'000LL;
    if (behind.take(t, true)) taken.push_back(t);
    EXPECT_TRUE(keeping_up.take(t, false));
  }
  ASSERT_EQ(taken.size(), 17u);
  for (std::size_t i = 1; i < taken.size(); ++i) EXPECT_EQ(taken[i] - taken[i - 1], 120'000'000LL);
}

// A consumer that takes nothing while the camera pushes: beyond the bounds the oldest event chunks go,
// and the frames are thinned: each time the one whose neighbours are closest, never the newest, and
// before any frame was taken never the oldest either (each kind on its own), counted; what stays
// comes out in order, and a frame reports whether a newer one is waiting.
TEST(Realtime, TheReleaseQueueDropsItsOldestChunksAndThinsItsFramesBeyondItsBounds) {
  ReleaseQueue queue(2500, 4);
  for (std::size_t k = 0; k < 10; ++k) {
    ReleasedItem frame{.frame = true, .index = k, .t = static_cast<TimeNs>(k)};
    queue.push(std::move(frame));
    ReleasedItem chunk;
    for (int e = 0; e < 1000; ++e) chunk.events.push_back(static_cast<TimeNs>(k), 1, 2, 1);
    queue.push(std::move(chunk));
  }
  queue.close();
  EXPECT_EQ(queue.droppedFrames(), 6u);
  EXPECT_EQ(queue.droppedEvents(), 8000u);
  std::vector<std::size_t> frames;
  std::vector<TimeNs> chunks;
  std::vector<bool> newer;
  ReleasedItem item;
  bool newer_frame = false;
  while (queue.pop(item, newer_frame)) {
    if (item.frame)
      frames.push_back(item.index), newer.push_back(newer_frame);
    else
      chunks.push_back(item.events.t.front());
  }
  EXPECT_EQ(frames, (std::vector<std::size_t>{0, 4, 7, 9}));
  EXPECT_EQ(newer, (std::vector<bool>{true, true, true, false}));
  EXPECT_EQ(chunks, (std::vector<TimeNs>{8, 9}));
}

std::vector<TimeNs> frameTimes(ReleaseQueue& queue) {
  std::vector<TimeNs> t;
  ReleasedItem item;
  bool newer_frame = false;
  while (queue.pop(item, newer_frame)) t.push_back(item.t);
  return t;
}

// Once a frame was taken, the oldest queued frame's gap runs from it; with room for one frame, the
// newer of two stays.
TEST(Realtime, TheReleaseQueueThinsFromTheLastFrameTaken) {
  ReleaseQueue queue(1000, 3);
  const auto push = [&](TimeNs t) { queue.push(ReleasedItem{.frame = true, .t = t}); };
  push(0);
  ReleasedItem item;
  bool newer_frame = false;
  ASSERT_TRUE(queue.pop(item, newer_frame));
  for (const TimeNs t : {10, 11, 12, 30}) push(t);  // 11 goes: 12 - 10 is the shortest gap
  push(31);                                         // 10 goes: 12 - 0 against 30 - 10 and 31 - 12
  queue.close();
  EXPECT_EQ(frameTimes(queue), (std::vector<TimeNs>{12, 30, 31}));
  EXPECT_EQ(queue.droppedFrames(), 2u);
  ReleaseQueue one(1000, 1);
  one.push(ReleasedItem{.frame = true, .t = 5});
  one.push(ReleasedItem{.frame = true, .t = 6});
  one.close();
  EXPECT_EQ(frameTimes(one), (std::vector<TimeNs>{6}));
}

TEST(Realtime, AStopRequestEndsTheRun) {
  EDS_REQUIRE_SHARED(dir, "esim_poster6dof_planar");
  const Sequence seq(dir);
  OdometryConfig cfg = defaultOdometryConfig(seq.width(), seq.height());
  std::atomic<bool> stop{false};
  std::thread stopper([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(700));
    stop = true;
  });
  const OdometryResult r = runOdometryRealtime(seq, cfg, {.speed = 1.0}, &stop);
  stopper.join();
  EXPECT_TRUE(r.interrupted);
  // The feeding stopped about 0.7 s into the 6 s sequence, however slowly this machine processed it.
  EXPECT_LT(toSeconds(r.interrupted_t - seq.frames().front().t), 3.0);
}

// A damaged recording: the producer thread's InputError reaches the caller (no terminate()).
TEST(Realtime, BadInputInTheRecordingIsAnInputError) {
  EDS_REQUIRE_SHARED(dir, "esim_poster6dof_planar");
  const auto seq_dir = test::tempDir("realtime_bad");
  std::filesystem::copy_file(dir / "calib.txt", seq_dir / "calib.txt");
  std::filesystem::copy_file(dir / "images.txt", seq_dir / "images.txt");
  std::filesystem::create_directory_symlink(dir / "images", seq_dir / "images");
  const std::string cmd = "zcat " + (dir / "events.txt.gz").string() + " | head -n 200000 > " +
                          (seq_dir / "events.txt").string() + " && echo '0.9 not an event' >> " +
                          (seq_dir / "events.txt").string();
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const Sequence seq(seq_dir);
  OdometryConfig cfg = defaultOdometryConfig(seq.width(), seq.height());
  try {
    runOdometryRealtime(seq, cfg, {.speed = 5.0});
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find((seq_dir / "events.txt").string() + ":200001"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace eds
