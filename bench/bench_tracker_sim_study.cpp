// Accuracy study of the event tracker from one event frame: the simulated case
// of tests/frontend/test_tracker_on_sim.cpp (plane at ~1 m, 240x180, keyframe with true depth, one event
// frame 40 ms later, start 1 deg and 1 cm off), repeated with the keyframe at several times of the
// hand-held motion and with three sensors: a DVS (hysteresis, the simulator's default and ESIM's), the
// same events with the builder's reversal compensation, and an idealized sensor without hysteresis.
// Prints the error of each case and the medians. Not a timing benchmark.
// Usage: bench_tracker_sim_study [C=0.15] [N=30000]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <vector>

#include "support/sim_event_frame_case.hpp"

namespace {

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const std::size_t m = v.size() / 2;
  return v.size() % 2 ? v[m] : 0.5 * (v[m - 1] + v[m]);
}

}  // namespace

int main(int argc, char** argv) {
  using namespace eds;
  const double contrast = argc > 1 ? std::atof(argv[1]) : 0.15;
  const int num_events = argc > 2 ? std::atoi(argv[2]) : 30000;
  if (!(contrast > 0) || num_events <= 0) {
    std::fprintf(stderr, "usage: %s [C > 0] [N > 0]\n", argv[0]);
    return 2;
  }
  struct Sensor {
    const char* name;
    bool hysteresis, compensation;
  };
  const Sensor sensors[] = {{"DVS", true, false}, {"DVS+comp", true, true}, {"ideal", false, false}};
  const SE3 offset(SO3::exp(Vec3(0.6, -0.8, 0.0).normalized() * (M_PI / 180.0)), Vec3(0.006, -0.008, 0.0));
  std::vector<double> trans[3], rot[3];
  std::printf("C = %.3f, N = %d; error after tracking from 1 deg / 1 cm off (mm, deg)\n", contrast,
              num_events);
  std::printf("%8s %16s | %16s | %16s | %16s\n", "kf [s]", "motion", sensors[0].name, sensors[1].name,
              sensors[2].name);
  for (int k = 0; k <= 10; ++k) {
    const double t_kf = 0.05 * k;
    std::printf("%8.2f", t_kf);
    for (int s = 0; s < 3; ++s) {
      SimEventFrameCaseConfig cfg;
      cfg.keyframe_time_s = t_kf;
      cfg.contrast = contrast;
      cfg.num_events = num_events;
      cfg.hysteresis = sensors[s].hysteresis;
      cfg.reversal_compensation = sensors[s].compensation;
      try {
        const SimEventFrameCase c = makeSimEventFrameCase(cfg);
        if (s == 0)
          std::printf(" %6.1f mm %5.2f deg |", c.T_ef_kf_true.translation().norm() * 1e3,
                      c.T_ef_kf_true.so3().angle() * 180 / M_PI);
        const SimCaseSolution sol = trackSimCase(c, offset);
        trans[s].push_back(sol.trans_err_mm);
        rot[s].push_back(sol.rot_err_deg);
        std::printf(" %7.3f %7.4f%s|", sol.trans_err_mm, sol.rot_err_deg, sol.first.ok ? " " : "!");
      } catch (const std::exception& e) {
        std::printf(" %16s |", "no case");
        std::fprintf(stderr, "kf %.2f s, %s: %s\n", t_kf, sensors[s].name, e.what());
      }
    }
    std::printf("\n");
  }
  std::printf("%21s |", "median");
  for (int s = 0; s < 3; ++s) std::printf(" %7.3f %7.4f |", median(trans[s]), median(rot[s]));
  std::printf("\n");
  return 0;
}
