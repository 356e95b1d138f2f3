// Event tracker cost per event frame (build + solve) at 240x180 with 2,000 and 5,000 points, one core:
// events of a textured plane 1 m away from the simulator, a keyframe with true depth, and every event
// frame of 20,000 events (50% overlap) tracked warm-started from the previous one, as in `eds track`.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>

#include "frontend/event_tracker.hpp"
#include "frontend/point_selection.hpp"
#include "sim/presets.hpp"
#include "sim/simulator.hpp"

namespace {

using namespace eds;

struct Collect : sim::SimSink {
  void onEvents(const EventArray& e) override {
    for (std::size_t i = 0; i < e.size(); ++i) events.push_back(e.t[i], e.x[i], e.y[i], e.p[i]);
  }
  void onFrame(TimeNs, const cv::Mat& intensity, const cv::Mat& depth) override {
    if (image.empty()) image = intensity.clone(), depth0 = depth.clone();
  }
  EventArray events;
  cv::Mat image, depth0;
};

struct Fixture {
  CameraModel cam;
  Collect data;
  Keyframe kf;
  Fixture() {
    const sim::Motion motion(sim::handheldMotion(0.5, 3));
    sim::Scene scene = sim::makePreset("planar", motion, 3);
    for (auto& spec : scene.texture_specs) spec.blur_sigma = 2.0;
    scene.loadTextures();
    cam.width = 240, cam.height = 180;
    cam.fx = cam.fy = 200;
    cam.cx = 119.5, cam.cy = 89.5;
    sim::SimConfig cfg;
    cfg.fps = 1;
    sim::Simulator(scene, cam, motion, cfg).run(motion.start(), motion.end(), data);
    setKeyframeImage(kf, data.image);
    PointSelectionConfig pc;
    pc.fraction = 0.3;
    for (const cv::Point& p : selectPoints(kf.grad_x, kf.grad_y, pc)) {
      const float z = data.depth0.at<float>(p.y, p.x);
      if (z > 0)
        kf.points.push_back({static_cast<float>(p.x), static_cast<float>(p.y), kf.grad_x.at<float>(p.y, p.x),
                             kf.grad_y.at<float>(p.y, p.x), 1.0 / z});
    }
  }
};

Fixture& fixture() {
  static Fixture f;
  return f;
}

void BM_TrackEventFrame(benchmark::State& state) {
  Fixture& f = fixture();
  Keyframe kf = f.kf;
  // The strongest-gradient points, as a tighter selection would keep.
  std::sort(kf.points.begin(), kf.points.end(), [](const KeyframePoint& a, const KeyframePoint& b) {
    return a.gx * a.gx + a.gy * a.gy > b.gx * b.gx + b.gy * b.gy;
  });
  kf.points.resize(std::min<std::size_t>(kf.points.size(), static_cast<std::size_t>(state.range(0))));
  const Undistorter und(f.cam);
  EventFrameConfig efc;
  efc.reversal_compensation = state.range(1) != 0;
  EventFrameBuilder builder(und, efc);
  EventTracker tracker(f.cam, {});
  tracker.setKeyframe(kf);
  std::vector<double> ms;
  EventFrame ef;
  SE3 T;
  Vec6 nu = Vec6::Zero();
  std::size_t begin = 0;
  for (auto _ : state) {
    if (begin + efc.num_events > f.data.events.size()) begin = 0, T = SE3(), nu.setZero();
    const auto t0 = std::chrono::steady_clock::now();
    builder.build(f.data.events, begin, ef);
    const TrackResult r = tracker.track(ef, T, nu, nu.norm() > 0 ? 1 : 0);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    benchmark::DoNotOptimize(r.cost);
    begin += efc.stride();
  }
  std::sort(ms.begin(), ms.end());
  state.counters["points"] = static_cast<double>(kf.points.size());
  state.counters["median_ms"] = ms[ms.size() / 2];
  state.counters["p95_ms"] = ms[std::min(ms.size() - 1, static_cast<std::size_t>(0.95 * ms.size()))];
}

// Second argument: reversal compensation on (the default) or off, to show what it costs.
BENCHMARK(BM_TrackEventFrame)
    ->Args({1000, 1})
    ->Args({2000, 1})
    ->Args({5000, 1})
    ->Args({2000, 0})
    ->Args({5000, 0})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0);

// Building one event frame alone, at 240x180 with 20,000 events and at 640x480 with 80,000 (what
// `eds run` uses at VGA), radtan lens. Events at random pixels: time order scatters them over the
// sensor, so the lookup table and the accumulator are read out of cache order, as on real data.
void BM_BuildEventFrame(benchmark::State& state) {
  CameraModel cam;
  cam.width = static_cast<int>(state.range(0));
  cam.height = cam.width * 3 / 4;
  cam.fx = cam.fy = 0.8 * cam.width;
  cam.cx = 0.5 * (cam.width - 1), cam.cy = 0.5 * (cam.height - 1);
  cam.distortion = Distortion::kRadTan;
  cam.k = {-0.14, 0.09, 0.0, 0.0, 0.0};
  const Undistorter und(cam);
  EventFrameConfig efc;
  efc.num_events = static_cast<int>(state.range(1));
  EventFrameBuilder builder(und, efc);
  EventArray events;
  std::uint64_t z = 7;
  for (int i = 0; i < 4 * efc.num_events; ++i) {
    z = z * 6364136223846793005ULL + 1442695040888963407ULL;
    events.push_back(1000 * i, static_cast<std::uint16_t>((z >> 33) % cam.width),
                     static_cast<std::uint16_t>((z >> 13) % cam.height), (z >> 60) & 1 ? 1 : -1);
  }
  EventFrame ef;
  std::size_t begin = 0;
  for (auto _ : state) {
    if (begin + efc.num_events > events.size()) begin = 0;
    builder.build(events, begin, ef);
    benchmark::DoNotOptimize(ef.delta.data);
    begin += efc.stride();
  }
}

BENCHMARK(BM_BuildEventFrame)->Args({240, 20000})->Args({640, 80000})->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
