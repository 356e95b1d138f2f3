// Event frames tracked backwards from a later pose (the pass behind the time before the bootstrap's
// reference and the time lost before a relocalization), on simulated event frames of one keyframe with
// true depth: each is tracked from the next one's pose, and a pose faster than the speed bound allows is
// refused.
#include <gtest/gtest.h>

#include <limits>
#include <vector>

#include "support/sim_event_frame_case.hpp"
#include "system/backward_events.hpp"

namespace eds {
namespace {

struct Cases {
  std::vector<SimEventFrameCase> c;  // one keyframe (t = 0), event frames at increasing delays
  std::vector<EventFrame> buffered;  // all but the last, in time order
  BackwardPass pass;                 // from the last one's true pose, the truth's mean speed
};

Cases makeCases() {
  Cases out;
  for (const double delay : {0.02, 0.035, 0.05, 0.065}) {
    SimEventFrameCaseConfig cfg;
    cfg.event_frame_delay_s = delay;
    out.c.push_back(makeSimEventFrameCase(cfg));
  }
  for (std::size_t k = 0; k + 1 < out.c.size(); ++k) out.buffered.push_back(out.c[k].ef);
  const SimEventFrameCase& last = out.c.back();
  const SE3 T_w_first = out.c.front().T_ef_kf_true.inverse(), T_w_last = last.T_ef_kf_true.inverse();
  const SE3 move = T_w_first.inverse() * T_w_last;
  const double span = toSeconds(last.ef.t - out.c.front().ef.t);
  out.pass = {&out.c.front().kf,
              SE3(),
              {last.ef.t + 1, T_w_last},
              std::numeric_limits<TimeNs>::min(),
              move.translation().norm() / span,
              move.so3().angle() / span,
              "test pass"};
  return out;
}

TEST(BackwardEvents, EarlierEventFramesTrackedFromALaterPoseAndTheSpeedBoundRefusesFasterOnes) {
  const Cases cs = makeCases();
  const SE3 moved = cs.c.front().T_ef_kf_true * cs.c.back().T_ef_kf_true.inverse();
  std::printf(
      "[ backward pass ] the camera moves %.1f mm and %.2f deg from the first event frame to the last\n",
      moved.translation().norm() * 1e3, moved.so3().angle() * 180 / M_PI);
  const OdometryConfig cfg;
  OdometryResult res;
  const std::size_t n = trackEventsBackwards(cs.buffered, cs.pass, cs.c.front().cam, cfg, res);
  ASSERT_EQ(n, cs.buffered.size());
  ASSERT_EQ(res.events.size(), n);
  ASSERT_EQ(res.event_anchors.size(), n);
  for (std::size_t k = 0; k < n; ++k) {
    const SE3 T_w_true = cs.c[k].T_ef_kf_true.inverse();
    const SE3 d = T_w_true.inverse() * res.events[k].T_w_c;
    std::printf("[ backward pass ] event frame at %.1f ms: %.3f mm, %.4f deg off the truth\n",
                toSeconds(res.events[k].t) * 1e3, d.translation().norm() * 1e3, d.so3().angle() * 180 / M_PI);
    EXPECT_EQ(res.events[k].t, cs.buffered[k].t);  // in time order
    EXPECT_EQ(res.event_last_t[k], cs.buffered[k].t_last);
    // Measured 1.5-3.4 mm and 0.12-0.59 deg (one event frame each, as in the tracker's own tests); the
    // camera moves 4.4 mm and 1.7 deg over these 45 ms (the start pose kept for all would be 1.7 deg off).
    EXPECT_LT(d.translation().norm(), 0.005);
    EXPECT_LT(d.so3().angle() * 180 / M_PI, 0.9);
  }
  // A camera said to have been all but still: every step is too fast; three refusals end the pass.
  BackwardPass still = cs.pass;
  still.speed_t = still.speed_r = 1e-7;
  OdometryResult refused;
  EXPECT_EQ(trackEventsBackwards(cs.buffered, still, cs.c.front().cam, cfg, refused), 0u);
  EXPECT_TRUE(refused.events.empty());
  ASSERT_EQ(refused.failures.size(), cs.buffered.size());
  EXPECT_NE(refused.failures[0].reason.find("test pass: faster than"), std::string::npos);
}

// After a sparse interval the event poses since the frame before are tracked again backwards from the
// new frame, and the refined trajectory merges the passes: a pose the two agree on is their blend,
// weighted by the time fraction towards the later frame; where they disagree the backward pose wins
// unless it fits its event frame clearly worse. The live poses stay as tracked.
TEST(BackwardEvents, PosesTrackedAgainAreMergedWithTheForwardOnes) {
  const Cases cs = makeCases();
  const OdometryConfig cfg;
  const StampedPose before{0, SE3()};  // the keyframe's frame
  const BackwardPass pass{cs.pass.ref, SE3(), cs.pass.start, before.t + 1, 1.0, 1.0, "again"};
  std::vector<OdometryFailure> rejected;
  const BackwardPoses b = trackBackwards(cs.buffered, pass, cs.c.front().cam, cfg, rejected);
  ASSERT_EQ(b.poses.size(), 3u);
  ASSERT_EQ(b.correlations.size(), 3u);
  // Forward poses: the oldest and the newest 1 cm off what the backward pass finds (outside the 2 mm
  // gate), the oldest with a clearly higher correlation, the newest with a lower one; the middle one
  // 1 mm off (inside the gate).
  const SE3 off(SO3(), Vec3(0.01, 0, 0)), near(SO3(), Vec3(0.001, 0, 0));
  const double margin = kRetrackCorrelationMargin;
  OdometryResult res;
  for (std::size_t k = 0; k < 3; ++k) {
    const SE3 T_back = b.poses[2 - k].T_w_c;  // b.poses is newest first
    res.events.push_back({cs.buffered[k].t, T_back * (k == 1 ? near : off)});
    res.event_last_t.push_back(cs.buffered[k].t_last);
    res.event_anchors.push_back({7, res.events.back().T_w_c});
    res.event_correlations.push_back(b.correlations[2 - k] + (k == 0 ? 1.5 : k == 2 ? 0.5 : -1.0) * margin);
  }
  const OdometryResult forward = res;
  const std::size_t n =
      retrackEvents(cs.buffered, before, cs.pass.start, *cs.pass.ref, SE3(), cs.c.front().cam, cfg, res);
  EXPECT_EQ(n, 2u);
  // The newest: the backward pose (its correlation lower, but within the margin).
  EXPECT_EQ(res.event_anchors[2].kf_id, b.kf_id);
  EXPECT_LT((res.event_anchors[2].T_kf_c.inverse() * b.poses[0].T_w_c).log().norm(), 1e-9);
  // The middle: w of the way from the forward pose to the backward one, w its time's fraction.
  const double w = toSeconds(cs.buffered[1].t - before.t) / toSeconds(cs.pass.start.t - before.t);
  ASSERT_GT(w, 0.2);
  ASSERT_LT(w, 0.95);
  EXPECT_EQ(res.event_anchors[1].kf_id, b.kf_id);
  const SE3 blend = res.event_anchors[1].T_kf_c;
  EXPECT_NEAR((forward.events[1].T_w_c.inverse() * blend).translation().norm(), w * 0.001, 1e-9);
  EXPECT_NEAR((b.poses[1].T_w_c.inverse() * blend).translation().norm(), (1 - w) * 0.001, 1e-9);
  // The oldest: kept, the backward pose fitting its event frame worse by more than the margin.
  EXPECT_EQ(res.event_anchors[0].kf_id, 7);
  EXPECT_LT((res.event_anchors[0].T_kf_c.inverse() * forward.event_anchors[0].T_kf_c).log().norm(), 1e-12);
  for (std::size_t k = 0; k < 3; ++k)
    EXPECT_LT((res.events[k].T_w_c.inverse() * forward.events[k].T_w_c).log().norm(), 1e-12);
  EXPECT_TRUE(res.failures.empty());
}

}  // namespace
}  // namespace eds
