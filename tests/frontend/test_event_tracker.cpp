#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <random>

#include "core/image_sampling.hpp"
#include "frontend/event_frame.hpp"
#include "frontend/event_packets.hpp"
#include "frontend/event_tracker.hpp"
#include "frontend/point_selection.hpp"

namespace eds {
namespace {

CameraModel pinhole240() {
  CameraModel c;
  c.width = 240, c.height = 180;
  c.fx = 200, c.fy = 198, c.cx = 119.5, c.cy = 89.5;
  return c;
}

cv::Mat smoothRandomImage(int w, int h, unsigned seed, double sigma) {
  cv::Mat img(h, w, CV_32F);
  cv::RNG rng(seed);
  rng.fill(img, cv::RNG::NORMAL, 0.0, 1.0);
  cv::GaussianBlur(img, img, cv::Size(0, 0), sigma);
  return img;
}

TEST(Bicubic, DerivativesMatchNumericDifferences) {
  const cv::Mat img = smoothRandomImage(60, 40, 3, 2.0);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> ux(2, 57), uy(2, 37);
  for (int k = 0; k < 200; ++k) {
    const double x = ux(rng), y = uy(rng), h = 1e-4;
    double dx, dy;
    sampleBicubic(img, x, y, &dx, &dy);
    const double ndx = (sampleBicubic(img, x + h, y) - sampleBicubic(img, x - h, y)) / (2 * h);
    const double ndy = (sampleBicubic(img, x, y + h) - sampleBicubic(img, x, y - h)) / (2 * h);
    EXPECT_NEAR(dx, ndx, 2e-3 * (1 + std::abs(ndx)));
    EXPECT_NEAR(dy, ndy, 2e-3 * (1 + std::abs(ndy)));
  }
  // Interpolates: exact at pixel centres.
  EXPECT_FLOAT_EQ(sampleBicubic(img, 10, 12), img.at<float>(12, 10));
}

TEST(EventFrame, GaussianWeightsBilinearVotesMedianTimeUnitNorm) {
  const Undistorter und(pinhole240());
  EventFrameConfig cfg;
  cfg.num_events = 5;
  cfg.blur = false;
  EventFrameBuilder builder(und, cfg);
  EventArray ev;
  for (int k = 0; k < 5; ++k)
    ev.push_back(1000 + 10 * k, static_cast<std::uint16_t>(50 + k), 60, k % 2 ? -1 : 1);
  EventFrame ef;
  builder.build(ev, 0, ef);
  EXPECT_EQ(ef.t, 1020);
  EXPECT_EQ(ef.t_first, 1000);
  EXPECT_EQ(ef.t_last, 1040);
  EXPECT_NEAR(cv::norm(ef.delta), 1.0, 1e-6);
  // Middle event has weight 1, the ends exp(-0.5 * (2 / (5/6))^2); polarities alternate.
  const float mid = ef.delta.at<float>(60, 52), end = ef.delta.at<float>(60, 50);
  EXPECT_NEAR(end / mid, std::exp(-0.5 * std::pow(2.0 / (5.0 / 6.0), 2)), 1e-5);
  EXPECT_LT(ef.delta.at<float>(60, 51), 0);
  EXPECT_THROW(builder.build(ev, 1, ef), std::out_of_range);
  EventFrameConfig bad;
  bad.overlap = 1.0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = {};
  bad.num_events = 0;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad = {};
  bad.compensation_lookahead = -0.5;
  EXPECT_THROW(bad.validate(), std::invalid_argument);
  bad.compensation_lookahead = std::nan("");
  EXPECT_THROW(bad.validate(), std::invalid_argument);
}

// A distorted lens puts events between pixel centres: each event's vote goes to the four pixels around
// its undistorted position with the bilinear weights (1-ax)(1-ay), ax(1-ay), (1-ax)ay, ax ay.
TEST(EventFrame, BilinearVoteOfADistortedEventSplitsOverFourPixels) {
  CameraModel cam = pinhole240();
  cam.distortion = Distortion::kRadTan;  // the ECD DAVIS240C lens
  cam.k = {-0.138592767408, 0.0933736664192, -0.000335586987532, 0.000173720158228, 0.0};
  const Undistorter und(cam);
  EventFrameConfig cfg;
  cfg.num_events = 1;
  cfg.blur = false;
  cfg.reversal_compensation = false;
  EventFrameBuilder builder(und, cfg);
  int checked = 0;
  for (int y = 10; y < cam.height - 10; y += 13) {
    for (int x = 10; x < cam.width - 10; x += 17) {
      const cv::Point2f u = und.eventLut(x, y);
      const float ax = u.x - std::floor(u.x), ay = u.y - std::floor(u.y);
      // Fractions that tell every weight apart (and ax from ay).
      if (ax < 0.1f || ax > 0.9f || ay < 0.1f || ay > 0.9f || std::abs(ax - ay) < 0.1f) continue;
      EventArray ev;
      ev.push_back(1000, static_cast<std::uint16_t>(x), static_cast<std::uint16_t>(y), -1);
      EventFrame ef;
      builder.build(ev, 0, ef);
      const int x0 = static_cast<int>(std::floor(u.x)), y0 = static_cast<int>(std::floor(u.y));
      const std::array<double, 4> w = {(1 - ax) * (1 - ay), ax * (1 - ay), (1 - ax) * ay, ax * ay};
      const double norm = std::sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2] + w[3] * w[3]);
      EXPECT_NEAR(ef.delta.at<float>(y0, x0), -w[0] / norm, 1e-5) << x << "," << y;
      EXPECT_NEAR(ef.delta.at<float>(y0, x0 + 1), -w[1] / norm, 1e-5) << x << "," << y;
      EXPECT_NEAR(ef.delta.at<float>(y0 + 1, x0), -w[2] / norm, 1e-5) << x << "," << y;
      EXPECT_NEAR(ef.delta.at<float>(y0 + 1, x0 + 1), -w[3] / norm, 1e-5) << x << "," << y;
      EXPECT_NEAR(cv::norm(ef.delta), 1.0, 1e-5);  // nothing voted anywhere else
      ++checked;
    }
  }
  EXPECT_GT(checked, 10);
}

