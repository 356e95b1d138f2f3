#include "frontend/exposure_estimate.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "frontend/exposure_deblur.hpp"

namespace eds {

namespace {

// Exposures tried, in seconds: the blur of a few milliseconds up to most of a 12 Hz frame interval.
constexpr double kCandidates[] = {0,
                                  0.0025,
                                  0.005,
                                  0.0075,
                                  0.01,
                                  0.015,
                                  0.02,
                                  0.025,
                                  0.03,
                                  0.04,
                                  0.05,
                                  0.06,
                                  ExposureEstimator::kLongestExposureSeconds};
// Fewer events than this per pixel between two frames: too little motion to blur a frame.
constexpr double kMinEventsPerPixel = 0.2;
// A pair whose worst candidate scores less than this times its best cannot tell the exposures apart.
constexpr double kMinContrast = 1.5;
constexpr double kLogOffset = 0.02;  // log(I + offset): dark pixels' noise does not dominate

// The vertex of the parabola through (x0, y0), (x1, y1), (x2, y2) when it is a minimum between x0 and x2;
// else x1.
double parabolaMin(double x0, double y0, double x1, double y1, double x2, double y2) {
  const double d01 = (y1 - y0) / (x1 - x0), d12 = (y2 - y1) / (x2 - x1);
  const double a = (d12 - d01) / (x2 - x0);
  if (!(a > 0)) return x1;
  const double x = 0.5 * (x0 + x1) - d01 / (2 * a);
  return std::clamp(x, x0, x2);
}

}  // namespace

ExposureEstimator::ExposureEstimator(cv::Size sensor, double contrast) : contrast_(contrast) {
  if (sensor.width <= 4 || sensor.height <= 4 || !(contrast > 0))
    throw std::invalid_argument("ExposureEstimator: bad sensor size or contrast");
  const int w = std::min(sensor.width, kMaxWidth), h = std::min(sensor.height, kMaxHeight);
  roi_ = cv::Rect((sensor.width - w) / 2, (sensor.height - h) / 2, w, h);
  log_lut_.create(1, 256, CV_64F);
  for (int v = 0; v < 256; ++v) log_lut_.at<double>(v) = std::log(v / 255.0 + kLogOffset);
}

void ExposureEstimator::addEvents(const EventArray& ev, std::size_t begin, std::size_t end) {
  if (done_) return;
  end = std::min(end, ev.size());
  for (std::size_t i = begin; i < end; ++i) {
    const int x = ev.x[i] - roi_.x, y = ev.y[i] - roi_.y;
    if (x < 0 || y < 0 || x >= roi_.width || y >= roi_.height) continue;
    ev_.t.push_back(ev.t[i]);
    ev_.x.push_back(static_cast<std::uint16_t>(x));
    ev_.y.push_back(static_cast<std::uint16_t>(y));
    ev_.p.push_back(ev.p[i]);
  }
}

void ExposureEstimator::addFrame(TimeNs t, const cv::Mat& gray8) {
  if (done_) return;
  frames_.push_back({t, gray8(roi_).clone()});
  if (candidates_s_.empty() && frames_.size() >= 2) {
    // At most the first frame interval: a frame's exposure cannot be longer.
    const double interval = toSeconds(frames_[1].t - frames_[0].t);
    for (const double c : kCandidates)
      if (c <= interval) candidates_s_.push_back(c);
    score_.assign(candidates_s_.size(), 0.0);
  }
  if (frames_.size() < 3) return;
  const TimeNs half_max = fromSeconds(candidates_s_.back() / 2);
  // The events around the second frame of the pair are all in once a frame after them came.
  if (frames_[2].t >= frames_[1].t + half_max) {
    scorePair(frames_[0], frames_[1]);
    frames_.pop_front();
  }
  if (scored_ >= kPairsNeeded || tried_ >= kMaxPairsScored || ++frames_seen_ >= kMaxFrames) return finish();
  // Events before the oldest frame's widest exposure are needed no more.
  const auto keep =
      std::lower_bound(ev_.t.begin(), ev_.t.end(), frames_.front().t - half_max) - ev_.t.begin();
  ev_.t.erase(ev_.t.begin(), ev_.t.begin() + keep);
  ev_.x.erase(ev_.x.begin(), ev_.x.begin() + keep);
  ev_.y.erase(ev_.y.begin(), ev_.y.begin() + keep);
  ev_.p.erase(ev_.p.begin(), ev_.p.begin() + keep);
}

cv::Mat ExposureEstimator::deblur(const Frame& f, TimeNs exposure) {
  const auto from = std::lower_bound(ev_.t.begin(), ev_.t.end(), f.t - exposure / 2) - ev_.t.begin();
  return deblurrer_(f.gray8, ev_, static_cast<std::size_t>(from), ev_.size(), f.t, exposure, contrast_);
}

std::vector<cv::Mat> ExposureEstimator::logImages(const Frame& f) {
  std::vector<cv::Mat> out(candidates_s_.size());
  for (std::size_t j = 0; j < candidates_s_.size(); ++j) {
    const TimeNs T = fromSeconds(candidates_s_[j]);
    cv::LUT(T > 0 ? deblur(f, T) : f.gray8, log_lut_, out[j]);
  }
  return out;
}

void ExposureEstimator::scorePair(const Frame& a, const Frame& b) {
  const int W = roi_.width, H = roi_.height;
  // The signed event count between the two frames.
  cv::Mat count(H, W, CV_32F, cv::Scalar(0));
  const auto first = std::lower_bound(ev_.t.begin(), ev_.t.end(), a.t) - ev_.t.begin();
  const auto last = std::lower_bound(ev_.t.begin(), ev_.t.end(), b.t) - ev_.t.begin();
  if (static_cast<double>(last - first) < kMinEventsPerPixel * W * H) return;
  ++tried_;
  for (auto i = first; i < last; ++i) count.at<float>(ev_.y[i], ev_.x[i]) += ev_.p[i] > 0 ? 1.f : -1.f;
  const std::vector<cv::Mat> La = logs_t_ == a.t ? std::move(logs_) : logImages(a);
  logs_ = logImages(b);
  logs_t_ = b.t;
  std::vector<double> cost(candidates_s_.size());
  for (std::size_t j = 0; j < candidates_s_.size(); ++j) {
    double sum = 0;
    int n = 0;
    for (int y = 2; y < H - 2; ++y) {
      const std::uint8_t *ra = a.gray8.ptr<std::uint8_t>(y), *rb = b.gray8.ptr<std::uint8_t>(y);
      const double *la = La[j].ptr<double>(y), *lb = logs_[j].ptr<double>(y);
      const float* c = count.ptr<float>(y);
      for (int x = 2; x < W - 2; ++x) {
        if (ra[x] <= 2 || rb[x] <= 2 || ra[x] >= 250 || rb[x] >= 250) continue;  // clipped: outside the model
        const double r = lb[x] - la[x] - contrast_ * c[x];
        sum += r * r, ++n;
      }
    }
    cost[j] = n > 0 ? sum / n : 0.0;
  }
  const auto [lo, hi] = std::minmax_element(cost.begin(), cost.end());
  // Its minimum at the longest exposure tried is no minimum: the pair cannot bound the exposure.
  if (!(*lo > 0) || *hi < kMinContrast * *lo || lo == cost.end() - 1) return;
  for (std::size_t j = 0; j < cost.size(); ++j) score_[j] += cost[j] / *lo;
  ++scored_;
}

void ExposureEstimator::finish() {
  done_ = true;
  ev_ = EventArray();
  frames_.clear();
  logs_.clear();
  if (scored_ == 0) return;
  const auto j = static_cast<std::size_t>(std::min_element(score_.begin(), score_.end()) - score_.begin());
  exposure_s_ = candidates_s_[j];
  if (j > 0 && j + 1 < score_.size())
    exposure_s_ = parabolaMin(candidates_s_[j - 1], score_[j - 1], candidates_s_[j], score_[j],
                              candidates_s_[j + 1], score_[j + 1]);
}

}  // namespace eds
