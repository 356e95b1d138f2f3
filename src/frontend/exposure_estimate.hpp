#pragma once
// The frames' exposure time estimated from two consecutive frames and the events between and around
// them (the consistency of the event-based double integral, Pan et al. 2019): deblurred with the right
// exposure T, the sharp images at the two frames' times differ by C times the events between them,
//     log L_b(T) - log L_a(T) = C E(t_a, t_b),
// while a wrong T leaves each image blurred or over-sharpened and the difference off. Each pair with
// enough motion scores every candidate T; the estimate is the minimum of their sum. Without motion a
// pair says nothing about the exposure (nor does blur matter then), and is skipped.
#include <cstddef>
#include <deque>
#include <opencv2/core.hpp>
#include <vector>

#include "core/events.hpp"
#include "core/time.hpp"
#include "frontend/exposure_deblur.hpp"

namespace eds {

class ExposureEstimator {
 public:
  // `sensor`: the raw frame size; at most a central region of kMaxWidth x kMaxHeight pixels is used.
  ExposureEstimator(cv::Size sensor, double contrast);

  // Checked events, in time order.
  void addEvents(const EventArray& ev, std::size_t begin, std::size_t end);
  // A raw 8-bit frame, after every event before its time was added. Scores the pair of the two frames
  // before it once the events around the second are in.
  void addFrame(TimeNs t, const cv::Mat& gray8);
  // An estimate is there (after enough pairs), or the frames gave too little motion for too long.
  bool done() const { return done_; }
  // The estimated exposure in seconds (0 when none was found); valid once done().
  double exposureSeconds() const { return exposure_s_; }
  int pairsScored() const { return scored_; }

  static constexpr int kMaxWidth = 346, kMaxHeight = 260;  // a DAVIS346
  static constexpr int kPairsNeeded = 5;
  static constexpr double kLongestExposureSeconds = 0.08;  // the longest tried
  static constexpr int kMaxPairsScored = 200;              // pairs with motion tried, an estimate or not
  static constexpr int kMaxFrames = 600;                   // frames without enough pairs: no estimate

 private:
  struct Frame {
    TimeNs t;
    cv::Mat gray8;  // the region used
  };
  void scorePair(const Frame& a, const Frame& b);
  cv::Mat deblur(const Frame& f, TimeNs exposure);
  // log(L + offset) of the frame deblurred with each candidate exposure (CV_64F; the frame for 0).
  std::vector<cv::Mat> logImages(const Frame& f);
  void finish();

  cv::Rect roi_;
  double contrast_;
  std::vector<double> candidates_s_;  // exposures tried (s)
  std::vector<double> score_;         // summed over the scored pairs, each relative to its minimum
  EventArray ev_;                     // in the region, its coordinates
  std::deque<Frame> frames_;
  Deblurrer deblurrer_;
  cv::Mat log_lut_;  // log(v / 255 + offset) for every 8-bit v
  // The second frame of the last scored pair is the first of the next: its images are kept.
  TimeNs logs_t_ = -1;
  std::vector<cv::Mat> logs_;
  int scored_ = 0, tried_ = 0, frames_seen_ = 0;
  bool done_ = false;
  double exposure_s_ = 0;
};

}  // namespace eds