TEST(EventFrame, ReversalCompensationAddsTheEventTheHysteresisHeldBack) {
  // Packet = array indices 3..9 (N = 7). Pixel A fires + + then - -: its first "-" (index 6) comes a
  // full threshold below the last level, one event late; its next "-" two indices later says the
  // brightness falls a threshold per two indices, so the missing "-" goes two before index 6 (at 4,
  // packet index 1). Pixel B never turns and is left alone. Pixel C's "+" before the packet (index 1)
  // counts: its turn at index 9 has no next event, so the missing "-" goes midway (index 5). Pixel D
  // turns only after the packet (index 11, then turns back at 12): the lookahead finds it, midway
  // between index 2 and 11 lands in the packet (index 6).
  const Undistorter und(pinhole240());
  EventFrameConfig cfg;
  cfg.num_events = 7;
  cfg.blur = false;
  EventArray ev;
  auto add = [&](std::uint16_t x, int p) {
    ev.push_back(1000 + 10 * static_cast<TimeNs>(ev.size()), x, 60, p);
  };
  const std::uint16_t A = 50, B = 60, C = 70, D = 80;
  add(90, 1), add(C, 1), add(D, 1);                                                // 0-2: before
  add(A, 1), add(A, 1), add(B, 1), add(A, -1), add(B, 1), add(A, -1), add(C, -1);  // 3-9: packet
  add(85, 1), add(D, -1), add(D, 1), add(85, 1);                                   // 10-13: after
  auto w = [&](int k) { return std::exp(-0.5 * std::pow((k - 3.0) / (7.0 / 6.0), 2)); };
  auto build = [&](bool compensate, double lookahead) {
    cfg.reversal_compensation = compensate;
    cfg.compensation_lookahead = lookahead;
    EventFrame f;
    EventFrameBuilder(und, cfg).build(ev, 3, f);
    const float b = f.delta.at<float>(60, B);
    return std::array<double, 3>{f.delta.at<float>(60, A) / b, f.delta.at<float>(60, C) / b,
                                 f.delta.at<float>(60, D) / b};
  };
  const double b = w(2) + w(4);  // pixel B: packet indices 2 and 4
  const auto off = build(false, 1.0), on = build(true, 1.0), near = build(true, 0.0);
  EXPECT_NEAR(off[0], (w(0) + w(1) - w(3) - w(5)) / b, 1e-5);
  EXPECT_NEAR(off[1], -w(6) / b, 1e-5);
  EXPECT_NEAR(off[2], 0.0, 1e-7);
  EXPECT_NEAR(on[0], (w(0) + w(1) - w(3) - w(5) - w(1)) / b, 1e-5);
  EXPECT_NEAR(on[1], -(w(6) + w(2)) / b, 1e-5);
  EXPECT_NEAR(on[2], -w(3) / b, 1e-5);
  // Without lookahead D's turn is not seen; A's and C's are the same.
  EXPECT_NEAR(near[0], on[0], 1e-6);
  EXPECT_NEAR(near[1], on[1], 1e-6);
  EXPECT_NEAR(near[2], 0.0, 1e-7);
}

