#pragma once
// ESIM-style event generation (Rebecq et al., CoRL 2018): each pixel keeps a reference log
// intensity; between two renders the log intensity is taken as linear in time, and every crossing of
// reference +/- C emits an event at the interpolated time and moves the reference by C (or, with
// hysteresis off, every crossing of a fixed lattice of levels). Noise models:
// per-crossing threshold noise, refractory period, background activity and hot pixels. Deterministic
// for a seed, whatever the number of threads: every random draw comes from a counter-based hash of
// (seed, pixel, draw index), not from a shared generator.
#include <cstdint>
#include <limits>
#include <opencv2/core.hpp>
#include <vector>

#include "core/events.hpp"

namespace eds::sim {

struct EventSimConfig {
  double C_pos = 0.2, C_neg = 0.2;   // contrast thresholds (log intensity)
  double sigma_C = 0.0;              // std-dev of each crossing's threshold (log units)
  double C_min = 0.01;               // thresholds are clamped above this
  double refractory_s = 0.0;         // events of a pixel closer than this are dropped
  double noise_rate_hz = 0.0;        // background activity per pixel (Poisson)
  double hot_pixel_fraction = 0.0;   // fraction of pixels that fire continuously
  double hot_pixel_rate_hz = 100.0;  // their rate
  double log_eps = 1e-3;             // L = log(I + eps)
  std::uint64_t seed = 1;
  // true: a DVS pixel, which re-arms at each event, so after the brightness turns the first event of
  // the other polarity needs a full threshold past the last level (as in ESIM and real sensors).
  // false: an idealized sensor that fires at every crossing of its lattice of levels, re-crossing the
  // last one included, so the events count the brightness change without that lost event per turn.
  // For studies of what hysteresis costs the tracker (tests/frontend/test_tracker_on_sim.cpp).
  bool hysteresis = true;
};

class EventGenerator {
 public:
  EventGenerator(int width, int height, EventSimConfig cfg);

  // Starts from a first log image (CV_32F) at time t0: the reference levels.
  void reset(const cv::Mat& log_image, TimeNs t0);
  // Advances to log image `log_image` at time t1 > previous time and appends the events in between,
  // sorted by time, to `out`.
  void step(const cv::Mat& log_image, TimeNs t1, EventArray& out);

  const EventSimConfig& config() const { return cfg_; }
  std::uint64_t stepCount() const { return steps_; }

 private:
  double uniform(std::uint64_t pixel, std::uint64_t counter) const;  // [0, 1)
  double gaussian(std::uint64_t pixel, std::uint64_t counter) const;
  double threshold(int pixel, int polarity);
  std::uint64_t poisson(double lambda, std::uint64_t key, std::uint64_t& counter) const;
  void addNoise(TimeNs t0, TimeNs t1);  // background and hot-pixel events into merged_

  int width_, height_;
  EventSimConfig cfg_;
  cv::Mat prev_;                          // previous log image
  std::vector<float> ref_;                // reference level per pixel (the last level crossed)
  std::vector<std::int8_t> last_pol_;     // polarity of that crossing (hysteresis off only)
  std::vector<TimeNs> last_event_;        // for the refractory period
  std::vector<std::uint32_t> draws_;      // per-pixel draw counters (threshold noise)
  std::vector<float> thr_pos_, thr_neg_;  // each pixel's next thresholds
  std::vector<std::uint32_t> hot_;        // hot pixel indices
  TimeNs t_prev_ = 0;
  std::uint64_t steps_ = 0;
  // Scratch, reused every step (no allocation in the per-step loop once warm).
  struct Pending {
    TimeNs t;
    std::uint32_t pixel;
    std::int8_t polarity;
  };
  std::vector<std::vector<Pending>> row_events_;
  std::vector<Pending> merged_;
};

// L = log(I + eps) of a CV_32F intensity image, optionally of its 8-bit quantization (as ESIM's
// pipeline on stored 8-bit images does).
void toLogImage(const cv::Mat& intensity, double eps, bool quantize_8bit, cv::Mat& log_image);

// splitmix64: a good 64-bit mixer, used as a counter-based random source.
inline std::uint64_t mix64(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

}  // namespace eds::sim
