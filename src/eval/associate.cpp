#include "eval/associate.hpp"

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <tuple>

#include "core/se3.hpp"

namespace eds::eval {
namespace {

std::vector<std::size_t> sortedOrder(const Trajectory& traj) {
  std::vector<std::size_t> order(traj.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return traj[a].t < traj[b].t; });
  return order;
}

struct Candidate {
  TimeNs abs_dt;
  TimeNs t_est;
  TimeNs t_gt;
  std::size_t est;
  std::size_t gt;
};

}  // namespace

std::vector<MatchedPair> associate(const Trajectory& est, const Trajectory& gt, TimeNs max_dt) {
  const std::vector<std::size_t> est_order = sortedOrder(est);
  const std::vector<std::size_t> gt_order = sortedOrder(gt);

  // Two pointers: for each estimate (ascending), the gt stamps within (t - max_dt, t + max_dt) form a
  // window whose lower edge only moves forward.
  std::vector<Candidate> candidates;
  std::size_t lo = 0;
  for (const std::size_t e : est_order) {
    const TimeNs te = est[e].t;
    while (lo < gt_order.size() && gt[gt_order[lo]].t <= te - max_dt) ++lo;
    for (std::size_t k = lo; k < gt_order.size(); ++k) {
      const TimeNs tg = gt[gt_order[k]].t;
      if (tg >= te + max_dt) break;
      candidates.push_back({tg > te ? tg - te : te - tg, te, tg, e, gt_order[k]});
    }
  }
  // Indices break the remaining ties (duplicate stamps) so the result is deterministic.
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    return std::tie(a.abs_dt, a.t_est, a.t_gt, a.est, a.gt) <
           std::tie(b.abs_dt, b.t_est, b.t_gt, b.est, b.gt);
  });

  std::vector<std::uint8_t> est_used(est.size(), 0), gt_used(gt.size(), 0);
  std::vector<MatchedPair> pairs;
  for (const Candidate& c : candidates) {
    if (est_used[c.est] || gt_used[c.gt]) continue;
    est_used[c.est] = gt_used[c.gt] = 1;
    pairs.push_back({c.est, c.gt});
  }
  std::sort(pairs.begin(), pairs.end(), [&](const MatchedPair& a, const MatchedPair& b) {
    return std::tie(est[a.est].t, a.est) < std::tie(est[b.est].t, b.est);
  });
  return pairs;
}

std::vector<MatchedPair> filterByGtWindow(const std::vector<MatchedPair>& pairs, const Trajectory& gt,
                                          const TimeWindow& window) {
  std::vector<MatchedPair> kept;
  kept.reserve(pairs.size());
  for (const MatchedPair& p : pairs)
    if (window.contains(gt[p.gt].t)) kept.push_back(p);
  return kept;
}

Trajectory interpolatedAtStamps(const Trajectory& gt, const Trajectory& est, TimeNs max_bracket) {
  const auto by_time = [](const StampedPose& a, const StampedPose& b) { return a.t < b.t; };
  Trajectory sorted = gt;
  std::stable_sort(sorted.begin(), sorted.end(), by_time);
  Trajectory out = sorted;
  for (const StampedPose& e : est) {
    const auto hi = std::lower_bound(sorted.begin(), sorted.end(), e, by_time);
    if (hi == sorted.begin() || hi == sorted.end() || hi->t == e.t) continue;
    const auto lo = hi - 1;
    if (hi->t - lo->t > max_bracket) continue;
    const double s = static_cast<double>(e.t - lo->t) / static_cast<double>(hi->t - lo->t);
    out.push_back({e.t, interpolate(lo->T_w_c, hi->T_w_c, s)});
  }
  std::stable_sort(out.begin(), out.end(), by_time);
  out.erase(std::unique(out.begin(), out.end(),
                        [](const StampedPose& a, const StampedPose& b) { return a.t == b.t; }),
            out.end());
  return out;
}

}  // namespace eds::eval
