#pragma once
// Smoothing of the event-rate poses written as the run's result. Each event frame is solved on its own,
// so its pose carries a jitter (about 0.1-0.2 cm on the simulated scenes, 2-3x the frame poses' error)
// that is white from one event frame to the next, while the camera's motion is smooth at that scale; a
// local quadratic fit over a few tens of milliseconds removes most of it without lag (a line's fit
// would be a moving average, biased by the motion's curvature).
#include <vector>

#include "io/trajectory_io.hpp"

namespace eds {

// Each position replaced by the value at its own time of the least-squares parabola through the
// positions within ±half_window_s of it, and each orientation likewise (the parabola through the
// neighbours' rotation vectors relative to it); times unchanged. Poses with no neighbour in the window
// stay as they are; half_window_s <= 0 returns the input. std::invalid_argument when the poses are not
// in time order.
Trajectory smoothPoses(const Trajectory& traj, double half_window_s);

// The event-rate poses anchored to the frame poses: at each frame time the event trajectory
// (interpolated) is off the frame's pose by a position and a rotation difference; between two frames
// both differences are interpolated in time and applied to every event pose. The frame alignment is the
// more accurate of the two where both exist, and its error is independent of the events', so what is
// left between frames is the events' short-term shape. Poses not between two anchors at most
// `max_gap` apart, or with a break (a new map segment) between them, stay as they are. Both
// trajectories in time order.
Trajectory anchorToFrames(const Trajectory& events, const Trajectory& frames, TimeNs max_gap,
                          const std::vector<TimeNs>& breaks = {});

}  // namespace eds
