// The stage clock behind summary.json's time by stage: nested stages are charged exclusively, so the
// totals add up to the elapsed time and nothing is counted twice.
#include <gtest/gtest.h>

#include <chrono>
#include <numeric>
#include <thread>

#include "system/stage_clock.hpp"

namespace eds {
namespace {

double at(const StageSeconds& s, Stage st) { return s[static_cast<std::size_t>(st)]; }

TEST(StageClock, NestedStagesAreChargedExclusivelyAndAddUpToTheElapsedTime) {
  using namespace std::chrono;
  const auto t0 = steady_clock::now();
  StageClock clock(Stage::kInput);
  std::this_thread::sleep_for(milliseconds(5));
  {
    const ScopedStage tracking(&clock, Stage::kFrameTracking);
    std::this_thread::sleep_for(milliseconds(10));
    {
      const ScopedStage ba(&clock, Stage::kBundleAdjustment);
      std::this_thread::sleep_for(milliseconds(20));
    }
    std::this_thread::sleep_for(milliseconds(10));
  }
  const double before = duration<double>(steady_clock::now() - t0).count();
  const StageSeconds s = clock.seconds();
  const double after = duration<double>(steady_clock::now() - t0).count();
  EXPECT_GE(at(s, Stage::kInput), 0.005);
  EXPECT_GE(at(s, Stage::kFrameTracking), 0.020);
  EXPECT_GE(at(s, Stage::kBundleAdjustment), 0.020);
  EXPECT_EQ(at(s, Stage::kMapping), 0.0);
  // Counting the solve inside the tracking too would make the sum exceed the elapsed time.
  const double sum = std::accumulate(s.begin(), s.end(), 0.0);
  EXPECT_LE(sum, after);
  EXPECT_GE(sum, before - 1e-3);
  // A null clock is allowed (callers without a clock) and charges nothing.
  { const ScopedStage none(nullptr, Stage::kMapping); }
  EXPECT_EQ(at(clock.seconds(), Stage::kMapping), 0.0);
}

TEST(StageClock, EveryStageHasAName) {
  for (std::size_t i = 0; i < kStageCount; ++i) EXPECT_STRNE(stageName(static_cast<Stage>(i)), "");
  EXPECT_STREQ(stageName(Stage::kBundleAdjustment), "bundle_adjustment");
}

}  // namespace
}  // namespace eds
