#pragma once
// The plausibility gate of the event frames buffered during the bootstrap, tracked once the map exists
// between the bootstrap's frames. A pose is a wrong minimum, not motion, when it is far from both the
// frames' interpolation and what the camera's speed allows from the nearer frame, or when it jumps from
// the last accepted pose faster than the frames' mean speed allows.
#include "core/se3.hpp"
#include "core/time.hpp"
#include "io/trajectory_io.hpp"

namespace eds {

class BufferedEventGate {
 public:
  // `frames`: the bootstrap's poses in time order; `last`: the last accepted pose (its time <= t);
  // margins in map units and radians.
  BufferedEventGate(const Trajectory& frames, TimeNs t, const StampedPose& last, double margin_t,
                    double margin_r);
  bool accepts(const SE3& T_w_c) const;
  // The frames before and after t (null when t is not between two of them) and their interpolation.
  const StampedPose* before() const { return before_; }
  const StampedPose* after() const { return after_; }
  const SE3& interpolated() const { return T_interp_; }
  // The last accepted pose, moved on to the frame before t when that is later.
  const StampedPose& last() const { return last_; }

 private:
  const StampedPose* before_ = nullptr;
  const StampedPose* after_ = nullptr;
  StampedPose last_;
  SE3 T_interp_, T_near_;
  double max_t_ = 0, max_r_ = 0;    // from the interpolation
  double near_t_ = 0, near_r_ = 0;  // from the nearer frame
  double step_t_ = 0, step_r_ = 0;  // from the last accepted pose
};

}  // namespace eds
