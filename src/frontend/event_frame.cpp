#include "frontend/event_frame.hpp"

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>

#include "core/image_sampling.hpp"

namespace eds {

void EventFrameConfig::validate() const {
  if (num_events <= 0)
    throw std::invalid_argument("event frame: num_events must be > 0, got " + std::to_string(num_events));
  if (!(overlap >= 0.0 && overlap < 1.0))
    throw std::invalid_argument("event frame: overlap must be in [0, 1), got " + std::to_string(overlap));
  if (!(sigma_frac > 0)) throw std::invalid_argument("event frame: sigma_frac must be > 0");
  if (!(compensation_lookahead >= 0 && compensation_lookahead <= 10))
    throw std::invalid_argument("event frame: compensation_lookahead must be in [0, 10], got " +
                                std::to_string(compensation_lookahead));
  if (!(max_rate_hz >= 0))
    throw std::invalid_argument("event frame: max_rate_hz must be >= 0 (0: no cap), got " +
                                std::to_string(max_rate_hz));
}

std::size_t EventFrameConfig::stride() const {
  return std::max<std::size_t>(1, static_cast<std::size_t>(std::llround(num_events * (1.0 - overlap))));
}

std::size_t EventFrameConfig::lookahead() const {
  return reversal_compensation ? static_cast<std::size_t>(std::llround(num_events * compensation_lookahead))
                               : 0;
}

EventFrameBuilder::EventFrameBuilder(const Undistorter& undistorter, EventFrameConfig cfg)
    : und_(undistorter), cfg_(cfg) {
  cfg_.validate();
  weights_.resize(cfg_.num_events);
  const double mid = 0.5 * (cfg_.num_events - 1), sigma = cfg_.sigma_frac * cfg_.num_events;
  for (int k = 0; k < cfg_.num_events; ++k) {
    const double z = (k - mid) / sigma;
    weights_[k] = static_cast<float>(std::exp(-0.5 * z * z));
  }
  acc_.create(und_.pinhole().height, und_.pinhole().width, CV_32F);
  if (cfg_.reversal_compensation) {
    const std::size_t raw_pixels = static_cast<std::size_t>(und_.raw().width) * und_.raw().height;
    turns_.assign(raw_pixels, PixelTurns{});
    listed_.assign(raw_pixels, 0);
  }
}

void EventFrameBuilder::vote(const cv::Point2f& u, float v) {
  const int W = acc_.cols, H = acc_.rows;
  const float fx = std::floor(u.x), fy = std::floor(u.y);
  const int x0 = static_cast<int>(fx), y0 = static_cast<int>(fy);
  if (x0 < 0 || y0 < 0 || x0 + 1 >= W || y0 + 1 >= H) return;
  const float ax = u.x - fx, ay = u.y - fy;
  float* r0 = acc_.ptr<float>(y0) + x0;
  float* r1 = r0 + W;
  r0[0] += v * (1 - ax) * (1 - ay);
  r0[1] += v * ax * (1 - ay);
  r1[0] += v * (1 - ax) * ay;
  r1[1] += v * ax * ay;
}

void EventFrameBuilder::prefetchCells(const cv::Point2f& u) const {
  const int x0 = static_cast<int>(std::floor(u.x)), y0 = static_cast<int>(std::floor(u.y));
  if (x0 < 0 || y0 < 0 || x0 + 1 >= acc_.cols || y0 + 1 >= acc_.rows) return;
  const float* r0 = acc_.ptr<float>(y0) + x0;
  __builtin_prefetch(r0, 1);
  __builtin_prefetch(r0 + acc_.cols, 1);
}

void EventFrameBuilder::build(const EventArray& events, std::size_t begin, EventFrame& out,
                              std::uint64_t base) {
  const std::size_t n = static_cast<std::size_t>(cfg_.num_events);
  if (begin + n > events.size()) throw std::out_of_range("EventFrameBuilder: not enough events");
  acc_.setTo(0.0f);
  const int raw_w = und_.raw().width, raw_h = und_.raw().height;
  // Events hit pixels out of memory order: each one's undistortion entry is fetched 16 events ahead,
  // and the accumulator cells it votes into 8 events ahead (from the entry fetched before).
  constexpr std::size_t kLutAhead = 16, kCellsAhead = 8;
  const cv::Point2f* lut = und_.eventLut().data();
  const auto rawIndex = [&](std::size_t i) {
    const int xr = events.x[i], yr = events.y[i];
    return xr < raw_w && yr < raw_h ? static_cast<std::ptrdiff_t>(yr) * raw_w + xr : std::ptrdiff_t{-1};
  };
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t i = begin + k;
    if (k + kLutAhead < n) {
      if (const std::ptrdiff_t j = rawIndex(i + kLutAhead); j >= 0) __builtin_prefetch(lut + j);
    }
    if (k + kCellsAhead < n) {
      if (const std::ptrdiff_t j = rawIndex(i + kCellsAhead); j >= 0) prefetchCells(lut[j]);
    }
    const std::ptrdiff_t r = rawIndex(i);
    if (r < 0) continue;
    vote(lut[r], weights_[k] * static_cast<float>(events.p[i]));
  }
  if (cfg_.reversal_compensation) {
    const std::uint64_t b = base + begin;
    if (b < last_packet_ || base > frontier_) resetTurns(base);
    last_packet_ = b;
    advanceTurns(events, base, base + std::min(events.size(), begin + n + cfg_.lookahead()), b);
    voteRestored(b);
  }
  if (cfg_.blur)
    cv::GaussianBlur(acc_, out.delta, cv::Size(3, 3), 0, 0, cv::BORDER_REPLICATE);
  else
    acc_.copyTo(out.delta);
  const double norm = cv::norm(out.delta, cv::NORM_L2);
  if (norm > 0) out.delta *= 1.0 / norm;
  out.t = events.t[begin + n / 2];
  out.t_first = events.t[begin];
  out.t_last = events.t[begin + n - 1];
}

