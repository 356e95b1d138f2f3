#include "sim/event_sim.hpp"

#include <tbb/blocked_range.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "core/parallel.hpp"

namespace eds::sim {

namespace {
constexpr std::uint64_t kStreamThreshold = 1;
constexpr std::uint64_t kStreamNoise = 2;
constexpr std::uint64_t kStreamHot = 3;
}  // namespace

EventGenerator::EventGenerator(int width, int height, EventSimConfig cfg)
    : width_(width), height_(height), cfg_(cfg) {
  if (width <= 0 || height <= 0) throw std::invalid_argument("EventGenerator: empty sensor");
  if (!(cfg.C_pos > 0) || !(cfg.C_neg > 0)) throw std::invalid_argument("contrast thresholds must be > 0");
  if (cfg.sigma_C < 0 || cfg.refractory_s < 0 || cfg.noise_rate_hz < 0 || cfg.hot_pixel_fraction < 0 ||
      cfg.hot_pixel_fraction > 1)
    throw std::invalid_argument("noise parameters must be non-negative (hot-pixel fraction <= 1)");
  const std::size_t n = static_cast<std::size_t>(width) * height;
  ref_.resize(n);
  last_pol_.assign(n, 1);
  last_event_.assign(n, std::numeric_limits<TimeNs>::min() / 2);
  draws_.assign(n, 0);
  thr_pos_.resize(n);
  thr_neg_.resize(n);
  row_events_.resize(height);
  // Hot pixels: a fixed, seed-determined set.
  const auto n_hot = static_cast<std::size_t>(std::llround(cfg.hot_pixel_fraction * n));
  for (std::size_t k = 0; hot_.size() < n_hot; ++k) {
    const auto p = static_cast<std::uint32_t>(uniform(kStreamHot << 40, k) * n);
    if (std::find(hot_.begin(), hot_.end(), p) == hot_.end()) hot_.push_back(p);
  }
}

double EventGenerator::uniform(std::uint64_t key, std::uint64_t counter) const {
  const std::uint64_t h = mix64(cfg_.seed * 0x9e3779b97f4a7c15ULL ^ mix64(key * 0x100000001b3ULL + counter));
  return static_cast<double>(h >> 11) * 0x1.0p-53;
}

double EventGenerator::gaussian(std::uint64_t key, std::uint64_t counter) const {
  const double u1 = std::max(uniform(key, 2 * counter), 1e-300);
  const double u2 = uniform(key, 2 * counter + 1);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

double EventGenerator::threshold(int pixel, int polarity) {
  const double C = polarity > 0 ? cfg_.C_pos : cfg_.C_neg;
  if (cfg_.sigma_C <= 0) return C;
  const double noisy = C + cfg_.sigma_C * gaussian((kStreamThreshold << 40) + pixel, draws_[pixel]++);
  return std::max(noisy, cfg_.C_min);
}

void EventGenerator::reset(const cv::Mat& log_image, TimeNs t0) {
  if (log_image.type() != CV_32F || log_image.cols != width_ || log_image.rows != height_)
    throw std::invalid_argument("EventGenerator: log image must be CV_32F of the sensor size");
  prev_ = log_image.clone();
  for (int y = 0; y < height_; ++y) {
    const float* row = prev_.ptr<float>(y);
    for (int x = 0; x < width_; ++x) {
      const int i = y * width_ + x;
      // Without hysteresis the signal starts mid-way between two levels (last crossed upwards), so
      // neither direction's first event comes sooner.
      ref_[i] = cfg_.hysteresis ? row[x] : static_cast<float>(row[x] - 0.5 * cfg_.C_pos);
      last_pol_[i] = 1;
      thr_pos_[i] = static_cast<float>(threshold(i, +1));
      thr_neg_[i] = static_cast<float>(threshold(i, -1));
    }
  }
  t_prev_ = t0;
}

void EventGenerator::step(const cv::Mat& log_image, TimeNs t1, EventArray& out) {
  if (prev_.empty()) throw std::logic_error("EventGenerator::step before reset");
  if (t1 <= t_prev_) throw std::invalid_argument("EventGenerator::step: time must increase");
  if (log_image.type() != CV_32F || log_image.cols != width_ || log_image.rows != height_)
    throw std::invalid_argument("EventGenerator: log image must be CV_32F of the sensor size");
  const TimeNs t0 = t_prev_;
  const double dt = static_cast<double>(t1 - t0);
  const auto refractory = static_cast<TimeNs>(cfg_.refractory_s * 1e9);
  parallelFor(tbb::blocked_range<int>(0, height_, 4), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y < rows.end(); ++y) {
      auto& ev = row_events_[y];
      ev.clear();
      const float* a = prev_.ptr<float>(y);
      const float* b = log_image.ptr<float>(y);
      for (int x = 0; x < width_; ++x) {
        const double it = a[x], itdt = b[x];
        if (itdt == it) continue;
        const int i = y * width_ + x;
        const int pol = itdt > it ? 1 : -1;
        double ref = ref_[i];
        // Each pixel's next threshold is drawn once and kept until it is crossed, so that threshold
        // noise does not depend on how finely time is stepped.
        for (;;) {
          float& thr = pol > 0 ? thr_pos_[i] : thr_neg_[i];
          // Without hysteresis, turning back re-crosses the last level first.
          const bool recross = !cfg_.hysteresis && last_pol_[i] != pol;
          const double next = recross ? ref : ref + pol * static_cast<double>(thr);
          const bool crossed = pol > 0 ? (next > it && next <= itdt) : (next < it && next >= itdt);
          if (!crossed) break;
          const TimeNs te = t0 + static_cast<TimeNs>(std::llround((next - it) / (itdt - it) * dt));
          if (te - last_event_[i] >= refractory) {
            ev.push_back({te, static_cast<std::uint32_t>(i), static_cast<std::int8_t>(pol)});
            last_event_[i] = te;
          }
          ref = next;
          last_pol_[i] = static_cast<std::int8_t>(pol);
          if (!recross) thr = static_cast<float>(threshold(i, pol));
        }
        ref_[i] = static_cast<float>(ref);
      }
    }
  });
  merged_.clear();
  for (const auto& ev : row_events_) merged_.insert(merged_.end(), ev.begin(), ev.end());
  addNoise(t0, t1);
  // Time order; ties by pixel so that the output does not depend on thread scheduling.
  std::sort(merged_.begin(), merged_.end(),
            [](const Pending& l, const Pending& r) { return l.t != r.t ? l.t < r.t : l.pixel < r.pixel; });
  out.reserve(out.size() + merged_.size());
  for (const Pending& e : merged_)
    out.push_back(e.t, static_cast<std::uint16_t>(e.pixel % width_),
                  static_cast<std::uint16_t>(e.pixel / width_), e.polarity);
  prev_ = log_image.clone();
  t_prev_ = t1;
  ++steps_;
}

