#include "frontend/event_frame.hpp"

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>

namespace eds {

void EventFrameConfig::validate() const {
  if (num_events <= 0)
    throw std::invalid_argument("event frame: num_events must be > 0, got " + std::to_string(num_events));
  if (!(overlap >= 0.0 && overlap < 1.0))
    throw std::invalid_argument("event frame: overlap must be in [0, 1), got " + std::to_string(overlap));
  if (!(sigma_frac > 0)) throw std::invalid_argument("event frame: sigma_frac must be > 0");
}

std::size_t EventFrameConfig::stride() const {
  return std::max<std::size_t>(1, static_cast<std::size_t>(std::llround(num_events * (1.0 - overlap))));
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
    last_index_.assign(raw_pixels, 0);
    last_polarity_.assign(raw_pixels, 0);
    stamp_.assign(raw_pixels, 0);
  }
}

void EventFrameBuilder::build(const EventArray& events, std::size_t begin, EventFrame& out) {
  const std::size_t n = static_cast<std::size_t>(cfg_.num_events);
  if (begin + n > events.size()) throw std::out_of_range("EventFrameBuilder: not enough events");
  const int W = acc_.cols, H = acc_.rows;
  acc_.setTo(0.0f);
  float* a = acc_.ptr<float>(0);
  const int raw_w = und_.raw().width, raw_h = und_.raw().height;
  auto vote = [&](const cv::Point2f& u, float v) {
    const float fx = std::floor(u.x), fy = std::floor(u.y);
    const int x0 = static_cast<int>(fx), y0 = static_cast<int>(fy);
    if (x0 < 0 || y0 < 0 || x0 + 1 >= W || y0 + 1 >= H) return;
    const float ax = u.x - fx, ay = u.y - fy;
    float* r0 = a + y0 * W + x0;
    float* r1 = r0 + W;
    r0[0] += v * (1 - ax) * (1 - ay);
    r0[1] += v * ax * (1 - ay);
    r1[0] += v * (1 - ax) * ay;
    r1[1] += v * ax * ay;
  };
  const bool compensate = cfg_.reversal_compensation;
  auto rawPixel = [&](std::size_t i) { return static_cast<std::size_t>(events.y[i]) * raw_w + events.x[i]; };
  auto remember = [&](std::size_t px, std::size_t i) {
    last_index_[px] = static_cast<std::int64_t>(i);
    last_polarity_[px] = events.p[i];
    stamp_[px] = generation_;
  };
  if (compensate) {
    if (++generation_ == 0) {  // wrapped: old stamps could alias
      std::fill(stamp_.begin(), stamp_.end(), 0u);
      generation_ = 1;
    }
    // The pixels' last events before the packet: up to N events back, where the array still has them.
    for (std::size_t i = begin - std::min(begin, n); i < begin; ++i)
      if (events.x[i] < raw_w && events.y[i] < raw_h) remember(rawPixel(i), i);
  }
  const auto b = static_cast<std::int64_t>(begin);
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t i = begin + k;
    const int xr = events.x[i], yr = events.y[i];
    if (xr >= raw_w || yr >= raw_h) continue;
    const cv::Point2f u = und_.eventLut(xr, yr);
    vote(u, weights_[k] * static_cast<float>(events.p[i]));
    if (!compensate) continue;
    const std::size_t px = rawPixel(i);
    if (stamp_[px] == generation_ && last_polarity_[px] != events.p[i]) {
      const std::int64_t mid = (last_index_[px] + static_cast<std::int64_t>(i)) / 2 - b;
      if (mid >= 0) vote(u, weights_[static_cast<std::size_t>(mid)] * static_cast<float>(events.p[i]));
    }
    remember(px, i);
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

namespace {
// Catmull-Rom weights and their derivatives for fraction t in [0, 1).
inline void cubicWeights(double t, double w[4], double dw[4]) {
  const double t2 = t * t, t3 = t2 * t;
  w[0] = 0.5 * (-t3 + 2 * t2 - t);
  w[1] = 0.5 * (3 * t3 - 5 * t2 + 2);
  w[2] = 0.5 * (-3 * t3 + 4 * t2 + t);
  w[3] = 0.5 * (t3 - t2);
  dw[0] = 0.5 * (-3 * t2 + 4 * t - 1);
  dw[1] = 0.5 * (9 * t2 - 10 * t);
  dw[2] = 0.5 * (-9 * t2 + 8 * t + 1);
  dw[3] = 0.5 * (3 * t2 - 2 * t);
}
}  // namespace

double sampleBicubic(const cv::Mat& img, double x, double y, double* dx, double* dy) {
  const int W = img.cols, H = img.rows;
  const double fx = std::floor(x), fy = std::floor(y);
  const int x0 = static_cast<int>(fx), y0 = static_cast<int>(fy);
  // Double accumulation: the tracker's numeric Jacobian checks need more than float's 7 digits.
  double wx[4], dwx[4], wy[4], dwy[4];
  cubicWeights(x - fx, wx, dwx);
  cubicWeights(y - fy, wy, dwy);
  double val = 0, gx = 0, gy = 0;
  for (int j = 0; j < 4; ++j) {
    const int yy = std::clamp(y0 - 1 + j, 0, H - 1);
    const float* row = img.ptr<float>(yy);
    double rv = 0, rd = 0;
    for (int i = 0; i < 4; ++i) {
      const double p = row[std::clamp(x0 - 1 + i, 0, W - 1)];
      rv += wx[i] * p;
      rd += dwx[i] * p;
    }
    val += wy[j] * rv;
    gx += wy[j] * rd;
    gy += dwy[j] * rv;
  }
  if (dx) *dx = gx;
  if (dy) *dy = gy;
  return val;
}

}  // namespace eds
