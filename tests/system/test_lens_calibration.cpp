// Lens self-calibration on a real sequence (ECD slider_depth, its ground-truth poses as the start) and
// the frame-to-pose association it relies on.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "system/lens_calibration.hpp"
#include "test_data.hpp"

namespace eds {
namespace {

TEST(LensCalibration, PosesAtFramesTakesTheNearestWithinTheGap) {
  std::vector<FrameRef> frames{{1'000'000'000, {}}, {1'040'000'000, {}}, {2'000'000'000, {}}};
  Trajectory traj;
  for (int i = 0; i < 5; ++i)
    traj.push_back({1'000'000'000 + i * 10'000'000 + 2'000'000, SE3(Quat::Identity(), Vec3(i, 0, 0))});
  const auto poses = posesAtFrames(frames, traj, 0.005);
  ASSERT_TRUE(poses[0].has_value());
  EXPECT_DOUBLE_EQ(poses[0]->translation().x(), 0);  // 2 ms after frame 0
  ASSERT_TRUE(poses[1].has_value());
  EXPECT_DOUBLE_EQ(poses[1]->translation().x(), 4);  // 2 ms after frame 1 (not 8 ms before)
  EXPECT_FALSE(poses[2].has_value());                // nothing within 5 ms
}

// The slider's 1,000+ tracks agree with the calibration that comes with it: the refined k1 lies within
// three standard deviations of the given one. They do not pin the lens down to a quarter pixel at the
// border, which is why the slider's rotation drift cannot be calibrated away (README).
TEST(LensCalibration, SliderTracksAgreeWithTheGivenLens) {
  EDS_REQUIRE_SHARED(dir, "ecd_slider_depth");
  const Sequence seq(dir);
  const LensCalibrationReport rep = calibrateLens(seq, seq.groundTruth(), LensCalibrationConfig{});
  const LensRefineResult& r = rep.result;
  std::printf(
      "[ slider lens ] %zu tracks used, RMS %.3f -> %.3f px, k1 %.4f +- %.4f (given %.4f), border sigma %.2f "
      "px\n",
      r.tracks_used, r.rms_fixed_px, r.rms_refined_px, r.camera.k[0], r.k_sigma[0], seq.camera().k[0],
      r.lens_sigma_px);
  EXPECT_GE(rep.posed_frames, 80u);
  EXPECT_GT(r.tracks_used, 500u);
  EXPECT_LT(r.rms_refined_px, 1.0);
  EXPECT_LE(r.rms_refined_px, 1.01 * r.rms_fixed_px);  // Huber, not the RMS, is minimized
  ASSERT_TRUE(std::isfinite(r.lens_sigma_px));
  EXPECT_GT(r.k_sigma[0], 0);
  EXPECT_LT(std::abs(r.camera.k[0] - seq.camera().k[0]), 3 * r.k_sigma[0]);
}

TEST(LensCalibration, ATrajectoryOfAnotherSequenceIsRefused) {
  EDS_REQUIRE_SHARED(dir, "ecd_slider_depth");
  const Sequence seq(dir);
  Trajectory elsewhere{{500'000'000'000, SE3()}, {501'000'000'000, SE3()}};
  try {
    calibrateLens(seq, elsewhere, LensCalibrationConfig{});
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("0 of 87 frames"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace eds
