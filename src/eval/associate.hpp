#pragma once
// Time association of an estimated trajectory with ground truth, as rpg_trajectory_evaluation does
// it (DESIGN.md section 5): one-to-one, closest pairs first, no interpolation.
#include <cstddef>
#include <optional>
#include <vector>

#include "core/time.hpp"
#include "io/trajectory_io.hpp"

namespace eds::eval {

// Closed interval of ground-truth time; pairs whose gt stamp lies outside are dropped.
struct TimeWindow {
  TimeNs start = 0;
  TimeNs end = 0;
  bool contains(TimeNs t) const { return t >= start && t <= end; }
};

struct MatchedPair {
  std::size_t est = 0;  // index into the estimate
  std::size_t gt = 0;   // index into the ground truth
};

// Every (est, gt) pair with |t_est - t_gt| < max_dt is a candidate; candidates are taken greedily in
// ascending (|dt|, t_est, t_gt) order when neither side is used yet. The result is sorted by estimate
// time. Inputs need not be sorted. Cost: O((n + m) log(n + m) + c log c) for c candidates, where c is
// bounded by n times the number of gt stamps inside a 2*max_dt window.
std::vector<MatchedPair> associate(const Trajectory& est, const Trajectory& gt, TimeNs max_dt);

// Keeps the pairs whose ground-truth stamp lies in the window (the toolbox filters on gt, not est).
std::vector<MatchedPair> filterByGtWindow(const std::vector<MatchedPair>& pairs, const Trajectory& gt,
                                          const TimeWindow& window);

// The ground truth, time-sorted, with a pose interpolated (linear position, slerp rotation) at every
// estimate stamp that two ground-truth samples at most max_bracket apart enclose, so that association
// pairs such an estimate with the truth at its own time. Not the toolbox's convention (it pairs with
// the nearest stamp): an estimate at a higher rate than the ground truth is otherwise charged with
// speed x offset to the nearest stamp.
Trajectory interpolatedAtStamps(const Trajectory& gt, const Trajectory& est, TimeNs max_bracket);

}  // namespace eds::eval