// Hands out a stored array in chunks of a few hundred events.
class ChunkedSource : public EventSource {
 public:
  explicit ChunkedSource(const EventArray& all) : all_(all) {}
  std::size_t read(EventArray& out, std::size_t max_events) override {
    const std::size_t n = std::min({max_events, std::size_t{777}, all_.size() - pos_});
    for (std::size_t i = pos_; i < pos_ + n; ++i) out.push_back(all_.t[i], all_.x[i], all_.y[i], all_.p[i]);
    pos_ += n;
    return n;
  }

 private:
  const EventArray& all_;
  std::size_t pos_ = 0;
};

TEST(EventFrame, CompensatedFramesFromAStreamEqualThoseFromTheWholeArray) {
  // The packet stream drops old events as it goes (past 2^20 of them) and stops at the end with a
  // short lookahead; the builder's per-pixel memory must make the frames identical to those built
  // from the whole array, where every earlier event is at hand.
  // Most events on a busy patch, some spread thinly over the whole sensor: those pixels fire every
  // few hundred thousand events, so only a memory of the whole past knows their last polarity.
  const CameraModel cam = pinhole240();
  const Undistorter und(cam);
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> busy(0, 24 * 18 - 1), any(0, cam.width * cam.height - 1), flip(0, 9);
  std::vector<int> pol(cam.width * cam.height, 1);
  EventArray all;
  for (int i = 0; i < 1'300'000; ++i) {
    int q = any(rng);
    if (flip(rng) != 0) q = 100 * cam.width + 100 + (busy(rng) / 24) * cam.width + busy(rng) % 24;
    if (flip(rng) == 0) pol[q] = -pol[q];  // runs of one polarity with turns in between
    all.push_back(1000 + i, static_cast<std::uint16_t>(q % cam.width),
                  static_cast<std::uint16_t>(q / cam.width), pol[q]);
  }
  EventFrameConfig cfg;
  cfg.num_events = 4000;
  ChunkedSource src(all);
  EventPacketStream stream(src, cfg);
  EventFrameBuilder from_stream(und, cfg), from_array(und, cfg);
  const EventArray* events = nullptr;
  std::size_t begin = 0, frames = 0, differing = 0;
  EventFrame a, b;
  while (stream.next(events, begin)) {
    from_stream.build(*events, begin, a, stream.base());
    from_array.build(all, static_cast<std::size_t>(stream.base() + begin), b);
    if (cv::norm(a.delta, b.delta, cv::NORM_INF) != 0.0) ++differing;
    ++frames;
  }
  EXPECT_GT(stream.base(), 0u);  // the stream did drop events
  EXPECT_EQ(frames, (all.size() - cfg.num_events) / cfg.stride() + 1);
  EXPECT_EQ(differing, 0u);
}

