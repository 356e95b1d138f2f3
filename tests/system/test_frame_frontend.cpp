// The frame front-end's hand-over with a threaded back-end: which reference a frame tracks against while
// the back-end works on a keyframe. A usable frame takes the keyframe once it is mapped (its
// preliminary reference); a refused one, after which the events carry the pose alone, waits for the
// keyframe's bundle adjustment, even when an event frame took up the preliminary reference meanwhile;
// the pipeline asks for that wait when the quality check refuses a frame.
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "io/sequence.hpp"
#include "sim_frames.hpp"
#include "system/frame_frontend.hpp"
#include "system/odometry_core.hpp"
#include "test_data.hpp"

namespace eds {
namespace {

struct Harness {
  CameraModel cam = test::simCamera();
  OdometryConfig cfg;
  OdometryResult res;
  cv::Mat image;
  std::vector<KeyframePoint> points;

  Harness() {
    cfg.threaded_backend = cfg.wait_for_keyframe = cfg.early_reference = cfg.use_events = true;
    image.create(cam.height, cam.width, CV_32F);
    cv::RNG rng(3);
    rng.fill(image, cv::RNG::UNIFORM, 0.0, 1.0);
    cv::GaussianBlur(image, image, cv::Size(0, 0), 1.5);
    for (int v = 12; v < cam.height - 12; v += 6)
      for (int u = 12; u < cam.width - 12; u += 6) {
        KeyframePoint p;
        p.u = static_cast<float>(u), p.v = static_cast<float>(v);
        p.inv_depth = 0.5;
        points.push_back(p);
      }
  }

