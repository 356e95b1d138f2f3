#pragma once
// Frames the odometry must not trust: too dark, blown out, robbed of texture (a hand over the lens,
// heavy blur) or a sudden exposure jump. Frames are not high-dynamic-range, events are: a frame that
// fails here is kept out of tracking, keyframes and the map, and the events carry the pose meanwhile.
// Measured on the raw 8-bit frame, absolutely and against the frames accepted just before it.
#include <deque>
#include <opencv2/core.hpp>
#include <string>

#include "core/reflect.hpp"
#include "core/time.hpp"

namespace eds {

struct FrameQualityConfig {
  bool enabled = true;
  double max_saturated = 0.3;         // fraction of pixels at 250 or more
  double max_dark = 0.7;              // fraction of pixels at 5 or less
  double min_texture_ratio = 0.35;    // mean gradient against the median of the recent accepted frames
  double max_brightness_ratio = 3.0;  // mean intensity jump, either way, against the same
  int history = 15;                   // accepted frames the reference is the median of
  // A new normal: after this long of frames refused only against the recent ones (none absolutely),
  // the reference starts again from the current frames (a light switched off for good).
  double relearn_after_s = 2.0;
  // A refused frame still gives a pose, never a keyframe or map point: its clipped pixels left out and
  // its brightness scaled to the recent frames', it is aligned from the events' pose (without events,
  // the constant-velocity prediction) and kept when it lands within these bounds of that start
  // (translation as a fraction of the reference keyframe's median depth) on at least this fraction of
  // the residuals the last usable frame had (a frame blown out but for a few dark spots does not hold
  // the pose).
  bool track_refused = true;
  double refused_max_shift = 0.02;
  double refused_max_turn_deg = 2.0;
  double refused_min_residuals = 0.25;
};

EDS_FIELDS(FrameQualityConfig, enabled, max_saturated, max_dark, min_texture_ratio, max_brightness_ratio,
           history, relearn_after_s, track_refused, refused_max_shift, refused_max_turn_deg,
           refused_min_residuals)

struct FrameStats {
  double mean = 0;       // intensity, 0..255
  double saturated = 0;  // fraction of pixels >= 250
  double dark = 0;       // fraction of pixels <= 5
  double texture = 0;    // mean |horizontal| + |vertical| neighbour difference
};

FrameStats measureFrame(const cv::Mat& gray8);

// A refused frame made fit for alignment: CV_32F, its clipped pixels (0, or 250 and above) NaN, the
// others scaled so that their mean is `ref_mean` / 255 (the recent frames' brightness; the alignment's
// own brightness parameters absorb what the clipping biases). Empty when no pixel is left.
cv::Mat normalizeRefusedFrame(const cv::Mat& gray8, double ref_mean);

class FrameQualityGate {
 public:
  explicit FrameQualityGate(const FrameQualityConfig& cfg);
  // Empty when the frame at time t can be used (it then joins the reference); else why it cannot.
  std::string check(TimeNs t, const cv::Mat& gray8);
  // Median mean intensity of the recent accepted frames (0 before the first).
  double referenceMean() const;

 private:
  std::string absoluteProblem(const FrameStats& s) const;
  std::string relativeProblem(const FrameStats& s) const;

  FrameQualityConfig cfg_;
  std::deque<FrameStats> accepted_;
  TimeNs refused_since_ = -1;  // first of the current run of relative refusals
};

}  // namespace eds
