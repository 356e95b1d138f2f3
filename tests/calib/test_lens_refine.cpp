// Lens self-calibration: the templated radtan model against CameraModel, and recovery of a lens from
// synthetic tracks of a slide like the ECD slider's (same intrinsics), started from a wrong lens and
// drifting poses.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "calib/lens_refine.hpp"

namespace eds {
namespace {

CameraModel sliderLikeCamera(double k1, double k2) {
  CameraModel c;
  c.width = 240, c.height = 180;
  c.fx = 335.4, c.fy = 335.4, c.cx = 129.9, c.cy = 99.2;
  c.distortion = Distortion::kRadTan;
  c.k = {k1, k2, -0.0003, 0.0002, 0.0};
  return c;
}

TEST(LensRefine, TemplatedRadTanMatchesCameraModel) {
  const CameraModel c = sliderLikeCamera(-0.14, 0.09);
  for (double x : {-0.4, -0.1, 0.0, 0.2, 0.35})
    for (double y : {-0.3, 0.0, 0.15, 0.28}) {
      double xd, yd;
      distortRadTan(c.k.data(), x, y, &xd, &yd);
      const Vec2 ref = c.distort(Vec2(x, y));
      EXPECT_NEAR(xd, ref.x(), 1e-15);
      EXPECT_NEAR(yd, ref.y(), 1e-15);
    }
}

struct SyntheticSlide {
  std::vector<FeatureTrack> tracks;
  std::vector<SE3> T_w_c;  // true poses
};

// A camera sliding 1 m along its x axis over 87 frames, with a slight wobble, looking at points 0.6-3 m
// away; tracks are the true lens's projections with Gaussian noise, cut where a point leaves the image.
SyntheticSlide makeSlide(const CameraModel& lens, double noise_px, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> n(0, noise_px);
  SyntheticSlide s;
  const int frames = 87;
  for (int i = 0; i < frames; ++i) {
    const double a = i / double(frames - 1);
    const Vec3 w(0.01 * std::sin(6 * a), 0.02 * std::sin(4 * a), 0.005 * std::cos(5 * a));
    s.T_w_c.emplace_back(SO3::exp(w), Vec3(a, 0.02 * std::sin(3 * a), 0));
  }
  for (int p = 0; p < 400; ++p) {
    const double z = 0.6 + 2.4 * u(rng);
    const Vec3 X((u(rng) * 1.6 - 0.3) * z / 1.5 + 0.5 * u(rng), (u(rng) - 0.5) * 0.55 * z, z);
    FeatureTrack t;
    for (int i = 0; i < frames; ++i) {
      const Vec3 p_c = s.T_w_c[i].inverse() * X;
      const Vec2 px = lens.project(p_c);
      if (p_c.z() > 0.1 && lens.inside(px, 4)) {
        t.frames.push_back(i);
        t.px.push_back(px + Vec2(n(rng), n(rng)));
      } else if (!t.frames.empty()) {
        break;
      }
    }
    if (t.frames.size() >= 5) s.tracks.push_back(std::move(t));
  }
  return s;
}

// Largest pixel difference between two lenses over the image (a grid of rays through the true lens).
double maxLensDifferencePx(const CameraModel& a, const CameraModel& b) {
  double worst = 0;
  for (int y = 0; y < a.height; y += 10)
    for (int x = 0; x < a.width; x += 10) {
      const Vec3 ray = a.unproject(Vec2(x, y));
      worst = std::max(worst, (a.project(ray) - b.project(ray)).norm());
    }
  return worst;
}

TEST(LensRefine, RecoversTheLensOfASlideFromAWrongStart) {
  const CameraModel truth = sliderLikeCamera(-0.08, 0.09);
  const CameraModel given = sliderLikeCamera(-0.1386, 0.0934);
  const SyntheticSlide s = makeSlide(truth, 0.2, 7);
  // Initial poses as a drifting odometry would give them: 3 deg of yaw by the end, 5 mm of noise.
  std::vector<std::optional<SE3>> init(s.T_w_c.size());
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0, 0.005);
  for (std::size_t i = 0; i < init.size(); ++i) {
    const double a = i / double(init.size() - 1);
    init[i] = SE3(SO3::exp(Vec3(0, a * 3 * M_PI / 180, 0)), Vec3(n(rng), n(rng), n(rng))) * s.T_w_c[i];
  }
  init[0] = s.T_w_c[0];
  const double before = maxLensDifferencePx(truth, given);
  const LensRefineResult r = refineLens(given, s.tracks, init, LensRefineConfig{});
  const double after = maxLensDifferencePx(truth, r.camera);
  EXPECT_GT(before, 2.0);
  EXPECT_LT(after, 0.3) << "k1 " << r.camera.k[0] << " k2 " << r.camera.k[1];
  EXPECT_LT(r.rms_refined_px, 0.3);
  // The wrong lens hardly shows in the RMS (poses and depths absorb most of it), but the covariance says
  // the lens is determined, and the truth lies within it.
  EXPECT_LE(r.rms_refined_px, 1.01 * r.rms_fixed_px);  // Huber, not the RMS, is minimized
  EXPECT_LT(r.lens_sigma_px, 0.2);
  EXPECT_LT(after, 3 * r.lens_sigma_px + 0.02) << "sigma " << r.lens_sigma_px;
  std::printf("lens error at the border %.3f px (given lens %.2f px), sigma %.3f px; k1 %.4f +- %.4f\n",
              after, before, r.lens_sigma_px, r.camera.k[0], r.k_sigma[0]);
  EXPECT_GT(r.tracks_used, 250u);
  // The refined poses lose the yaw drift.
  const SE3 T_end_true = s.T_w_c.front().inverse() * s.T_w_c.back();
  const SE3 T_end_est = r.T_w_c.front()->inverse() * *r.T_w_c.back();
  EXPECT_LT((T_end_true.so3().inverse() * T_end_est.so3()).log().norm() * 180 / M_PI, 0.3);
}

TEST(LensRefine, RejectsTooFewPosesTracksOrAnotherModel) {
  const CameraModel c = sliderLikeCamera(-0.1, 0.0);
  const SyntheticSlide s = makeSlide(c, 0.2, 1);
  std::vector<std::optional<SE3>> one(s.T_w_c.size());
  one[0] = s.T_w_c[0];
  EXPECT_THROW(refineLens(c, s.tracks, one, {}), std::invalid_argument);
  std::vector<std::optional<SE3>> all(s.T_w_c.begin(), s.T_w_c.end());
  EXPECT_THROW(refineLens(c, {s.tracks.begin(), s.tracks.begin() + 5}, all, {}), std::invalid_argument);
  CameraModel fish = c;
  fish.distortion = Distortion::kEquidistant;
  EXPECT_THROW(refineLens(fish, s.tracks, all, {}), std::invalid_argument);
  LensRefineConfig bad;
  bad.huber_px = 0;
  EXPECT_THROW(refineLens(c, s.tracks, all, bad), std::invalid_argument);
}

}  // namespace
}  // namespace eds
