#pragma once
// EventFrame (paper Eq. 2 with Gaussian weights): a packet of N events accumulated into a brightness
// increment image ΔL(u) on the undistorted pixel grid, each event's polarity weighted by a Gaussian in
// its index (centred mid-packet, sigma = N/6), voted bilinearly into 4 pixels, lightly blurred (3x3)
// and normalized to unit L2 norm (the tracker compares shapes, not magnitudes).
#include <cstddef>
#include <opencv2/core.hpp>
#include <vector>

#include "core/events.hpp"
#include "core/undistorter.hpp"

namespace eds {

struct EventFrameConfig {
  int num_events = 20000;         // N
  double overlap = 0.5;           // fraction of N shared with the previous packet, in [0, 1)
  double sigma_frac = 1.0 / 6.0;  // Gaussian sigma in units of N
  bool blur = true;               // 3x3 Gaussian
  // Throws std::invalid_argument naming the bad field.
  void validate() const;
  std::size_t stride() const;  // events between consecutive packets' starts
};

struct EventFrame {
  TimeNs t = 0;  // the median event's time
  TimeNs t_first = 0, t_last = 0;
  cv::Mat delta;  // CV_32F, undistorted pixel grid, unit L2 norm (all zero if no events)
};

class EventFrameBuilder {
 public:
  EventFrameBuilder(const Undistorter& undistorter, EventFrameConfig cfg);
  // Builds a frame from events [begin, begin + N) of `events` (must all exist).
  void build(const EventArray& events, std::size_t begin, EventFrame& out);
  const EventFrameConfig& config() const { return cfg_; }

 private:
  const Undistorter& und_;
  EventFrameConfig cfg_;
  std::vector<float> weights_;  // per index in the packet
  cv::Mat acc_;
};

// Bicubic (Catmull-Rom) sample of a CV_32F image with its derivatives in x and y; (x, y) must be at
// least 1 px inside the border (callers check with inside(..., 1.0)); pixel centres at integers.
double sampleBicubic(const cv::Mat& img, double x, double y, double* dx = nullptr, double* dy = nullptr);

}  // namespace eds
