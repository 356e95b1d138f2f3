#pragma once
// A recorded sequence fed to the odometry on the wall clock, as a camera driver would: a producer
// thread releases each chunk of events and each frame when its time comes (at `speed` times real time),
// and the calling thread processes what was released. When processing falls behind, it sheds load
// rather than fall further behind: first it builds and tracks only every 2nd, 4th or 8th event frame
// (the stride rises while items wait and falls once they do not); then event chunks released more than
// `max_latency_s` ago are dropped (the odometry sees a gap, as after a USB drop) and a frame is
// dropped when a newer one is already waiting, but never so many that the frames taken come fewer
// than `min_frame_rate_hz` per sensor second; the queue between the threads is bounded. The
// result's `realtime` part says what was dropped and how late each event pose came.
#include <atomic>
#include <cstddef>

#include "system/odometry.hpp"

namespace eds {

struct RealtimeOptions {
  double speed = 1.0;  // sensor seconds per wall second
  // Wall time an event chunk may wait before it is dropped. Long enough for the backlog of a bootstrap
  // or a keyframe to be worked off at a higher stride: a dropped chunk is a gap in the event poses.
  double max_latency_s = 0.5;
  // Behind, frames are dropped for newer ones only while the last one taken is less than 1 / this
  // (sensor time) before: a consumer that is always behind would otherwise drop every frame, and the
  // frame tracker's basin, not the events, must bound the motion between two frames.
  double min_frame_rate_hz = 10.0;
  std::size_t max_queued_events = 4'000'000;  // the producer drops its oldest chunks beyond this
  // And frames beyond this, thinned so that those kept stay spread over the backlog (a run of
  // dropped frames is a gap the events must bridge): where even min_frame_rate_hz is more than the
  // processing does, at most this many frames wait.
  std::size_t max_queued_frames = 32;
};

// Which frames a consumer that is behind takes: a frame with a newer one already waiting is dropped,
// unless the last frame taken is 1 / min_rate_hz (sensor time) or more before it.
class FramePacer {
 public:
  explicit FramePacer(double min_rate_hz) : max_gap_(fromSeconds(1.0 / min_rate_hz)) {}
  bool take(TimeNs t, bool newer_waiting) {
    if (newer_waiting && last_ >= 0 && t - last_ < max_gap_) return false;
    last_ = t;
    return true;
  }

 private:
  TimeNs max_gap_;
  TimeNs last_ = -1;  // the last frame taken
};

OdometryResult runOdometryRealtime(const Sequence& seq, const OdometryConfig& cfg,
                                   const RealtimeOptions& options, const std::atomic<bool>* stop = nullptr,
                                   OdometryListener* listener = nullptr);

}  // namespace eds