// Poisson(lambda) from counter-based uniforms: inversion for small lambda, normal approximation above.
std::uint64_t EventGenerator::poisson(double lambda, std::uint64_t key, std::uint64_t& counter) const {
  if (lambda <= 0) return 0;
  if (lambda > 50) {
    const double g = gaussian(key, counter++);
    return static_cast<std::uint64_t>(std::max(0.0, std::round(lambda + std::sqrt(lambda) * g)));
  }
  const double L = std::exp(-lambda);
  double p = 1.0;
  std::uint64_t k = 0;
  for (;;) {
    p *= uniform(key, counter++);
    if (p <= L) return k;
    ++k;
  }
}

void EventGenerator::addNoise(TimeNs t0, TimeNs t1) {
  const double dt_s = static_cast<double>(t1 - t0) * 1e-9;
  const std::uint64_t key = (kStreamNoise << 40) + steps_;
  std::uint64_t counter = 0;
  const auto emit = [&](std::uint32_t pixel) {
    const auto t = t0 + 1 + static_cast<TimeNs>(uniform(key, counter++) * static_cast<double>(t1 - t0 - 1));
    const std::int8_t pol = uniform(key, counter++) < 0.5 ? -1 : 1;
    if (t - last_event_[pixel] < static_cast<TimeNs>(cfg_.refractory_s * 1e9)) return;
    merged_.push_back({t, pixel, pol});
  };
  const std::size_t n_pix = static_cast<std::size_t>(width_) * height_;
  const std::uint64_t n_noise = poisson(cfg_.noise_rate_hz * n_pix * dt_s, key, counter);
  for (std::uint64_t k = 0; k < n_noise; ++k)
    emit(static_cast<std::uint32_t>(uniform(key, counter++) * n_pix));
  for (std::uint32_t p : hot_) {
    const std::uint64_t n_hot = poisson(cfg_.hot_pixel_rate_hz * dt_s, key, counter);
    for (std::uint64_t k = 0; k < n_hot; ++k) emit(p);
  }
}

void toLogImage(const cv::Mat& intensity, double eps, bool quantize_8bit, cv::Mat& log_image) {
  log_image.create(intensity.size(), CV_32F);
  for (int y = 0; y < intensity.rows; ++y) {
    const float* in = intensity.ptr<float>(y);
    float* out = log_image.ptr<float>(y);
    for (int x = 0; x < intensity.cols; ++x) {
      double v = in[x];
      // ESIM-style pipelines log the stored 8-bit image, not the rendered float.
      if (quantize_8bit) v = std::round(std::clamp(v, 0.0, 1.0) * 255.0) / 255.0;
      out[x] = static_cast<float>(std::log(v + eps));
    }
  }
}

}  // namespace eds::sim