// Packet starts of a capped stream read in chunks of `chunk` events.
std::vector<std::uint64_t> cappedStarts(const EventArray& all, std::size_t chunk, double max_rate_hz) {
  struct Source : EventSource {
    const EventArray& all;
    std::size_t chunk, pos = 0;
    Source(const EventArray& a, std::size_t c) : all(a), chunk(c) {}
    std::size_t read(EventArray& out, std::size_t max_events) override {
      const std::size_t n = std::min({max_events, chunk, all.size() - pos});
      for (std::size_t i = pos; i < pos + n; ++i) out.push_back(all.t[i], all.x[i], all.y[i], all.p[i]);
      pos += n;
      return n;
    }
  } src(all, chunk);
  EventPacketStream stream(src, 1000, 500, 1000, max_rate_hz);
  const EventArray* events = nullptr;
  std::size_t begin = 0;
  std::vector<std::uint64_t> starts;
  while (stream.next(events, begin)) starts.push_back(stream.base() + begin);
  return starts;
}

TEST(EventPackets, ARateCapSpacesPacketsInTimeWhateverTheChunks) {
  // 3 s of events: 10 k events/s (a packet every 50 ms), then 2 M events/s (every 0.25 ms), then
  // 10 k events/s again.
  EventArray all;
  for (TimeNs t = 0, i = 0; t < fromSeconds(3.0); ++i) {
    t += t < fromSeconds(1.0) || t >= fromSeconds(2.0) ? 100'000 : 500;
    all.push_back(t, static_cast<std::uint16_t>(i % 240), static_cast<std::uint16_t>(i % 180),
                  i % 3 ? 1 : -1);
  }
  const std::vector<std::uint64_t> uncapped = cappedStarts(all, 1 << 18, 0);
  const std::vector<std::uint64_t> capped = cappedStarts(all, 1 << 18, 100);
  EXPECT_EQ(capped, cappedStarts(all, 777, 100));  // the same packets, whatever the chunks
  std::size_t slow_uncapped = 0, slow_capped = 0;
  for (std::uint64_t s : uncapped) slow_uncapped += all.t[s] < fromSeconds(1.0) ? 1 : 0;
  for (std::uint64_t s : capped) slow_capped += all.t[s] < fromSeconds(1.0) ? 1 : 0;
  EXPECT_EQ(slow_capped, slow_uncapped);  // 20 packets/s: under the cap, untouched
  // The fast second: 4000 packets uncapped, at most 100 + 1 capped, never closer than 10 ms.
  std::size_t fast = 0;
  for (std::size_t k = 0; k < capped.size(); ++k) {
    if (k > 0) EXPECT_GE(all.t[capped[k]] - all.t[capped[k - 1]], fromSeconds(0.01)) << k;
    fast += all.t[capped[k]] >= fromSeconds(1.0) && all.t[capped[k]] < fromSeconds(2.0) ? 1 : 0;
  }
  EXPECT_GE(fast, 99u);
  EXPECT_LE(fast, 101u);
  EXPECT_GT(uncapped.size(), 4000u);
}

Keyframe syntheticKeyframe(const CameraModel& cam, int n, unsigned seed) {
  Keyframe kf;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(20, cam.width - 20), uy(20, cam.height - 20), g(-0.5, 0.5),
      d(0.6, 3.0);
  for (int i = 0; i < n; ++i) {
    KeyframePoint p;
    p.u = static_cast<float>(ux(rng));
    p.v = static_cast<float>(uy(rng));
    p.gx = static_cast<float>(g(rng));
    p.gy = static_cast<float>(g(rng));
    p.inv_depth = 1.0 / d(rng);
    kf.points.push_back(p);
  }
  return kf;
}

