#pragma once
// Events as structure-of-arrays: the per-event loops of the front-end read one field at a time, and
// contiguous arrays keep them cache friendly and vectorizable.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "core/time.hpp"

namespace eds {

struct EventArray {
  std::vector<TimeNs> t;         // nanoseconds
  std::vector<std::uint16_t> x;  // raw (distorted) pixel column
  std::vector<std::uint16_t> y;  // raw pixel row
  std::vector<std::int8_t> p;    // polarity: +1 or -1

  std::size_t size() const { return t.size(); }
  bool empty() const { return t.empty(); }
  void clear() {
    t.clear();
    x.clear();
    y.clear();
    p.clear();
  }
  void reserve(std::size_t n) {
    t.reserve(n);
    x.reserve(n);
    y.reserve(n);
    p.reserve(n);
  }
  void push_back(TimeNs ti, std::uint16_t xi, std::uint16_t yi, std::int8_t pi) {
    t.push_back(ti);
    x.push_back(xi);
    y.push_back(yi);
    p.push_back(pi);
  }
  void resize(std::size_t n) {
    t.resize(n);
    x.resize(n);
    y.resize(n);
    p.resize(n);
  }
};

// Appends src[from, from + n) to out.
inline void appendRange(EventArray& out, const EventArray& src, std::size_t from, std::size_t n) {
  const auto b = static_cast<std::ptrdiff_t>(from), e = b + static_cast<std::ptrdiff_t>(n);
  out.t.insert(out.t.end(), src.t.begin() + b, src.t.begin() + e);
  out.x.insert(out.x.end(), src.x.begin() + b, src.x.begin() + e);
  out.y.insert(out.y.end(), src.y.begin() + b, src.y.begin() + e);
  out.p.insert(out.p.end(), src.p.begin() + b, src.p.begin() + e);
}

// An inertial measurement, in SI units in the sensor's own frame: recorded and exposed, not yet used
// by the odometry.
struct ImuSample {
  TimeNs t = 0;
  double acc[3] = {0, 0, 0};   // linear acceleration, m/s^2
  double gyro[3] = {0, 0, 0};  // angular velocity, rad/s
};

// An external trigger edge (a flash, a shutter signal) recorded by the sensor beside its events.
struct TriggerEvent {
  TimeNs t = 0;
  std::uint8_t channel = 0;
  bool rising = false;
};

}  // namespace eds
