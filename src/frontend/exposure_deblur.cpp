#include "frontend/exposure_deblur.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

namespace eds {

void ExposureDeblurConfig::validate() const {
  if (!(exposure_s >= 0 && exposure_s <= 1))
    throw std::invalid_argument("deblur: exposure_s must be in [0, 1] s (0: off), got " +
                                std::to_string(exposure_s));
  if (!(min_exposure_s >= 0 && min_exposure_s <= 1))
    throw std::invalid_argument("deblur: min_exposure_s must be in [0, 1] s, got " +
                                std::to_string(min_exposure_s));
  if (!(contrast > 0 && contrast <= 2))
    throw std::invalid_argument("deblur: contrast must be in (0, 2], got " + std::to_string(contrast));
}

namespace {

// One pixel's signed event count over the exposure and the integral of exp(C count) dt so far.
struct PixelState {
  double integral = 0;  // ns
  TimeNs last = 0;      // time up to which the integral runs
  int count = 0;
  int count_at_t = 0;  // the count at the frame's time
  bool at_t = false;   // count_at_t is final
  bool seen = false;
};

}  // namespace

cv::Mat deblurFrame(const cv::Mat& gray8, const EventArray& events, std::size_t begin, std::size_t end,
                    TimeNs t, TimeNs exposure, double contrast) {
  if (gray8.type() != CV_8UC1 || gray8.empty())
    throw std::invalid_argument("deblurFrame: the frame must be 8-bit gray");
  if (exposure <= 0 || !(contrast > 0)) throw std::invalid_argument("deblurFrame: exposure and contrast > 0");
  const int W = gray8.cols, H = gray8.rows;
  const TimeNs t0 = t - exposure / 2, t1 = t0 + exposure;
  std::vector<PixelState> state(static_cast<std::size_t>(W) * H);
  std::vector<std::size_t> touched;  // pixels with events, once each
  end = std::min(end, events.size());
  for (std::size_t i = begin; i < end; ++i) {
    const TimeNs te = events.t[i];
    if (te < t0) continue;
    if (te >= t1) break;
    if (events.x[i] >= W || events.y[i] >= H) continue;
    const std::size_t k = static_cast<std::size_t>(events.y[i]) * W + events.x[i];
    PixelState& s = state[k];
    if (!s.seen) s.seen = true, s.last = t0, touched.push_back(k);
    if (te >= t && !s.at_t) s.count_at_t = s.count, s.at_t = true;
    s.integral += std::exp(contrast * s.count) * static_cast<double>(te - s.last);
    s.last = te;
    s.count += events.p[i] > 0 ? 1 : -1;
  }
  // L = log(I + eps) as a sensor's log stage has it: dark pixels do not explode.
  constexpr double kEps = 1e-3;
  cv::Mat out = gray8.clone();  // continuous, whatever the input's layout
  for (const std::size_t k : touched) {
    PixelState& s = state[k];
    if (!s.at_t) s.count_at_t = s.count;
    s.integral += std::exp(contrast * s.count) * static_cast<double>(t1 - s.last);
    const double mean = s.integral / static_cast<double>(exposure);
    const double B = out.data[k] / 255.0 + kEps;
    const double L = B * std::exp(contrast * s.count_at_t) / mean - kEps;
    out.data[k] = static_cast<std::uint8_t>(std::clamp(std::lround(L * 255.0), 0L, 255L));
  }
  return out;
}

}  // namespace eds
