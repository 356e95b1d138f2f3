#pragma once
// A flickering light (mains at 100/120 Hz, LED PWM) makes every pixel it reaches fire ON and OFF events
// in turn, many times a second, events that no camera motion explains. A pixel whose polarity keeps
// reversing faster than the leak rate accumulates a score; while the score is above the threshold its
// events are dropped before they reach the event frames. A moving edge reverses a pixel's polarity once
// per texture period, so only fine periodic texture moving fast for tens of ms looks alike.
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#include "core/reflect.hpp"
#include "core/time.hpp"

namespace eds {

struct FlickerFilterConfig {
  bool enabled = true;
  double leak_ms = 12.0;  // the score loses 1 per this much time between reversals
  double score = 2.0;     // events of a pixel whose score exceeds this are dropped
};

EDS_FIELDS(FlickerFilterConfig, enabled, leak_ms, score)

class FlickerFilter {
 public:
  FlickerFilter(int width, int height, const FlickerFilterConfig& cfg);
  // Whether the event is kept; events must come in time order.
  bool keep(TimeNs t, int x, int y, int polarity) {
    if (!cfg_.enabled) return true;
    Pixel& px =
        pixels_[static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x)];
    if (polarity != px.last_p) {
      const double leak = static_cast<double>(t - px.last_reversal) * inv_leak_ns_;
      // Capped at twice the threshold, so a pixel is free again soon after the light stops.
      px.score = static_cast<float>(std::min(std::max(0.0, px.score - leak) + 1.0, 2.0 * cfg_.score));
      px.last_reversal = t;
      px.last_p = static_cast<std::int8_t>(polarity);
    }
    const bool kept = px.score <= cfg_.score;
    dropped_ += !kept;
    return kept;
  }
  std::size_t dropped() const { return dropped_; }
  // Fetches the state of the pixel of an event to come into the cache: events hit pixels out of
  // memory order, and at large sensor sizes the states do not fit the cache.
  void prefetch(int x, int y) const {
    const std::size_t i =
        static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x);
    if (cfg_.enabled && i < pixels_.size()) __builtin_prefetch(pixels_.data() + i, 1);
  }

 private:
  FlickerFilterConfig cfg_;
  int width_;
  double inv_leak_ns_;
  // One pixel's state in one place: a single cache line per event at large sensor sizes.
  struct Pixel {
    TimeNs last_reversal = std::numeric_limits<TimeNs>::min() / 2;
    float score = 0;
    std::int8_t last_p = 0;
  };
  std::vector<Pixel> pixels_;
  std::size_t dropped_ = 0;
};

}  // namespace eds
