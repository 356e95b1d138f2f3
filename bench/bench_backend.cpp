// The two photometric solves on frames, at 240x180: one bundle adjustment of a full window (7 keyframes,
// ~2,000 points each seen in every other keyframe, depths 5 % off) and one frame alignment to a
// keyframe of ~2,000 points from a start 1 cm and 0.5° off. Frames of a textured plane from the
// simulator along the hand-held motion; the bundle adjustment runs on all cores, as in `eds run`.
#include <benchmark/benchmark.h>

#include <random>

#include "backend/photometric_ba.hpp"
#include "frontend/frame_tracker.hpp"
#include "frontend/point_selection.hpp"
#include "map/keyframe.hpp"
#include "sim/presets.hpp"
#include "sim/simulator.hpp"

namespace {

using namespace eds;

struct Frames : sim::SimSink {
  void onEvents(const EventArray&) override {}
  void onFrame(TimeNs t, const cv::Mat& intensity, const cv::Mat& depth) override {
    times.push_back(t), images.push_back(intensity.clone()), depths.push_back(depth.clone());
  }
  std::vector<TimeNs> times;
  std::vector<cv::Mat> images, depths;
};

struct Fixture {
  static constexpr int kFrames = 7;
  CameraModel cam;
  sim::Motion motion{sim::handheldMotion(1.5, 5)};
  Frames data;
  std::vector<BaFrame> frames;
  std::vector<BaPoint> points;
  Keyframe kf;  // frame 0 with true depth, for the frame tracker
  Fixture() {
    sim::Scene scene = sim::makePreset("planar", motion, 5);
    scene.loadTextures();
    cam.width = 240, cam.height = 180;
    cam.fx = cam.fy = 200;
    cam.cx = 119.5, cam.cy = 89.5;
    sim::SimConfig cfg;
    cfg.fps = 1.0 / 0.2;
    cfg.events.C_pos = cfg.events.C_neg = 1.0;  // events are not needed
    sim::Simulator(scene, cam, motion, cfg).run(motion.start(), motion.end(), data);
    std::mt19937 rng(1);
    std::normal_distribution<double> noise(0.0, 1.0);
    for (int f = 0; f < kFrames; ++f) {
      BaFrame bf;
      bf.image = data.images[f];
      bf.T_w_c = data.times.size() > static_cast<std::size_t>(f) ? motion.pose(data.times[f]) : SE3();
      bf.fixed = f == 0;
      frames.push_back(bf);
      Keyframe k;
      setKeyframeImage(k, data.images[f]);
      PointSelectionConfig pc;
      pc.fraction = 0.045;
      for (const cv::Point& q : selectPoints(k.grad_x, k.grad_y, pc)) {
        const float z = data.depths[f].at<float>(q.y, q.x);
        if (!(z > 0)) continue;
        if (f == 0) {
          k.points.push_back({static_cast<float>(q.x), static_cast<float>(q.y), k.grad_x.at<float>(q.y, q.x),
                              k.grad_y.at<float>(q.y, q.x), 1.0 / z});
        }
        if (points.size() >= static_cast<std::size_t>(300 * (f + 1))) continue;
        BaPoint p;
        p.host = f;
        p.u = static_cast<float>(q.x), p.v = static_cast<float>(q.y);
        p.inv_depth = 1.0 / (z * (1.0 + 0.05 * noise(rng)));
        for (int t = 0; t < kFrames; ++t)
          if (t != f) p.targets.push_back(t);
        points.push_back(p);
      }
      if (f == 0) kf = k;
    }
  }
};

Fixture& fixture() {
  static Fixture f;
  return f;
}

void BM_BundleAdjustment(benchmark::State& state) {
  Fixture& fx = fixture();
  const PhotometricBA ba(fx.cam, BaConfig{});
  int residuals = 0;
  for (auto _ : state) {
    std::vector<BaFrame> frames = fx.frames;
    std::vector<BaPoint> points = fx.points;
    residuals = ba.optimize(frames, points).residuals;
    benchmark::DoNotOptimize(frames.back().T_w_c);
  }
  state.counters["points"] = static_cast<double>(fx.points.size());
  state.counters["residuals"] = residuals;
}
BENCHMARK(BM_BundleAdjustment)->Unit(benchmark::kMillisecond);

void BM_FrameAlignment(benchmark::State& state) {
  Fixture& fx = fixture();
  FrameTracker tracker(fx.cam, FrameTrackerConfig{});
  tracker.setKeyframe(fx.kf);
  const SE3 T_f_kf = fx.frames[1].T_w_c.inverse() * fx.frames[0].T_w_c;
  const SE3 offset = SE3::exp((Eigen::Matrix<double, 6, 1>() << 0.01, 0, 0, 0, 0.0087, 0).finished());
  for (auto _ : state) {
    SE3 T = offset * T_f_kf;
    double a = 1, b = 0;
    const FrameTrackResult r = tracker.track(fx.data.images[1], T, a, b, static_cast<int>(state.range(0)));
    benchmark::DoNotOptimize(r.rmse);
  }
  state.counters["keyframe_points"] = static_cast<double>(fx.kf.points.size());
}
BENCHMARK(BM_FrameAlignment)->Arg(0)->Arg(2)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