TEST(EventTracker, JacobianMatchesNumericDifferences) {
  const CameraModel cam = pinhole240();
  EventTracker tracker(cam, {});
  tracker.setKeyframe(syntheticKeyframe(cam, 400, 7));
  const cv::Mat delta = smoothRandomImage(cam.width, cam.height, 11, 3.0);
  const SE3 T(SO3::exp(Vec3(0.01, -0.02, 0.005)), Vec3(0.02, -0.01, 0.03));
  Vec6 nu;
  nu << 0.3, -0.2, 0.1, 0.5, -0.4, 0.2;
  nu.normalize();
  Eigen::VectorXd r;
  Eigen::MatrixXd J;
  const int n = tracker.evaluate(delta, T, nu, r, &J);
  ASSERT_GT(n, 300);
  const double h = 1e-6;
  Eigen::MatrixXd Jn(n, 12);
  for (int k = 0; k < 12; ++k) {
    Eigen::VectorXd rp, rm;
    if (k < 6) {
      const Vec6 d = Vec6::Unit(k) * h;
      ASSERT_EQ(tracker.evaluate(delta, SE3::exp(d) * T, nu, rp, nullptr), n);
      ASSERT_EQ(tracker.evaluate(delta, SE3::exp(-d) * T, nu, rm, nullptr), n);
    } else {
      const Vec6 d = Vec6::Unit(k - 6) * h;
      tracker.evaluate(delta, T, nu + d, rp, nullptr);
      tracker.evaluate(delta, T, nu - d, rm, nullptr);
    }
    Jn.col(k) = (rp - rm) / (2 * h);
  }
  for (int k = 0; k < 12; ++k) {
    const double rel = (J.col(k) - Jn.col(k)).norm() / Jn.col(k).norm();
    EXPECT_LT(rel, 1e-4) << "parameter " << k;
  }
}

// The motion prior's gradient and Gauss-Newton Hessian in the solve against numeric derivatives of its
// cost, a little off the prior (where e(exp(ξ) T) ≈ e(T) + ξ holds to O(|e|)) with unequal sigmas.
TEST(EventTracker, PosePriorGradientAndHessianMatchNumericDifferences) {
  PosePrior prior;
  prior.T_ef_kf = SE3(SO3::exp(Vec3(0.02, -0.01, 0.03)), Vec3(0.1, -0.05, 0.02));
  prior.sigma << 0.01, 0.02, 0.005, 0.004, 0.008, 0.002;
  const double scale = 0.3;
  Vec6 off;
  off << 2e-4, -1e-4, 3e-4, -2e-4, 1e-4, 2e-4;
  const SE3 T = SE3::exp(off) * prior.T_ef_kf;
  Eigen::Matrix<double, 12, 12> H = Eigen::Matrix<double, 12, 12>::Zero();
  Eigen::Matrix<double, 12, 1> g = Eigen::Matrix<double, 12, 1>::Zero();
  const double cost = accumulatePosePrior(prior, scale, T, H, g);
  const auto costAt = [&](const Vec6& xi) {
    Eigen::Matrix<double, 12, 12> h = Eigen::Matrix<double, 12, 12>::Zero();
    Eigen::Matrix<double, 12, 1> q = Eigen::Matrix<double, 12, 1>::Zero();
    return accumulatePosePrior(prior, scale, SE3::exp(xi) * T, h, q);
  };
  EXPECT_NEAR(cost, costAt(Vec6::Zero()), 1e-15);
  const Vec6 info = scale * prior.sigma.cwiseProduct(prior.sigma).cwiseInverse();
  EXPECT_NEAR(cost, 0.5 * off.dot(info.cwiseProduct(off)), 1e-3 * cost);
  const double h = 1e-7;
  Vec6 num;
  for (int k = 0; k < 6; ++k) num[k] = (costAt(Vec6::Unit(k) * h) - costAt(-Vec6::Unit(k) * h)) / (2 * h);
  EXPECT_LT((g.head<6>() - num).norm(), 1e-2 * num.norm())
      << g.head<6>().transpose() << " vs " << num.transpose();
  const double hh = 1e-4;  // second differences: the Hessian of the cost at T
  for (int k = 0; k < 6; ++k) {
    const double d2 = (costAt(Vec6::Unit(k) * hh) - 2 * cost + costAt(-Vec6::Unit(k) * hh)) / (hh * hh);
    EXPECT_NEAR(H(k, k), d2, 1e-2 * d2) << "pose parameter " << k;
  }
  EXPECT_TRUE((H.bottomRows<6>().isZero() && H.topRightCorner<6, 6>().isZero() && g.tail<6>().isZero()));
  EXPECT_TRUE((H.topLeftCorner<6, 6>() - Mat6(info.asDiagonal())).isZero(1e-12));
}

