#pragma once
// Whether the events' clock is offset from the frames': the event poses and the frame poses of one run
// track the same map, so at each frame's time the event trajectory, shifted by the right offset, has
// the frame's orientation. The offset that best aligns them (a grid search over +-10 ms on the rotation
// differences, which do not depend on the monocular scale) is reported; eds does not correct for it.
#include <cmath>

#include "io/trajectory_io.hpp"

namespace eds {

struct ClockOffsetEstimate {
  bool valid = false;          // enough frames inside the event trajectory, and motion to tell
  double offset_ms = 0;        // events' times minus the frames' for the same instant (> 0: events late)
  double rms_deg_at_zero = 0;  // rotation difference RMS with no offset
  double rms_deg_at_best = 0;  // ... at the estimate
  // A clear offset: at least 1 ms, and the differences at least 20 % lower there than at zero.
  bool suggestsOffset() const {
    return valid && std::abs(offset_ms) >= 1.0 && rms_deg_at_best < 0.8 * rms_deg_at_zero;
  }
};

ClockOffsetEstimate estimateEventClockOffset(const Trajectory& frames, const Trajectory& events);

}  // namespace eds