  // A front-end with its first keyframe adopted and a second one handed to the back-end.
  void startSecondKeyframe(FrameFrontend& fe) {
    fe.addKeyframe(0, image, SE3(), 0, 0, points);
    fe.awaitPendingKeyframe();
    ASSERT_EQ(fe.referenceId(), 0);
    ASSERT_FALSE(fe.referencePreliminary());
    fe.addKeyframe(fromSeconds(0.05), image, SE3(SO3(), Vec3(0.01, 0, 0)), 0, 0, points);
  }
};

TEST(FrameFrontend, AUsableFrameTakesThePendingKeyframeOnceMapped) {
  Harness h;
  FrameFrontend fe(h.cam, h.cfg, h.res);
  h.startSecondKeyframe(fe);
  fe.awaitPendingKeyframe();
  EXPECT_EQ(fe.referenceId(), 1);  // preliminary or adjusted, as the back-end's thread has got on
  fe.worker().waitIdle();
  fe.adoptReference(false);
  EXPECT_EQ(fe.referenceId(), 1);
  EXPECT_FALSE(fe.referencePreliminary());
}

// ... and no longer than that: it tracks against the preliminary reference while the bundle adjustment
// still runs. Whether the adjustment is done by then is up to the threads: each attempt hands the
// back-end a new keyframe, and one of them must find the adjustment still running.
TEST(FrameFrontend, AUsableFrameDoesNotWaitForTheAdjustment) {
  Harness h;
  FrameFrontend fe(h.cam, h.cfg, h.res);
  h.startSecondKeyframe(fe);
  fe.awaitPendingKeyframe();
  for (int k = 2; k < 20 && !fe.referencePreliminary(); ++k) {
    fe.worker().waitIdle();
    fe.addKeyframe(fromSeconds(0.05 * k), h.image, SE3(SO3(), Vec3(0.01 * k, 0, 0)), 0, 0);
    fe.awaitPendingKeyframe();
    ASSERT_EQ(fe.referenceId(), k);
  }
  EXPECT_TRUE(fe.referencePreliminary());
}

TEST(FrameFrontend, ARefusedFrameWaitsForTheAdjustedKeyframe) {
  Harness h;
  FrameFrontend fe(h.cam, h.cfg, h.res);
  h.startSecondKeyframe(fe);
  fe.awaitPendingKeyframe(true);
  EXPECT_EQ(fe.referenceId(), 1);
  EXPECT_FALSE(fe.referencePreliminary());
}

TEST(FrameFrontend, ARefusedFrameWaitsForTheAdjustmentOfAPreliminaryReferenceTakenUp) {
  Harness h;
  FrameFrontend fe(h.cam, h.cfg, h.res);
  h.startSecondKeyframe(fe);
  // An event frame's take-up right after the mapping, while the adjustment still runs. On this small
  // window the adjustment may win the race now and then: the next keyframe tries again.
  for (int k = 1; k < 20; ++k) {
    fe.worker().waitMapped();
    fe.adoptReference(false);
    ASSERT_EQ(fe.referenceId(), k);
    if (fe.referencePreliminary()) break;
    fe.addKeyframe(fromSeconds(0.05 * (k + 1)), h.image, SE3(SO3(), Vec3(0.01 * (k + 1), 0, 0)), 0, 0);
  }
  ASSERT_TRUE(fe.referencePreliminary());
  const int id = fe.referenceId();
  fe.awaitPendingKeyframe(true);
  EXPECT_EQ(fe.referenceId(), id);
  EXPECT_FALSE(fe.referencePreliminary());
}

// The same through the pipeline: a frame the quality check refuses right after a keyframe (frames alone,
// threaded back-end) leaves the frame front-end on that keyframe, adjusted, with nothing pending,
// whether or not the back-end had finished by then.
TEST(FrameFrontend, ARefusedFrameAfterAKeyframeLeavesTheKeyframeAdjustedInThePipeline) {
  EDS_REQUIRE_SHARED(dir, "esim_poster6dof_planar");
  const Sequence seq(dir);
  OdometryConfig cfg;
  cfg.use_events = false;
  cfg.threaded_backend = true;
  OdometryResult res;
  StageClock clock(Stage::kInput);
  OdometryCore core(seq.camera(), cfg, res, clock);
  const cv::Mat black = cv::Mat::zeros(seq.camera().height, seq.camera().width, CV_8U);
  int checked = 0;
  for (std::size_t i = 0; i < seq.frames().size() && checked < 3; ++i) {
    core.frame(seq.frames()[i].t, seq.loadFrame(i));
    const FrameFrontend::Pending* kf = core.frontend().pendingKeyframe();
    if (!kf) continue;
    const int id = kf->id;
    const std::size_t rejected = res.frames_rejected;
    core.frame(seq.frames()[i].t + fromSeconds(0.01), black);
    ASSERT_EQ(res.frames_rejected, rejected + 1);
    EXPECT_EQ(core.frontend().pendingKeyframe(), nullptr);
    EXPECT_EQ(core.frontend().referenceId(), id);
    EXPECT_FALSE(core.frontend().referencePreliminary());
    ++checked;
  }
  EXPECT_EQ(checked, 3);
  core.finish();
}

// The image from a camera moved by `tx` along x before this fronto-parallel texture at depth 2 m: the
// texture shifted by fx · tx / 2 pixels.
cv::Mat movedView(const Harness& h, double tx) {
  const double px = h.cam.fx * tx * 0.5;
  const cv::Mat M = (cv::Mat_<double>(2, 3) << 1, 0, -px, 0, 1, 0);
  cv::Mat out;
  cv::warpAffine(h.image, out, M, h.image.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
  return out;
}

// Without waiting for keyframes (a live camera), a frame that wants a keyframe while the back-end is
// still busy with the last one is tracked against the current reference and the keyframe left to a
// later frame, unless the frame is far from that reference (three times the policy's bounds): then it
// waits. Here the policy wants a keyframe beyond 9.2 px of translation flow: 15 px is left for later,
// 40 px waits. Whether the back-end is still busy when the frame is tracked is up to the threads:
// each attempt hands it a new keyframe first.
TEST(FrameFrontend, WithoutWaitingAKeyframeIsDeferredWhileTheBackendIsBusyUnlessFar) {
  Harness h;
  h.cfg.wait_for_keyframe = false;
  FrameFrontend fe(h.cam, h.cfg, h.res);
  fe.addKeyframe(0, h.image, SE3(), 0, 0, h.points);
  fe.awaitPendingKeyframe();
  const auto attempt = [&](int k, double tx) {
    // The reference at the origin, then another keyframe there for the back-end to work on.
    fe.addKeyframe(fromSeconds(0.1 * k), h.image, SE3(), 0, 0, h.points);
    fe.worker().waitIdle();
    fe.adoptReference(false);
    const int next_id = fe.worker().nextId();  // read while the back-end is idle
    fe.addKeyframe(fromSeconds(0.1 * k + 0.01), h.image, SE3(), 0, 0, h.points);
    const SE3 T_w_f(SO3(), Vec3(tx, 0, 0));
    const SE3 T_w_out = fe.track(fromSeconds(0.1 * k + 0.05), movedView(h, tx), &T_w_f);
    EXPECT_LT((T_w_out.translation() - T_w_f.translation()).norm(), 0.01);
    fe.worker().waitIdle();
    return fe.worker().nextId() - next_id - 1;  // keyframes the frame made
  };
  int k = 1;
  for (; k < 20 && h.res.keyframes_deferred == 0; ++k) {
    const int made = attempt(k, 0.15);
    EXPECT_EQ(made, h.res.keyframes_deferred == 0 ? 1 : 0);
  }
  EXPECT_EQ(h.res.keyframes_deferred, 1u);
  const std::size_t waits = h.res.backend_waits;
  for (; k < 40 && h.res.backend_waits == waits; ++k) EXPECT_EQ(attempt(k, 0.4), 1);
  EXPECT_EQ(h.res.backend_waits, waits + 1);
  EXPECT_EQ(h.res.keyframes_deferred, 1u);
}

// The constant-velocity start of a frame's alignment goes on with the last two frames' motion for the
// time since the last frame: frames a real-time consumer takes irregularly, or after dropped ones,
// start where the camera is, not one step of the last motion further (at most 4 steps).
TEST(FrameFrontend, TheConstantVelocityPredictionFollowsTheTimeSinceTheLastFrame) {
  Harness h;
  FrameFrontend fe(h.cam, h.cfg, h.res);
  const SE3 T_w_0(SO3::exp(Vec3(0, 0.1, 0)), Vec3(0.5, 0, 0));
  const SE3 step(SO3::exp(Vec3(0.01, 0.02, 0)), Vec3(0.01, 0, 0.002));
  fe.setLast(fromSeconds(1.0), T_w_0);
  EXPECT_LT((fe.constantVelocityPose(fromSeconds(1.5)).inverse() * T_w_0).log().norm(), 1e-12);  // one frame
  fe.setLast(fromSeconds(1.04), T_w_0 * step);
  const auto off = [&](TimeNs t, const SE3& expected) {
    return (fe.constantVelocityPose(t).inverse() * expected).log().norm();
  };
  EXPECT_LT(off(fromSeconds(1.08), T_w_0 * step * step), 1e-12);
  EXPECT_LT(off(fromSeconds(1.16), T_w_0 * step * step * step * step), 1e-9);
  EXPECT_LT(off(fromSeconds(1.06), T_w_0 * step * SE3::exp(0.5 * step.log())), 1e-9);
  const SE3 four = T_w_0 * step * SE3::exp(4.0 * step.log());
  EXPECT_LT(off(fromSeconds(3.0), four), 1e-9);
}

// Frames a second apart: the events' pose may have drifted into a wrong minimum, and the
// constant-velocity start means little. The alignment from ORB features matched to the reference
// finds the frame all the same; frames closer together than feature_start.min_interval_s do not try it.
struct SparseFrameCase {
  SE3 T_w_f;  // what the front-end found
  std::size_t feature_starts = 0;
};

SparseFrameCase trackFarFrame(double interval_s, double min_interval_s, const SE3& T_w_true) {
  Harness h;
  h.cfg.threaded_backend = false;
  h.cfg.feature_start.min_interval_s = min_interval_s;
  cv::normalize(h.image, h.image, 0.05, 0.95, cv::NORM_MINMAX);
  FrameFrontend fe(h.cam, h.cfg, h.res);
  fe.addKeyframe(0, h.image, SE3(), 0, 0, h.points);
  fe.awaitPendingKeyframe();
  fe.setLast(0, SE3());
  // The events' pose: stuck near the keyframe while the camera went on.
  const SE3 T_w_events(SO3::exp(Vec3(0.01, -0.02, 0.0)), Vec3(0.03, 0, 0));
  const cv::Mat frame = test::renderPlaneView(h.image, h.cam, T_w_true.inverse(), 2.0);
  const SE3 T_w_f = fe.track(fromSeconds(interval_s), frame, &T_w_events);
  return {T_w_f, h.res.feature_starts};
}

TEST(FrameFrontend, ASparseFrameFarFromItsStartsIsFoundFromFeatures) {
  // 30 cm and 9 degrees from the keyframe at 2 m: 60-70 px of image motion.
  const SE3 T_w_true(SO3::exp(Vec3(0.05, -0.15, 0.06)), Vec3(0.30, -0.08, 0.12));
  const auto error = [&](const SE3& T_w_f) {
    const SE3 d = T_w_true.inverse() * T_w_f;
    return std::pair{d.translation().norm(), d.so3().angle() * 180 / M_PI};
  };
  const SparseFrameCase sparse = trackFarFrame(1.0, 0.4, T_w_true);
  const auto [t_err, r_err] = error(sparse.T_w_f);
  std::printf("[ sparse frame ] from features: %.2f mm, %.3f deg\n", t_err * 1e3, r_err);
  EXPECT_EQ(sparse.feature_starts, 1u);
  EXPECT_LT(t_err, 0.002);
  EXPECT_LT(r_err, 0.05);
  // The same frame 0.2 s after the last, or with the feature start off: the other starts miss it.
  for (const SparseFrameCase& other : {trackFarFrame(0.2, 0.4, T_w_true), trackFarFrame(1.0, 0, T_w_true)}) {
    EXPECT_EQ(other.feature_starts, 0u);
    EXPECT_GT(error(other.T_w_f).first, 0.02);
  }
}

// Which alignment a sparse frame keeps, with figures from real runs at 1 and 2 frames per second.
TEST(FrameFrontend, TheFeatureAlignmentWinsOnlyWhenClearlyBetterOverNearlyAsManyPoints) {
  const auto fit = [](bool ok, double rmse, int residuals) {
    FrameTrackResult r;
    r.ok = ok, r.rmse = rmse, r.residuals = residuals;
    return r;
  };
  const double ratio = OdometryConfig{}.feature_start.max_rmse_ratio;
  // The events had drifted (a desk at 1 FPS): half the residual over more points.
  EXPECT_TRUE(featureAlignmentWins(fit(true, 0.0152, 7326), fit(true, 0.0317, 6817), ratio));
  // The same minimum reached from both starts: no reason to move.
  EXPECT_FALSE(featureAlignmentWins(fit(true, 0.0187, 4378), fit(true, 0.0187, 4378), ratio));
  // A turning room: 15 % lower on a tenth of the points, where the features' translation is loose.
  EXPECT_FALSE(featureAlignmentWins(fit(true, 0.0134, 1360), fit(true, 0.0157, 12798), ratio));
  EXPECT_FALSE(featureAlignmentWins(fit(true, 0.0134, 12000), fit(true, 0.0157, 12798), ratio));
  EXPECT_FALSE(featureAlignmentWins(fit(true, 0.0100, 1360), fit(true, 0.0157, 12798), ratio));
  EXPECT_TRUE(featureAlignmentWins(fit(true, 0.0100, 11000), fit(true, 0.0157, 12798), ratio));
  // The others failed; a failed alignment from the features never wins.
  EXPECT_TRUE(featureAlignmentWins(fit(true, 0.03, 500), fit(false, 0.02, 5000), ratio));
  EXPECT_FALSE(featureAlignmentWins(fit(false, 0.01, 5000), fit(true, 0.03, 5000), ratio));
}

}  // namespace
}  // namespace eds
