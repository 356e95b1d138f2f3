#include "sim/event_faults.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "sim/event_sim.hpp"

namespace eds::sim {

namespace {

double uniform(std::uint64_t seed, std::uint64_t counter) {
  return static_cast<double>(mix64(seed ^ mix64(counter)) >> 11) * 0x1.0p-53;
}

bool inAny(const std::vector<EventFaults::Window>& windows, TimeNs t) {
  return std::any_of(windows.begin(), windows.end(), [t](const auto& w) { return t >= w.t0 && t < w.t1; });
}

void sortByTime(EventArray& e) {
  std::vector<std::size_t> order(e.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return e.t[a] < e.t[b]; });
  EventArray sorted;
  sorted.reserve(e.size());
  for (const std::size_t i : order) sorted.push_back(e.t[i], e.x[i], e.y[i], e.p[i]);
  e = std::move(sorted);
}

}  // namespace

void EventFaultSink::burstEvents(const EventFaults::Window& w, TimeNs from, TimeNs to, EventArray& out) {
  const TimeNs a = std::max(from, w.t0), b = std::min(to, w.t1);
  if (b <= a) return;
  // A Poisson count over the whole sensor, placed uniformly in time and space.
  const double mean = w.value * width_ * height_ * toSeconds(b - a);
  const auto n =
      static_cast<std::size_t>(mean + std::sqrt(mean) * (uniform(faults_.seed, draws_++) - 0.5) * 3.46);
  for (std::size_t k = 0; k < n; ++k) {
    const auto t = a + static_cast<TimeNs>(uniform(faults_.seed, draws_++) * static_cast<double>(b - a));
    const auto x = static_cast<std::uint16_t>(uniform(faults_.seed, draws_++) * width_);
    const auto y = static_cast<std::uint16_t>(uniform(faults_.seed, draws_++) * height_);
    out.push_back(std::min(t, b - 1) + 1, x, y, uniform(faults_.seed, draws_++) < 0.5 ? 1 : -1);
  }
}

void EventFaultSink::flickerEvents(const EventFaults::Window& w, TimeNs from, TimeNs to,
                                   EventArray& out) const {
  // The light's intensity rises and falls once per period: every pixel of the patch fires two ON
  // events at each rise and two OFF events at each fall (a log change of about twice the threshold),
  // each pixel with its own fixed delay of up to 0.5 ms.
  const int x0 = width_ / 8, y0 = height_ / 8, pw = width_ / 4, ph = height_ / 4;
  const auto half = static_cast<TimeNs>(std::llround(0.5e9 / w.value));
  for (TimeNs edge = w.t0 + (std::max(from, w.t0) - w.t0) / half * half; edge < std::min(to, w.t1);
       edge += half) {
    const std::int8_t pol = ((edge - w.t0) / half) % 2 == 0 ? 1 : -1;
    for (int y = y0; y < y0 + ph; ++y)
      for (int x = x0; x < x0 + pw; ++x) {
        const auto delay =
            static_cast<TimeNs>(uniform(faults_.seed + 7, static_cast<std::uint64_t>(y * width_ + x)) * 5e5);
        for (int k = 0; k < 2; ++k) {
          const TimeNs t = edge + delay + k * 100'000;
          if (t > from && t <= to)
            out.push_back(t, static_cast<std::uint16_t>(x), static_cast<std::uint16_t>(y), pol);
        }
      }
  }
}

void EventFaultSink::extraEvents(TimeNs from, TimeNs to, EventArray& out) {
  out.clear();
  for (const auto& w : faults_.bursts) burstEvents(w, from, to, out);
  for (const auto& w : faults_.flicker) flickerEvents(w, from, to, out);
  sortByTime(out);
}

void EventFaultSink::onEvents(const EventArray& events) {
  if (events.empty()) return;
  const TimeNs to = events.t.back();
  extraEvents(done_ == INT64_MIN ? events.t.front() - 1 : done_, to, extra_);
  done_ = to;
  merged_.clear();
  merged_.reserve(events.size() + extra_.size());
  std::size_t i = 0, j = 0;
  while (i < events.size() || j < extra_.size()) {
    const bool take_event = j == extra_.size() || (i < events.size() && events.t[i] <= extra_.t[j]);
    const EventArray& src = take_event ? events : extra_;
    const std::size_t k = take_event ? i++ : j++;
    if (inAny(faults_.gaps, src.t[k]) || src.t[k] + faults_.offset < 0) continue;  // no negative times
    merged_.push_back(src.t[k] + faults_.offset, src.x[k], src.y[k], src.p[k]);
  }
  inner_.onEvents(merged_);
}

}  // namespace eds::sim