void EventFrameBuilder::resetTurns(std::uint64_t from) {
  std::fill(turns_.begin(), turns_.end(), PixelTurns{});
  std::fill(listed_.begin(), listed_.end(), std::uint8_t{0});
  restored_.clear();
  waiting_.clear();
  frontier_ = from;
}

void EventFrameBuilder::advanceTurns(const EventArray& events, std::uint64_t base, std::uint64_t to,
                                     std::uint64_t b) {
  const int raw_w = und_.raw().width, raw_h = und_.raw().height;
  const auto packet = static_cast<std::int64_t>(b);
  constexpr std::uint64_t kAhead = 16;  // events: the pixel states are read out of cache order
  for (std::uint64_t s = frontier_; s < to; ++s) {
    const std::size_t i = static_cast<std::size_t>(s - base);
    if (s + kAhead < to) {
      const std::size_t j = i + kAhead;
      const std::size_t ahead = static_cast<std::size_t>(events.y[j]) * raw_w + events.x[j];
      if (ahead < turns_.size()) __builtin_prefetch(&turns_[ahead]);
    }
    if (events.x[i] >= raw_w || events.y[i] >= raw_h) continue;
    const auto px = static_cast<std::uint32_t>(events.y[i] * raw_w + events.x[i]);
    PixelTurns& pt = turns_[px];
    const bool positive = events.p[i] > 0;
    const auto k = static_cast<std::int64_t>(s);
    if (pt.prev >= 0) {  // a turn (the last event) waiting for this, the pixel's next event
      // Still going the turn's way: the re-crossing came one such step before the turn's event;
      // otherwise midway between the turn and the event before it.
      const std::int64_t t = pt.last >> 1, j = pt.prev;
      const bool turn_positive = (pt.last & 1) != 0;
      const std::int64_t r = positive == turn_positive ? std::max(j, t - (k - t)) : j + (t - j) / 2;
      if (r >= packet) restored_.push_back({r, px, turn_positive});
      pt.prev = -1;
    }
    if (pt.last >= 0 && ((pt.last & 1) != 0) != positive) {  // a turn
      pt.prev = pt.last >> 1;
      if (!listed_[px]) listed_[px] = 1, waiting_.push_back(px);
    }
    pt.last = (k << 1) | (positive ? 1 : 0);
  }
  frontier_ = std::max(frontier_, to);
}

void EventFrameBuilder::voteRestored(std::uint64_t b) {
  const auto first = static_cast<std::int64_t>(b), end = first + cfg_.num_events;
  const int raw_w = und_.raw().width;
  auto restore = [&](std::uint32_t px, std::int64_t r, bool positive) {
    const float w = weights_[static_cast<std::size_t>(r - first)];
    vote(und_.eventLut(static_cast<int>(px % raw_w), static_cast<int>(px / raw_w)), positive ? w : -w);
  };
  // Restored events before this packet are no use to later ones either.
  std::size_t kept = 0;
  for (const Restored& e : restored_) {
    if (e.index < first) continue;
    if (e.index < end) restore(e.pixel, e.index, e.positive);
    restored_[kept++] = e;
  }
  restored_.resize(kept);
  // Turns whose next event has not come yet: midway between the turn and the event before it. A turn
  // before this packet cannot land in it or in any later one.
  kept = 0;
  for (const std::uint32_t px : waiting_) {
    const PixelTurns& pt = turns_[px];
    const std::int64_t t = pt.last >> 1;
    if (pt.prev < 0 || t < first) {
      listed_[px] = 0;
      continue;
    }
    const std::int64_t r = pt.prev + (t - pt.prev) / 2;
    if (r >= first && r < end) restore(px, r, (pt.last & 1) != 0);
    waiting_[kept++] = px;
  }
  waiting_.resize(kept);
}

}  // namespace eds
