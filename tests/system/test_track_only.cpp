// Tracking-only mode end to end: the ESIM sequence with true depth and with noisy depth.
#include <gtest/gtest.h>

#include "accuracy.hpp"
#include "eval/ate.hpp"
#include "system/track_only.hpp"
#include "test_data.hpp"

namespace eds {
namespace {

// The estimate's world frame is the ground truth's (the first keyframe at its true pose), so it is
// aligned on that first pose: the first 1.5 s move almost on a straight line, about which an alignment
// of positions alone cannot fix the rotation.
eval::AteResult alignedOnFirstPose(const Trajectory& est, const Trajectory& gt) {
  eval::EvalConfig ec;
  ec.alignment = eval::Alignment::kSe3;
  ec.align_frames = 1;
  return eval::evaluateAte(est, gt, ec);
}

// The whole ESIM sequence with true depth.
TEST(TrackOnly, EsimWithTrueDepth) {
  EDS_REQUIRE_SHARED(dir, "esim_poster6dof_planar");
  const Sequence seq(dir);
  const TrackOnlyResult r = runTrackOnly(seq, TrackOnlyConfig{});
  EXPECT_TRUE(r.failures.empty());
  EXPECT_EQ(r.tracked, r.event_frames);
  const eval::AteResult a = alignedOnFirstPose(r.trajectory, seq.groundTruth());
  test::expectAccuracy("ESIM, tracking-only, true depth", a, {0.227, 0.102});
  EXPECT_GE(a.coverage, 0.95);
}

// The paper's depth-noise study (Fig. 6): 10 % of the median depth on every keyframe point. Without the
// keyframe depth median filter the translation is attenuated and the ATE reaches several cm in 1.5 s.
TEST(TrackOnly, EsimWithTenPercentDepthNoise) {
  EDS_REQUIRE_SHARED(dir, "esim_poster6dof_planar");
  const Sequence seq(dir);
  TrackOnlyConfig cfg;
  cfg.depth_noise = 0.1;
  const TrackOnlyResult r = runTrackOnly(seq, cfg);
  const eval::AteResult a = alignedOnFirstPose(r.trajectory, seq.groundTruth());
  test::expectAccuracy("ESIM, tracking-only, 10 % depth noise", a, {1.249, 0.577});
  EXPECT_GE(a.coverage, 0.95);
}

TEST(TrackOnly, BadConfigurationsAreClearErrors) {
  EDS_REQUIRE_SHARED(dir, "esim_poster6dof_planar");
  const Sequence seq(dir);
  TrackOnlyConfig cfg;
  cfg.event_frame.num_events = 0;
  EXPECT_THROW(runTrackOnly(seq, cfg), std::invalid_argument);
  cfg = {};
  cfg.event_frame.overlap = 1.0;
  EXPECT_THROW(runTrackOnly(seq, cfg), std::invalid_argument);
  cfg = {};
  cfg.events.lost_track.min_correlation_ratio = 1.5;
  EXPECT_THROW(runTrackOnly(seq, cfg), std::invalid_argument);
  cfg = {};
  cfg.events.lost_track.max_cost_ratio = 0.5;
  EXPECT_THROW(runTrackOnly(seq, cfg), std::invalid_argument);
  cfg = {};
  cfg.events.points.min_gradient = 1e9;  // nothing can be selected
  try {
    runTrackOnly(seq, cfg);
    FAIL() << "no error without points";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("no points selected"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace eds
