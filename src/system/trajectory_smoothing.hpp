#pragma once
// Smoothing of the event-rate positions written as the run's result. Each event frame is solved on
// its own, so its position carries a jitter (about 0.1-0.2 cm on the simulated scenes, 2-3x the frame
// poses' error) that is white from one event frame to the next, while the camera's motion is smooth at
// that scale; a local quadratic fit over a few tens of milliseconds removes most of it without lag (a
// line's fit would be a moving average, biased by the motion's curvature).
#include "io/trajectory_io.hpp"

namespace eds {

// Each position replaced by the value at its own time of the least-squares parabola through the
// positions within ±half_window_s of it (orientations and times unchanged). Poses with no neighbour in the
// window stay as they are; half_window_s <= 0 returns the input. std::invalid_argument when the poses
// are not in time order.
Trajectory smoothPositions(const Trajectory& traj, double half_window_s);

}  // namespace eds
