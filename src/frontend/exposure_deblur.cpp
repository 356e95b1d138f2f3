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

double Deblurrer::expCount(double contrast, int count) {
  if (contrast != table_contrast_) {
    table_contrast_ = contrast;
    for (int k = -kTableHalf; k <= kTableHalf; ++k) exp_table_[k + kTableHalf] = std::exp(contrast * k);
  }
  return count >= -kTableHalf && count <= kTableHalf ? exp_table_[count + kTableHalf]
                                                     : std::exp(contrast * count);
}

cv::Mat Deblurrer::operator()(const cv::Mat& gray8, const EventArray& events, std::size_t begin,
                              std::size_t end, TimeNs t, TimeNs exposure, double contrast) {
  if (gray8.type() != CV_8UC1 || gray8.empty())
    throw std::invalid_argument("deblurFrame: the frame must be 8-bit gray");
  if (exposure <= 0 || !(contrast > 0)) throw std::invalid_argument("deblurFrame: exposure and contrast > 0");
  const int W = gray8.cols, H = gray8.rows;
  const TimeNs t0 = t - exposure / 2, t1 = t0 + exposure;
  if (state_.size() != static_cast<std::size_t>(W) * H) state_.assign(static_cast<std::size_t>(W) * H, {});
  touched_.clear();  // pixels with events, once each
  end = std::min(end, events.size());
  for (std::size_t i = begin; i < end; ++i) {
    const TimeNs te = events.t[i];
    if (te < t0) continue;
    if (te >= t1) break;
    if (events.x[i] >= W || events.y[i] >= H) continue;
    const std::size_t k = static_cast<std::size_t>(events.y[i]) * W + events.x[i];
    PixelState& s = state_[k];
    if (!s.seen) s.seen = true, s.last = t0, touched_.push_back(k);
    if (te >= t && !s.at_t) s.count_at_t = s.count, s.at_t = true;
    s.integral += expCount(contrast, s.count) * static_cast<double>(te - s.last);
    s.last = te;
    s.count += events.p[i] > 0 ? 1 : -1;
  }
  // L = log(I + eps) as a sensor's log stage has it: dark pixels do not explode.
  constexpr double kEps = 1e-3;
  cv::Mat out = gray8.clone();  // continuous, whatever the input's layout
  for (const std::size_t k : touched_) {
    PixelState& s = state_[k];
    if (!s.at_t) s.count_at_t = s.count;
    s.integral += expCount(contrast, s.count) * static_cast<double>(t1 - s.last);
    const double mean = s.integral / static_cast<double>(exposure);
    const double B = out.data[k] / 255.0 + kEps;
    const double L = B * expCount(contrast, s.count_at_t) / mean - kEps;
    out.data[k] = static_cast<std::uint8_t>(std::clamp(std::lround(L * 255.0), 0L, 255L));
    s = PixelState{};  // ready for the next frame
  }
  return out;
}

cv::Mat deblurFrame(const cv::Mat& gray8, const EventArray& events, std::size_t begin, std::size_t end,
                    TimeNs t, TimeNs exposure, double contrast) {
  return Deblurrer()(gray8, events, begin, end, t, exposure, contrast);
}

}  // namespace eds
