// Bootstrap on simulated frames of the built-in room along the built-in hand-held motion: depths up to
// scale and the last frame's pose against the simulator's truth.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "init/bootstrap.hpp"
#include "sim/presets.hpp"
#include "sim/simulator.hpp"
#include "sim_frames.hpp"

namespace eds {
namespace {

CameraModel camera() { return test::simCamera(); }
using Frames = test::FrameSink;

// The frames between the reference and the last: RMS position error (at the depths' scale `med`)
// relative to the last frame's distance from the reference, and the largest rotation error (deg).
std::pair<double, double> framesBetweenError(const Bootstrap& boot, const sim::Motion& motion, double med) {
  const std::vector<BootstrapFrame>& fr = boot.frames();
  const SE3 T_w_ref = motion.pose(boot.reference().t);
  const double baseline = (T_w_ref.inverse() * motion.pose(fr.back().t)).translation().norm();
  double ss = 0, rot_max = 0;
  for (std::size_t k = 1; k + 1 < fr.size(); ++k) {
    const SE3 T_ref_c_true = T_w_ref.inverse() * motion.pose(fr[k].t);
    ss += (fr[k].T_ref_c.translation() * med - T_ref_c_true.translation()).squaredNorm();
    rot_max =
        std::max(rot_max, (fr[k].T_ref_c.so3().inverse() * T_ref_c_true.so3()).log().norm() * 180 / M_PI);
  }
  return {std::sqrt(ss / std::max<std::size_t>(1, fr.size() - 2)) / baseline, rot_max};
}

struct Bounds {
  std::size_t max_frames;
  double max_t_err;        // translation error of the last frame, relative to its distance from the reference
  double max_between_err;  // the same of the frames between (RMS)
  double max_between_rot_deg = 0.3;
};

void checkBootstrap(double seconds, unsigned seed, double fps, Bounds b, const char* preset = "room",
                    const BootstrapConfig& bc = {}) {
  const sim::Motion motion{sim::handheldMotion(seconds, seed)};
  sim::Scene scene = sim::makePreset(preset, motion, seed);
  scene.loadTextures();
  sim::SimConfig cfg;
  cfg.fps = fps;
  cfg.events.C_pos = cfg.events.C_neg = 1.0;  // events are not needed here
  Frames f;
  sim::Simulator(scene, camera(), motion, cfg).run(motion.start(), motion.end(), f);

  // As `eds run` sees them: 8-bit frames (the sequence's PNGs).
  for (cv::Mat& im : f.images) {
    cv::Mat q;
    im.convertTo(q, CV_8U, 255.0);
    q.convertTo(im, CV_32F, 1.0 / 255.0);
  }
  Bootstrap boot(camera(), bc);
  std::size_t i = 0;
  while (i < f.images.size() && !boot.add(f.times[i], f.images[i])) ++i;
  ASSERT_LT(i, f.images.size()) << "never initialized";
  std::printf("[ bootstrap ] initialized after %zu frames (%s), %d restarts, parallax %.1f px, rmse %.4f\n",
              i + 1, boot.usedGeometric() ? "essential matrix" : "photometric", boot.restarts(),
              boot.parallax(), boot.rmse());
  EXPECT_LE(i, b.max_frames);

  const Keyframe& ref = boot.reference();
  const std::size_t r = std::find(f.times.begin(), f.times.end(), ref.t) - f.times.begin();
  ASSERT_LT(r, f.times.size());
  // Depths up to one scale: the ratio estimate / truth is the same for every point.
  std::vector<double> ratio;
  for (const KeyframePoint& p : ref.points) {
    const float z = f.depths[r].at<float>(static_cast<int>(p.v), static_cast<int>(p.u));
    if (p.inv_depth > 0 && z > 0) ratio.push_back(z * p.inv_depth);
  }
  ASSERT_GT(ratio.size(), 100u);
  std::sort(ratio.begin(), ratio.end());
  const double med = ratio[ratio.size() / 2];
  std::vector<double> dev;
  for (double x : ratio) dev.push_back(std::abs(x / med - 1.0));
  std::sort(dev.begin(), dev.end());
  std::printf("[ bootstrap ] %zu points, median |depth error| after scale %.2f %%\n", ratio.size(),
              dev[dev.size() / 2] * 100);
  EXPECT_LT(dev[dev.size() / 2], 0.05);

  // The pose of the last frame in the reference: rotation, and translation up to the same scale.
  const SE3 T_ref_c_true = motion.pose(ref.t).inverse() * motion.pose(boot.frames().back().t);
  const SE3& T_ref_c = boot.frames().back().T_ref_c;
  const double rot_err = (T_ref_c.so3().inverse() * T_ref_c_true.so3()).log().norm() * 180 / M_PI;
  const Vec3 t_scaled = T_ref_c.translation() * med;  // true depth = med × estimated depth
  const double t_err = (t_scaled - T_ref_c_true.translation()).norm() / T_ref_c_true.translation().norm();
  std::printf("[ bootstrap ] rotation error %.3f deg, translation error %.1f %% of %.1f cm\n", rot_err,
              t_err * 100, T_ref_c_true.translation().norm() * 100);
  EXPECT_LT(rot_err, 0.2);
  EXPECT_LT(t_err, b.max_t_err);
  const auto [between_err, between_rot] = framesBetweenError(boot, motion, med);
  std::printf(
      "[ bootstrap ] frames between: RMS translation error %.1f %% of that, largest rotation error %.3f "
      "deg\n",
      between_err * 100, between_rot);
  EXPECT_LT(between_err, b.max_between_err);
  EXPECT_LT(between_rot, b.max_between_rot_deg);

  // The parallax it reports is the RMS image motion the translation alone causes: each point at its
  // depth, seen from the last frame with and without the translation.
  const SE3 T_c_ref = T_ref_c.inverse();
  double ss = 0;
  int n = 0;
  for (const KeyframePoint& p : ref.points) {
    if (!(p.inv_depth > 0)) continue;
    const Vec3 p_ref = camera().unproject(Vec2(p.u, p.v)) / p.inv_depth;
    const Vec3 rotated = T_c_ref.so3() * p_ref;
    ss += (camera().project(rotated + T_c_ref.translation()) - camera().project(rotated)).squaredNorm();
    ++n;
  }
  EXPECT_NEAR(boot.parallax(), std::sqrt(ss / n), 1e-6 * boot.parallax());
  EXPECT_THROW(boot.add(f.times.back(), f.images.back()), std::logic_error);
}

TEST(Bootstrap, InitializesPoseAndDepthsUpToScale) { checkBootstrap(2.5, 4, 25, {40, 0.05, 0.04}); }

// This motion shakes (mostly rotation) for 1.6 s before it translates. A homography explains the
// shaking as well as an essential matrix does, and when that verdict stuck, the constant-depth
// photometric path declared success on the room's 3D structure with wrong depths (frames-only ATE
// 1.8 cm over the 3 s instead of 0.13 cm; here 15 % depth and 78 % translation error). The essential
// matrix's pose, refined by the two-frame BA, is a few % off in translation.
TEST(Bootstrap, ShakingBeforeTranslatingIsNotTakenForAPlane) { checkBootstrap(3.0, 5, 20, {50, 0.1, 0.04}); }

// The same with five views in the final adjustment (the default from 640x480 on): last frame 5.9 -> 1.3 %,
// frames in between 2.2 -> 1.1 %.
TEST(Bootstrap, FiveViewsInTheFinalAdjustment) {
  BootstrapConfig bc;
  bc.final_views = 5;
  checkBootstrap(3.0, 5, 20, {50, 0.03, 0.02}, "room", bc);
}

// A plane: the photometric path initializes, and the frames in between, each fitted with the depths
// of its time, are aligned again to the final ones.
// Measured: largest rotation error 0.038 deg as they were, 0.018 aligned again.
TEST(Bootstrap, PlaneFramesInBetweenFollowTheFinalDepths) {
  checkBootstrap(2.5, 4, 25, {40, 0.05, 0.02, 0.03}, "planar");
}

// At 10 FPS this motion swings 7.8 degrees away and 2.6 back in the seven frames the corner tracks
// need: the frames in between (placeholders while the photometric path had given up) start from the
// pose their tracks give against the triangulated corners, not only from the geodesic to the last
// frame or the previous result, from which the alignment fell into a minimum several degrees off.
TEST(Bootstrap, FramesInBetweenASwingStartFromTheCornerTracks) {
  checkBootstrap(3.0, 4, 10, {8, 0.1, 0.1, 0.2});
}

// A frame that fits worse than the one before on both counts (residual RMS and inliers) is no
// success: it lies far from the last one (frames dropped in between) and its fit may have found a
// wrong basin. With bounds so tight that this motion's own frames break them (any growth of the RMS
// by 1 % with any inlier lost), the bootstrap gives up such references instead of initializing on
// them; with the defaults it initializes without a restart.
TEST(Bootstrap, AFrameFittingWorseThanTheOneBeforeIsNoSuccess) {
  const sim::Motion motion{sim::handheldMotion(2.5, 4)};
  sim::Scene scene = sim::makePreset("room", motion, 4);
  scene.loadTextures();
  sim::SimConfig cfg;
  cfg.fps = 25;
  cfg.events.C_pos = cfg.events.C_neg = 1.0;
  Frames f;
  sim::Simulator(scene, camera(), motion, cfg).run(motion.start(), motion.end(), f);
  BootstrapConfig tight;
  tight.max_rmse_growth = 1.01;
  tight.min_inlier_share = 1.0;
  Bootstrap normal(camera(), {}), strict(camera(), tight);
  std::size_t normal_at = 0, strict_at = 0;
  for (std::size_t i = 0; i < f.images.size(); ++i) {
    if (!normal.done() && normal.add(f.times[i], f.images[i])) normal_at = i;
    if (!strict.done() && strict.add(f.times[i], f.images[i])) strict_at = i;
  }
  std::printf("[ bootstrap ] defaults: frame %zu, %d restarts; tight: frame %zu, %d restarts\n", normal_at,
              normal.restarts(), strict_at, strict.restarts());
  ASSERT_TRUE(normal.done());
  EXPECT_EQ(normal.restarts(), 0);
  EXPECT_GT(strict.restarts(), 0);
  EXPECT_TRUE(!strict.done() || strict_at > normal_at);
}

TEST(Bootstrap, FlatFramesNeverInitializeAndBadConfigIsAnError) {
  Bootstrap boot(camera(), {});
  const cv::Mat flat(180, 240, CV_32F, cv::Scalar(0.5));
  for (int i = 0; i < 5; ++i) EXPECT_FALSE(boot.add(i * 40'000'000LL, flat));
  BootstrapConfig bad;
  bad.min_parallax_px = 0;
  EXPECT_THROW(Bootstrap(camera(), bad), std::invalid_argument);
  BootstrapConfig one_view;
  one_view.final_views = 1;
  EXPECT_THROW(Bootstrap(camera(), one_view), std::invalid_argument);
  BootstrapConfig no_frame;
  no_frame.min_frames_sparse = 0;
  EXPECT_THROW(Bootstrap(camera(), no_frame), std::invalid_argument);
}

}  // namespace
}  // namespace eds