TEST(EventTracker, EgmRowIsTheGradientDottedWithThePixelFlow) {
  // A pure x-translation of the camera moves a point at depth Z by -fx/Z px per metre along x.
  const CameraModel cam = pinhole240();
  const Row6 a = egmRow(cam, cam.cx, cam.cy, 0.7, 0.0, 0.5);  // Z = 2 m, at the principal point
  Vec6 nu = Vec6::Zero();
  nu[0] = 1.0;
  EXPECT_NEAR(a.dot(nu), -0.7 * (-cam.fx / 2.0), 1e-9);
  nu.setZero();
  nu[4] = 1.0;  // rotation about y: flow -(1 + x^2) fx = -fx at the centre
  EXPECT_NEAR(a.dot(nu), -0.7 * (-cam.fx), 1e-9);
}

// Every column of the EGM row against the numeric image velocity of the point, on a lens with fx != fy,
// off the principal point and with both gradient components non-zero: a centred point or a gradient
// along x alone would hide a wrong sign or focal length in the y row.
TEST(EventTracker, EgmRowMatchesTheNumericPixelFlowInEveryColumn) {
  CameraModel cam = pinhole240();
  cam.fx = 210.0, cam.fy = 180.0, cam.cx = 121.0, cam.cy = 87.0;
  const double u = 40.0, v = 150.0, Z = 1.7, gx = 0.4, gy = -0.9;
  const Vec3 p_c((u - cam.cx) / cam.fx * Z, (v - cam.cy) / cam.fy * Z, Z);
  const Row6 a = egmRow(cam, u, v, gx, gy, 1.0 / Z);
  const double h = 1e-6;
  for (int k = 0; k < 6; ++k) {
    // The camera moves with twist ν = e_k: a static point moves by -(v + ω × p) in the camera frame.
    const Vec6 nu = Vec6::Unit(k);
    const Vec3 dp = -(nu.head<3>() + nu.tail<3>().cross(p_c));
    const Vec2 flow = (cam.project(p_c + h * dp) - cam.project(p_c - h * dp)) / (2 * h);
    const double expected = -(gx * flow.x() + gy * flow.y());
    EXPECT_NEAR(a[k], expected, 1e-6 * (1 + std::abs(expected))) << "column " << k;
  }
}

// The row for a camera away from the keyframe against numbers made without it: the current image is the
// keyframe's (log intensity linear in the keyframe's pixels) seen through the plane z = Z of the
// keyframe, its gradient taken by numeric differences through that warp, and the point's image velocity
// in the current camera under each twist (given in the keyframe's axes, the rows' convention).
TEST(EventTracker, EgmRowAtAViewIsTheCurrentGradientDottedWithTheCurrentFlow) {
  CameraModel cam = pinhole240();
  cam.fx = 210.0, cam.fy = 180.0, cam.cx = 121.0, cam.cy = 87.0;
  const double u = 60.0, v = 120.0, Z = 1.7, gx = 0.4, gy = -0.9;
  const SE3 T_c_kf(SO3::exp(Vec3(0.1, -0.25, 0.15)), Vec3(0.3, -0.1, 0.2));
  const Row6 a = egmRowAtView(cam, u, v, gx, gy, 1.0 / Z, T_c_kf);
  EXPECT_LT((egmRowAtView(cam, u, v, gx, gy, 1.0 / Z, SE3()) - egmRow(cam, u, v, gx, gy, 1.0 / Z)).norm(),
            1e-9);

  const Vec3 q = T_c_kf * Vec3((u - cam.cx) / cam.fx * Z, (v - cam.cy) / cam.fy * Z, Z);
  const Vec2 uc = cam.project(q);
  // Log intensity of the current image at pixel x: the keyframe's at the plane point that x sees.
  const SE3 T_kf_c = T_c_kf.inverse();
  const auto L = [&](const Vec2& x) {
    const Vec3 d = T_kf_c.so3() * cam.pinholeRay(x.x(), x.y());
    const Vec3& o = T_kf_c.translation();
    const Vec3 X = o + (Z - o.z()) / d.z() * d;
    return gx * (cam.fx * X.x() / X.z() + cam.cx) + gy * (cam.fy * X.y() / X.z() + cam.cy);
  };
  const double h = 1e-4, e = 1e-6;
  const Vec2 g((L(uc + Vec2(h, 0)) - L(uc - Vec2(h, 0))) / (2 * h),
               (L(uc + Vec2(0, h)) - L(uc - Vec2(0, h))) / (2 * h));
  const Mat3 R = T_c_kf.rotationMatrix();
  for (int k = 0; k < 6; ++k) {
    const Vec6 nu_kf = Vec6::Unit(k);
    const Vec3 vel = R * nu_kf.head<3>(), omega = R * nu_kf.tail<3>();
    const Vec3 dq = -(vel + omega.cross(q));
    const Vec2 flow = (cam.project(q + e * dq) - cam.project(q - e * dq)) / (2 * e);
    const double expected = -g.dot(flow);
    EXPECT_NEAR(a[k], expected, 1e-5 * (1 + std::abs(expected))) << "column " << k;
  }
}

