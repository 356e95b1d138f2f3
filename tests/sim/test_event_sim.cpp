// The simulator against an independent one (ESIM, on the shared sequence) and against the physics it
// must obey: events integrate to log-intensity changes; frames warp into each other with true depth.
#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "io/ecd_events.hpp"
#include "io/sequence.hpp"
#include "sim/presets.hpp"
#include "sim/simulator.hpp"
#include "test_data.hpp"

namespace eds::sim {
namespace {

double correlation(const std::vector<double>& a, const std::vector<double>& b) {
  const std::size_t n = std::min(a.size(), b.size());
  double ma = 0, mb = 0;
  for (std::size_t i = 0; i < n; ++i) ma += a[i], mb += b[i];
  ma /= n, mb /= n;
  double sab = 0, saa = 0, sbb = 0;
  for (std::size_t i = 0; i < n; ++i) {
    sab += (a[i] - ma) * (b[i] - mb);
    saa += (a[i] - ma) * (a[i] - ma);
    sbb += (b[i] - mb) * (b[i] - mb);
  }
  return sab / std::sqrt(saa * sbb);
}

// Counts events per 100 ms window and per pixel.
struct CountingSink : SimSink {
  CountingSink(int w, int h) : width(w), per_pixel(static_cast<std::size_t>(w) * h, 0.0) {}
  void onEvents(const EventArray& ev) override {
    for (std::size_t i = 0; i < ev.size(); ++i) add(ev.t[i], ev.x[i], ev.y[i]);
  }
  void onFrame(TimeNs, const cv::Mat&, const cv::Mat&) override {}
  void add(TimeNs t, int x, int y) {
    const auto w = static_cast<std::size_t>(t / 100'000'000);
    if (per_window.size() <= w) per_window.resize(w + 1, 0.0);
    per_window[w] += 1;
    per_pixel[static_cast<std::size_t>(y) * width + x] += 1;
    ++total;
  }
  int width;
  std::vector<double> per_window, per_pixel;
  std::size_t total = 0;
};

TEST(Simulator, ReproducesEsimOnTheSharedPosterSequence) {
  EDS_REQUIRE_SHARED(dir, "esim_poster6dof_planar");
  EDS_REQUIRE_SHARED(textures, "textures/office.jpg");
  Scene scene = readEsimSceneTxt(dir / "scene.txt", textures.parent_path());
  scene.loadTextures();
  const Sequence seq(dir);
  const CameraModel cam = seq.camera();
  const Motion motion(seq.groundTruth());
  SimConfig cfg;  // the settings of scene.txt: C = 0.2, 1 kHz renders of 8-bit images, no noise
  cfg.events.C_pos = cfg.events.C_neg = 0.2;
  cfg.events.log_eps = 1e-3;
  cfg.render_hz = 1000;
  cfg.quantize_8bit = true;
  cfg.fps = 0;
  cfg.render.supersample = 1;
  Simulator sim(scene, cam, motion, cfg);
  CountingSink ours(cam.width, cam.height), esim(cam.width, cam.height);
  const SimStats st = sim.run(motion.start(), motion.end(), ours);

  EcdEventSource src(dir / "events.txt.gz");
  EventArray chunk;
  while (true) {
    chunk.clear();
    if (src.read(chunk, 1 << 20) == 0) break;
    for (std::size_t i = 0; i < chunk.size(); ++i) esim.add(chunk.t[i], chunk.x[i], chunk.y[i]);
  }
  const double ratio = static_cast<double>(ours.total) / static_cast<double>(esim.total);
  const double c_time = correlation(ours.per_window, esim.per_window);
  const double c_pixel = correlation(ours.per_pixel, esim.per_pixel);
  std::printf(
      "[ esim check ] ours %zu vs esim %zu events (ratio %.4f), per-100ms corr %.4f, per-pixel corr %.4f, "
      "%zu renders in %.1f s\n",
      ours.total, esim.total, ratio, c_time, c_pixel, st.renders, st.wall_s);
  EXPECT_EQ(esim.total, 4'908'566u);
  EXPECT_NEAR(ratio, 1.0, 0.10);
  EXPECT_GE(c_time, 0.95);
  EXPECT_GE(c_pixel, 0.90);
}

// Keeps the frames' log images and the per-pixel sum of polarity x C between frames 1 and 2.
struct IntegratingSink : SimSink {
  IntegratingSink(int w, int h, double C, double eps) : C(C), eps(eps), sum(h, w, CV_64F, cv::Scalar(0)) {}
  void onEvents(const EventArray& ev) override {
    if (frames != 2) return;  // between the 2nd and 3rd frame
    for (std::size_t i = 0; i < ev.size(); ++i) sum.at<double>(ev.y[i], ev.x[i]) += ev.p[i] * C;
  }
  void onFrame(TimeNs t, const cv::Mat& intensity, const cv::Mat& depth) override {
    cv::Mat L;
    cv::log(intensity + eps, L);
    logs.push_back(L);
    depths.push_back(depth.clone());
    images.push_back(intensity.clone());
    times.push_back(t);
    ++frames;
  }
  double C, eps;
  cv::Mat sum;
  int frames = 0;
  std::vector<cv::Mat> logs, depths, images;
  std::vector<TimeNs> times;
};

CameraModel defaultCamera() {
  CameraModel cam;
  cam.width = 240, cam.height = 180;
  cam.fx = cam.fy = 200;
  cam.cx = 119.5, cam.cy = 89.5;
  return cam;
}

TEST(Simulator, EventsIntegrateToTheLogIntensityChange) {
  const Motion motion(handheldMotion(0.2, 3));
  Scene scene = makePreset("room", motion, 3);
  scene.loadTextures();
  SimConfig cfg;
  cfg.events.C_pos = cfg.events.C_neg = 0.05;
  cfg.fps = 20;  // 50 ms between frames
  const CameraModel cam = defaultCamera();
  Simulator sim(scene, cam, motion, cfg);
  IntegratingSink sink(cam.width, cam.height, 0.05, cfg.events.log_eps);
  sim.run(motion.start(), motion.end(), sink);
  ASSERT_GE(sink.frames, 3);
  const cv::Mat diff = sink.logs[2] - sink.logs[1];
  std::vector<double> a, b;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      a.push_back(sink.sum.at<double>(y, x));
      b.push_back(diff.at<float>(y, x));
    }
  const double c = correlation(a, b);
  std::printf("[ integration ] corr(sum p*C, dlog) = %.4f\n", c);
  EXPECT_GE(c, 0.98);
}

// One pixel driven by a wavering log intensity. Without hysteresis the sensor is a quantizer: the net
// event count at any time is the current change rounded to whole thresholds, whatever the path. With
// hysteresis (the default, as a DVS) every turn of the signal loses one event of the new polarity, so
// the count strays from it; on a monotone ramp the two agree.
TEST(EventGenerator, WithoutHysteresisTheNetCountIsTheRoundedChange) {
  constexpr double C = 0.15;
  auto signal = [](double t) { return 0.5 * std::sin(2.0 * t) + 0.3 * std::sin(6.3 * t + 1.0) - 0.4; };
  auto run = [&](bool hysteresis, auto&& L, int& mismatches) {
    EventSimConfig cfg;
    cfg.C_pos = cfg.C_neg = C;
    cfg.hysteresis = hysteresis;
    EventGenerator gen(1, 1, cfg);
    cv::Mat img(1, 1, CV_32F, cv::Scalar(L(0.0)));
    gen.reset(img, 0);
    EventArray ev;
    int net = 0;
    mismatches = 0;
    for (int k = 1; k <= 20000; ++k) {
      const std::size_t before = ev.size();
      img.at<float>(0) = static_cast<float>(L(k * 1e-3));
      gen.step(img, k * 1'000'000LL, ev);
      for (std::size_t i = before; i < ev.size(); ++i) net += ev.p[i];
      const double change = (static_cast<double>(img.at<float>(0)) - static_cast<float>(L(0.0))) / C;
      // Levels are kept in float: a change within 1e-5 of a half threshold may round either way.
      const bool tie = std::abs(std::abs(change - std::trunc(change)) - 0.5) < 1e-5;
      if (!tie && net != static_cast<int>(std::lround(change))) ++mismatches;
    }
    return ev.size();
  };
  int miss_grid = 0, miss_dvs = 0;
  const std::size_t n_grid = run(false, signal, miss_grid);
  const std::size_t n_dvs = run(true, signal, miss_dvs);
  std::printf("[ hysteresis ] events %zu without, %zu with; steps off the rounded change: %d, %d\n", n_grid,
              n_dvs, miss_grid, miss_dvs);
  EXPECT_EQ(miss_grid, 0);
  EXPECT_GT(miss_dvs, 1000);  // of 20,000 steps
  EXPECT_GT(n_grid, n_dvs);   // the events lost at the turns
  // A monotone ramp has no turns: both sensors give the same events.
  auto ramp = [](double t) { return 0.37 * t; };
  int m0 = 0, m1 = 0;
  EXPECT_EQ(run(false, ramp, m0), run(true, ramp, m1));
}

TEST(Simulator, FramesWarpIntoEachOtherWithTrueDepthAndPose) {
  const Motion motion(handheldMotion(0.3, 5));
  Scene scene = makePreset("room", motion, 5);
  scene.loadTextures();
  SimConfig cfg;
  cfg.fps = 10;
  const CameraModel cam = defaultCamera();
  Simulator sim(scene, cam, motion, cfg);
  IntegratingSink sink(cam.width, cam.height, 0.2, 1e-3);
  sim.run(motion.start(), motion.end(), sink);
  ASSERT_GE(sink.frames, 3);
  const cv::Mat& A = sink.images[0];
  const cv::Mat& B = sink.images[2];
  const cv::Mat& depth_A = sink.depths[0];
  const SE3 T_b_a = motion.pose(sink.times[2]).inverse() * motion.pose(sink.times[0]);
  cv::Mat map_x(A.size(), CV_32F), map_y(A.size(), CV_32F);
  for (int y = 0; y < A.rows; ++y)
    for (int x = 0; x < A.cols; ++x) {
      const Vec3 p_b = T_b_a * (cam.unproject(Vec2(x, y)) * depth_A.at<float>(y, x));
      const Vec2 px = cam.project(p_b);
      map_x.at<float>(y, x) = static_cast<float>(px.x());
      map_y.at<float>(y, x) = static_cast<float>(px.y());
    }
  cv::Mat warped;
  cv::remap(B, warped, map_x, map_y, cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(-1));
  double err_warp = 0, err_none = 0;
  int n = 0;
  for (int y = 10; y < A.rows - 10; ++y)
    for (int x = 10; x < A.cols - 10; ++x) {
      if (warped.at<float>(y, x) < 0) continue;  // left the image
      // Pixels at depth discontinuities (occlusion edges) cannot warp: a fair test leaves them out.
      const float z = depth_A.at<float>(y, x);
      bool edge = false;
      for (int dy = -2; dy <= 2; ++dy)
        for (int dx = -2; dx <= 2; ++dx) edge |= std::abs(depth_A.at<float>(y + dy, x + dx) - z) > 0.03f * z;
      if (edge) continue;
      err_warp += std::abs(warped.at<float>(y, x) - A.at<float>(y, x));
      err_none += std::abs(B.at<float>(y, x) - A.at<float>(y, x));
      ++n;
    }
  ASSERT_GT(n, A.rows * A.cols / 2);
  std::printf("[ warp ] mean |A - B| %.5f unwarped, %.5f warped (ratio %.1f)\n", err_none / n, err_warp / n,
              err_none / err_warp);
  EXPECT_LT(err_warp * 10, err_none);
}

}  // namespace
}  // namespace eds::sim
