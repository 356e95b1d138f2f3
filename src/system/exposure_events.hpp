#pragma once
// The events of each frame's exposure, kept until the exposure has ended, so that the frame's image can
// be deblurred with them (frontend/exposure_deblur.hpp). The stream merge hands each exposure on at the
// same point of the merged order whatever the chunks the events came in: once the frame has been
// processed and before the first item later than the exposure's end.
#include <cstddef>
#include <deque>
#include <functional>
#include <opencv2/core.hpp>

#include "core/events.hpp"
#include "core/time.hpp"

namespace eds {

class ExposureEvents {
 public:
  // What an ended exposure gives: the frame's time, its exposure (the recorded one, else the default)
  // and whether it was recorded, its 8-bit image, and the events that were kept (events[begin, end)
  // spans the exposure).
  using Handler = std::function<void(TimeNs t, TimeNs exposure, bool recorded, const cv::Mat& gray8,
                                     const EventArray& events, std::size_t begin, std::size_t end)>;

  // `exposure`: the default, and the longest a frame's recorded exposure may be.
  explicit ExposureEvents(TimeNs exposure);
  TimeNs exposure() const { return exposure_; }
  // From now on (an estimate replacing the longest exposure assumed until it came).
  void setExposure(TimeNs exposure);
  // Checked events, in time order.
  void addEvents(const EventArray& ev, std::size_t begin, std::size_t end);
  // `recorded`: the frame's own exposure as the camera recorded it (0: none, the default applies).
  // std::invalid_argument when longer than the default given at construction.
  void addFrame(TimeNs t, const cv::Mat& gray8, TimeNs recorded = 0);
  // Hands on, oldest first, every frame whose exposure ended at or before `up_to` and whose time is
  // not after `processed` (the frame itself went first), then forgets it. A frame whose exposure began
  // before the oldest event kept (it came more than an exposure late) is dropped unhandled.
  void endExposures(TimeNs up_to, TimeNs processed, const Handler& handle);

 private:
  struct Frame {
    TimeNs t;
    cv::Mat gray8;
    TimeNs recorded;
  };
  void trim();

  TimeNs exposure_;
  TimeNs longest_;  // of a recorded exposure: the events are kept for the default given at first
  EventArray ev_;
  std::size_t first_ = 0;  // ev_[first_...] are kept; the rest wait to be erased in one go
  TimeNs newest_ = 0;
  bool any_ = false;
  TimeNs kept_from_ = 0;  // no event before this time was dropped
  std::deque<Frame> frames_;
};

}  // namespace eds
