#pragma once
// Faults of the event stream alone (the frames see the true scene), for robustness tests: USB drops (no
// events for a while), bursts of background noise, a flickering light over a patch of the image, and a
// constant offset between the events' clock and the frames'. Hot pixels are the simulator's own
// (EventSimConfig). Applied between the simulator and its writer.
#include <cstdint>
#include <vector>

#include "sim/simulator.hpp"

namespace eds::sim {

struct EventFaults {
  struct Window {
    TimeNs t0 = 0, t1 = 0;
    double value = 0;  // bursts: noise events per pixel per second; flicker: the light's frequency, Hz
  };
  std::vector<Window> gaps;     // [t0, t1): no event reaches the host
  std::vector<Window> bursts;   // uniform noise of both polarities over the whole sensor
  std::vector<Window> flicker;  // a light flickering over a quarter-size patch of the upper left
  TimeNs offset = 0;            // added to every event time (events late when > 0)
  std::uint64_t seed = 1;

  bool any() const { return !gaps.empty() || !bursts.empty() || !flicker.empty() || offset != 0; }
};

class EventFaultSink : public SimSink {
 public:
  EventFaultSink(SimSink& inner, const EventFaults& faults, int width, int height)
      : inner_(inner), faults_(faults), width_(width), height_(height) {}
  void onEvents(const EventArray& events) override;
  void onFrame(TimeNs t, const cv::Mat& intensity, const cv::Mat& depth) override {
    inner_.onFrame(t, intensity, depth);
  }

 private:
  // The faults' own events in (from, to], time-ordered.
  void extraEvents(TimeNs from, TimeNs to, EventArray& out);
  void burstEvents(const EventFaults::Window& w, TimeNs from, TimeNs to, EventArray& out);
  void flickerEvents(const EventFaults::Window& w, TimeNs from, TimeNs to, EventArray& out) const;

  SimSink& inner_;
  EventFaults faults_;
  int width_, height_;
  TimeNs done_ = INT64_MIN;  // events up to this time have been passed on
  std::uint64_t draws_ = 0;
  EventArray extra_, merged_;
};

}  // namespace eds::sim
