#include "frontend/frame_quality.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <vector>

namespace eds {

namespace {

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// `format` with one %f-style conversion of `value`.
std::string describe(const char* format, double value) {
  char buf[160];
  std::snprintf(buf, sizeof buf, format, value);
  return buf;
}

}  // namespace

FrameQualityGate::FrameQualityGate(const FrameQualityConfig& cfg) : cfg_(cfg) {
  const auto fraction = [](double v) { return v > 0 && v <= 1; };
  if (!fraction(cfg.max_saturated) || !fraction(cfg.max_dark) || !(cfg.min_texture_ratio >= 0) ||
      !(cfg.max_brightness_ratio >= 1) || cfg.history < 1 || !(cfg.relearn_after_s >= 0) ||
      !(cfg.refused_max_shift > 0) || !(cfg.refused_max_turn_deg > 0) ||
      !(cfg.refused_min_residuals >= 0 && cfg.refused_min_residuals <= 1))
    throw std::invalid_argument(
        "frame_quality: max_saturated and max_dark must be in (0, 1], min_texture_ratio >= 0, "
        "max_brightness_ratio >= 1, history >= 1, relearn_after_s >= 0, refused_max_shift and "
        "refused_max_turn_deg > 0, refused_min_residuals in [0, 1]");
}

FrameStats measureFrame(const cv::Mat& gray8) {
  CV_Assert(gray8.type() == CV_8UC1 && gray8.rows >= 2 && gray8.cols >= 2);
  std::uint64_t sum = 0, saturated = 0, dark = 0, grad = 0;
  for (int y = 0; y < gray8.rows; ++y) {
    const std::uint8_t* row = gray8.ptr<std::uint8_t>(y);
    const std::uint8_t* below = gray8.ptr<std::uint8_t>(std::min(y + 1, gray8.rows - 1));
    for (int x = 0; x < gray8.cols; ++x) {
      const int v = row[x];
      sum += v;
      saturated += v >= 250;
      dark += v <= 5;
      if (x + 1 < gray8.cols) grad += std::abs(row[x + 1] - v);
      grad += std::abs(below[x] - v);
    }
  }
  const double n = static_cast<double>(gray8.total());
  return {sum / n, saturated / n, dark / n, grad / n};
}

cv::Mat normalizeRefusedFrame(const cv::Mat& gray8, double ref_mean) {
  CV_Assert(gray8.type() == CV_8UC1);
  const cv::Mat valid = (gray8 > 0) & (gray8 < 250);
  const int n = cv::countNonZero(valid);
  if (n == 0 || !(ref_mean > 0)) return {};
  const double scale = ref_mean / cv::mean(gray8, valid)[0] / 255.0;
  cv::Mat out;
  gray8.convertTo(out, CV_32F, scale);
  out.setTo(std::numeric_limits<float>::quiet_NaN(), ~valid);
  return out;
}

std::string FrameQualityGate::absoluteProblem(const FrameStats& s) const {
  if (s.saturated > cfg_.max_saturated)
    return describe("overexposed (%.0f %% of the pixels saturated)", 100 * s.saturated);
  if (s.dark > cfg_.max_dark) return describe("too dark (%.0f %% of the pixels black)", 100 * s.dark);
  return {};
}

std::string FrameQualityGate::relativeProblem(const FrameStats& s) const {
  if (accepted_.empty()) return {};
  std::vector<double> textures;
  for (const FrameStats& a : accepted_) textures.push_back(a.texture);
  const double ref_mean = referenceMean(), ref_texture = median(textures);
  if (s.texture < cfg_.min_texture_ratio * ref_texture)
    return describe("low contrast or blurred (texture %.2f of the recent frames')", s.texture / ref_texture);
  const double ratio = (s.mean + 1.0) / (ref_mean + 1.0);
  if (ratio > cfg_.max_brightness_ratio || ratio < 1.0 / cfg_.max_brightness_ratio)
    return describe("sudden exposure change (brightness x%.2f of the recent frames')", ratio);
  return {};
}

double FrameQualityGate::referenceMean() const {
  if (accepted_.empty()) return 0;
  std::vector<double> means;
  for (const FrameStats& a : accepted_) means.push_back(a.mean);
  return median(means);
}

std::string FrameQualityGate::check(TimeNs t, const cv::Mat& gray8) {
  if (!cfg_.enabled) return {};
  const FrameStats s = measureFrame(gray8);
  if (std::string why = absoluteProblem(s); !why.empty()) return why;
  std::string why = relativeProblem(s);
  if (!why.empty()) {
    if (refused_since_ < 0) refused_since_ = t;
    if (t - refused_since_ < fromSeconds(cfg_.relearn_after_s)) return why;
    accepted_.clear();  // refused for long enough: this is how frames look now
  }
  refused_since_ = -1;
  accepted_.push_back(s);
  while (static_cast<int>(accepted_.size()) > cfg_.history) accepted_.pop_front();
  return {};
}

}  // namespace eds
