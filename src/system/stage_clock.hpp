#pragma once
// Wall time by pipeline stage on one thread, counted exclusively: a stage entered inside another
// stops the outer one's clock until it ends, so the totals add up to the time since the clock started
// and whatever no stage claims shows as "unaccounted".
#include <array>
#include <chrono>
#include <cstddef>
#include <stdexcept>

namespace eds {

enum class Stage : std::size_t {
  kInput,             // between the caller's calls: reading and decoding (eds run), the camera (live)
  kEventIntake,       // checking, flicker filtering and buffering new events
  kEventFrames,       // building event frames
  kEventTracking,     // event frames against the reference (and during the bootstrap)
  kFramePreparation,  // frame quality check, undistortion, waiting for the exposure estimate
  kFrameTracking,     // frame alignment and the keyframe decision
  kBootstrap,         // two-frame initialization
  kMapping,           // a new keyframe's points and depths
  kBundleAdjustment,  // the sliding-window solve
  kWaiting,           // for the threaded back-end
  kWaitingForEvents,  // for the event-frame producer thread
  kResults,           // listener calls, the refined trajectories at the end
  kIdle,              // the back-end thread with nothing to do
  kUnaccounted,
  kCount
};
inline constexpr std::size_t kStageCount = static_cast<std::size_t>(Stage::kCount);

inline const char* stageName(Stage s) {
  static constexpr const char* kNames[kStageCount] = {"input",
                                                      "event_intake",
                                                      "event_frames",
                                                      "event_tracking",
                                                      "frame_preparation",
                                                      "frame_tracking",
                                                      "bootstrap",
                                                      "mapping",
                                                      "bundle_adjustment",
                                                      "waiting_for_backend",
                                                      "waiting_for_events",
                                                      "results",
                                                      "idle",
                                                      "unaccounted"};
  return kNames[static_cast<std::size_t>(s)];
}

using StageSeconds = std::array<double, kStageCount>;

class StageClock {
 public:
  // `base`: the stage charged while no other is entered.
  explicit StageClock(Stage base) : last_(Clock::now()) { stack_[0] = base; }

  void enter(Stage s) {
    if (depth_ + 1 == kMaxDepth) throw std::logic_error("StageClock: stages nested too deep");
    charge();
    stack_[++depth_] = s;
  }
  void leave() {
    charge();
    if (depth_ > 0) --depth_;
  }
  // Seconds per stage so far (the current one up to now). Only the clock's own thread may call it,
  // or another once that thread has stopped using the clock (a happens-before through a lock).
  StageSeconds seconds() {
    charge();
    return s_;
  }

 private:
  using Clock = std::chrono::steady_clock;
  static constexpr std::size_t kMaxDepth = 8;
  void charge() {
    const Clock::time_point now = Clock::now();
    s_[static_cast<std::size_t>(stack_[depth_])] += std::chrono::duration<double>(now - last_).count();
    last_ = now;
  }
  StageSeconds s_{};
  std::array<Stage, kMaxDepth> stack_{};
  std::size_t depth_ = 0;
  Clock::time_point last_;
};

// A stage for the lifetime of the scope (nothing when `clock` is null).
class ScopedStage {
 public:
  ScopedStage(StageClock* clock, Stage s) : clock_(clock) {
    if (clock_) clock_->enter(s);
  }
  ~ScopedStage() {
    if (clock_) clock_->leave();
  }
  ScopedStage(const ScopedStage&) = delete;
  ScopedStage& operator=(const ScopedStage&) = delete;

 private:
  StageClock* clock_;
};

}  // namespace eds
