#include "system/exposure_events.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

namespace eds {

ExposureEvents::ExposureEvents(TimeNs exposure)
    : exposure_(exposure), longest_(exposure), kept_from_(std::numeric_limits<TimeNs>::min()) {
  if (exposure <= 0) throw std::invalid_argument("ExposureEvents: the exposure must be > 0");
}

void ExposureEvents::setExposure(TimeNs exposure) {
  if (exposure <= 0) throw std::invalid_argument("ExposureEvents: the exposure must be > 0");
  exposure_ = exposure;
}

void ExposureEvents::addEvents(const EventArray& ev, std::size_t begin, std::size_t end) {
  end = std::min(end, ev.size());
  if (begin >= end) return;
  const auto b = static_cast<std::ptrdiff_t>(begin), e = static_cast<std::ptrdiff_t>(end);
  ev_.t.insert(ev_.t.end(), ev.t.begin() + b, ev.t.begin() + e);
  ev_.x.insert(ev_.x.end(), ev.x.begin() + b, ev.x.begin() + e);
  ev_.y.insert(ev_.y.end(), ev.y.begin() + b, ev.y.begin() + e);
  ev_.p.insert(ev_.p.end(), ev.p.begin() + b, ev.p.begin() + e);
  newest_ = ev.t[end - 1];
  any_ = true;
  trim();
}

void ExposureEvents::addFrame(TimeNs t, const cv::Mat& gray8, TimeNs recorded) {
  if (recorded < 0 || recorded > longest_)
    throw std::invalid_argument("ExposureEvents: a recorded exposure must be in [0, " +
                                std::to_string(longest_) + "] ns, got " + std::to_string(recorded));
  frames_.push_back({t, gray8, recorded});
}

void ExposureEvents::endExposures(TimeNs up_to, TimeNs processed, const Handler& handle) {
  while (!frames_.empty()) {
    const Frame& f = frames_.front();
    const TimeNs exposure = f.recorded > 0 ? f.recorded : exposure_;
    const TimeNs start = f.t - exposure / 2, stop = start + exposure;
    if (stop > up_to || f.t > processed) break;
    if (start >= kept_from_) {
      const auto from = ev_.t.begin() + static_cast<std::ptrdiff_t>(first_);
      const auto b = std::lower_bound(from, ev_.t.end(), start), e = std::lower_bound(b, ev_.t.end(), stop);
      handle(f.t, exposure, f.recorded > 0, f.gray8, ev_, static_cast<std::size_t>(b - ev_.t.begin()),
             static_cast<std::size_t>(e - ev_.t.begin()));
    }
    frames_.pop_front();
  }
  trim();
}

// Keeps what a frame still to be handed on needs, and two exposures back from the newest event for a
// frame that comes after its exposure's events (a camera delivers it when the exposure has ended).
void ExposureEvents::trim() {
  if (!any_) return;
  TimeNs keep = newest_ - 2 * longest_;
  if (!frames_.empty()) keep = std::min(keep, frames_.front().t - longest_ / 2);
  const auto from = ev_.t.begin() + static_cast<std::ptrdiff_t>(first_);
  const auto it = std::lower_bound(from, ev_.t.end(), keep);
  if (it != from) kept_from_ = std::max(kept_from_, keep);
  first_ = static_cast<std::size_t>(it - ev_.t.begin());
  // Erased in one go once more than half is dead: each event is moved O(1) times on average.
  if (first_ > 4096 && 2 * first_ > ev_.size()) {
    const auto n = static_cast<std::ptrdiff_t>(first_);
    ev_.t.erase(ev_.t.begin(), ev_.t.begin() + n);
    ev_.x.erase(ev_.x.begin(), ev_.x.begin() + n);
    ev_.y.erase(ev_.y.begin(), ev_.y.begin() + n);
    ev_.p.erase(ev_.p.begin(), ev_.p.begin() + n);
    first_ = 0;
  }
}

}  // namespace eds
