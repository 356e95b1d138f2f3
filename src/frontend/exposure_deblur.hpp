#pragma once
// A motion-blurred frame made sharp with the events of its exposure (the event-based double integral of
// Pan et al., CVPR 2019). Under the event generation model a pixel's brightness at time s of the
// exposure [t - T/2, t + T/2] is L(s) = L(t) exp(C (E(s) - E(t))), E being its signed event count, and
// the frame is the mean of L over the exposure, so L(t) = B / mean_s exp(C (E(s) - E(t))). The event
// tracker takes its gradients from the keyframe's image: blurred, it predicts the events of an edge
// spread along the motion, where the sensor fires them at the sharp edge.
#include <array>
#include <cstddef>
#include <opencv2/core.hpp>
#include <vector>

#include "core/events.hpp"
#include "core/reflect.hpp"
#include "core/time.hpp"

namespace eds {

struct ExposureDeblurConfig {
  // The frames' exposure time in seconds, their time stamps at its middle; 0: unknown, estimated from
  // the first frames and their events when `estimate` (frontend/exposure_estimate.hpp) and the sensor
  // is at most a DAVIS346's size (a larger one keeps too many events meanwhile; a rig of an event
  // camera and a frame camera knows the frames' exposure), else none.
  double exposure_s = 0;
  bool estimate = true;
  // An estimated exposure shorter than this blurs too little at hand-held speeds to be worth deblurring,
  // and the estimate runs long: 15-21 ms on ESIM's instantaneous frames, 13-18 ms on 10 ms ones.
  double min_exposure_s = 0.025;
  // The log-intensity change of one event (the sensor's contrast threshold).
  double contrast = 0.2;
  // Throws std::invalid_argument naming the bad field.
  void validate() const;
};

EDS_FIELDS(ExposureDeblurConfig, exposure_s, estimate, min_exposure_s, contrast)

// The sharp image at time t of the 8-bit frame `gray8` (raw sensor pixels) exposed over
// [t - exposure/2, t + exposure/2), from the events [begin, end) of `events` (time-ordered; those
// outside the exposure or the sensor are ignored). 8-bit, the frame's size; pixels without events keep
// their value.
cv::Mat deblurFrame(const cv::Mat& gray8, const EventArray& events, std::size_t begin, std::size_t end,
                    TimeNs t, TimeNs exposure, double contrast);

// deblurFrame with its per-pixel state kept from one call to the next: the exposure estimate deblurs
// every frame a dozen times, and allocating the state each time cost as much as the integration.
class Deblurrer {
 public:
  cv::Mat operator()(const cv::Mat& gray8, const EventArray& events, std::size_t begin, std::size_t end,
                     TimeNs t, TimeNs exposure, double contrast);

 private:
  // One pixel's signed event count over the exposure and the integral of exp(C count) dt so far.
  struct PixelState {
    double integral = 0;  // ns
    TimeNs last = 0;      // time up to which the integral runs
    int count = 0;
    int count_at_t = 0;  // the count at the frame's time
    bool at_t = false;   // count_at_t is final
    bool seen = false;
  };
  // exp(C count), from a table for the counts a pixel reaches within one exposure.
  double expCount(double contrast, int count);

  static constexpr int kTableHalf = 64;
  std::vector<PixelState> state_;  // all reset between calls
  std::vector<std::size_t> touched_;
  std::array<double, 2 * kTableHalf + 1> exp_table_{};
  double table_contrast_ = 0;
};

}  // namespace eds
