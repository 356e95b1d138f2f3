#include "frontend/flicker_filter.hpp"

#include <limits>
#include <stdexcept>

namespace eds {

FlickerFilter::FlickerFilter(int width, int height, const FlickerFilterConfig& cfg)
    : cfg_(cfg),
      width_(width),
      inv_leak_ns_(1.0 / (cfg.leak_ms * 1e6)),
      pixels_(static_cast<std::size_t>(width) * static_cast<std::size_t>(height)) {
  if (cfg.enabled && !(cfg.leak_ms > 0 && cfg.score > 0))
    throw std::invalid_argument("flicker filter: leak_ms and score must be > 0");
}

}  // namespace eds
