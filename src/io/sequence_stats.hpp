#pragma once
// What a sequence holds, for `eds info`: one streaming pass over the events.
#include <cstddef>
#include <optional>

#include "io/sequence.hpp"

namespace eds {

struct SequenceStats {
  int width = 0, height = 0;
  std::size_t events = 0;
  TimeNs events_t0 = 0, events_t1 = 0;
  double events_per_s_mean = 0;
  double events_per_s_peak = 0;  // over windows of peak_window_ns
  TimeNs peak_window_ns = 10'000'000;
  std::size_t positive = 0;
  std::size_t triggers = 0;  // external trigger edges recorded with the events
  std::size_t frames = 0;
  TimeNs frames_t0 = 0, frames_t1 = 0;
  double frame_rate = 0;                      // frames - 1 over their span
  TimeNs exposure_min = 0, exposure_max = 0;  // of the frames whose exposure is recorded (0: none)
  std::size_t frames_with_exposure = 0;
  std::size_t gt_poses = 0;
  TimeNs gt_t0 = 0, gt_t1 = 0;
};

SequenceStats computeStats(const Sequence& seq);

}  // namespace eds