TEST(EventTracker, KeyframeWithoutDepthIsAClearError) {
  const CameraModel cam = pinhole240();
  EventTracker tracker(cam, {});
  Keyframe kf = syntheticKeyframe(cam, 10, 1);
  for (auto& p : kf.points) p.inv_depth = 0;
  EXPECT_THROW(tracker.setKeyframe(kf), std::invalid_argument);
}

// Sobel gradients of a smooth random image (seed), per pixel, as the keyframes have them.
void randomGradients(int w, int h, unsigned seed, cv::Mat& gx, cv::Mat& gy) {
  const cv::Mat img = smoothRandomImage(w, h, seed, 1.5);
  cv::Sobel(img, gx, CV_32F, 1, 0, 3, 1.0 / 8);
  cv::Sobel(img, gy, CV_32F, 0, 1, 3, 1.0 / 8);
}

// How many size x size blocks from (4, 4) up to (w - 4, h - 4) hold none of the points.
int emptyBlocks(const std::vector<cv::Point>& pts, int w, int h, int size) {
  int empty = 0;
  for (int by = 4; by + size <= h - 4; by += size)
    for (int bx = 4; bx + size <= w - 4; bx += size) {
      int c = 0;
      for (const auto& p : pts) c += p.x >= bx && p.x < bx + size && p.y >= by && p.y < by + size;
      empty += c == 0;
    }
  return empty;
}

TEST(PointSelection, SpreadsOverTilesAndHonoursFraction) {
  cv::Mat gx, gy;
  randomGradients(240, 180, 5, gx, gy);
  PointSelectionConfig cfg;
  cfg.min_gradient = 0;
  cfg.fraction = 0.1;
  const auto pts = selectPoints(gx, gy, cfg);
  const double usable = (240 - 8) * (180 - 8);
  EXPECT_NEAR(pts.size() / usable, 0.1, 0.02);
  EXPECT_EQ(emptyBlocks(pts, 240, 180, 11), 0);  // every 11x11 tile has its share
  cfg.max_points = 500;
  EXPECT_EQ(selectPoints(gx, gy, cfg).size(), 500u);
}

// Beyond full_density_pixels an image keeps the point count of an image that size, still spread: at
// 640x480 with a 240x180 density, about 240*180*fraction points and none of its 32x32 blocks empty.
TEST(PointSelection, LargeImagesKeepTheCountOfTheFullDensitySize) {
  cv::Mat gx, gy;
  randomGradients(640, 480, 7, gx, gy);
  PointSelectionConfig cfg;
  cfg.min_gradient = 0;
  cfg.fraction = 0.1;
  const std::size_t full = selectPoints(gx, gy, cfg).size();
  cfg.full_density_pixels = 240 * 180;
  const auto pts = selectPoints(gx, gy, cfg);
  EXPECT_NEAR(static_cast<double>(pts.size()), 0.1 * 240 * 180, 0.1 * 0.1 * 240 * 180);
  EXPECT_GT(full, 6 * pts.size());
  EXPECT_EQ(emptyBlocks(pts, 640, 480, 32), 0);
  // Images up to that size are selected as before.
  cfg.full_density_pixels = 640 * 480;
  EXPECT_EQ(selectPoints(gx, gy, cfg).size(), full);
}

}  // namespace
}  // namespace eds
