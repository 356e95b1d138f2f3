#include "system/track_only.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>

#include "core/error.hpp"
#include "core/undistorter.hpp"
#include "frontend/event_packets.hpp"
#include "io/output_file.hpp"
#include "mapping/depth_fill.hpp"
#include "system/run_stats.hpp"

namespace eds {

namespace {

cv::Mat toGray8(const cv::Mat& f) {
  double m = 0;
  cv::minMaxLoc(cv::abs(f), nullptr, &m);
  cv::Mat out;
  f.convertTo(out, CV_8U, m > 0 ? 127.0 / m : 1.0, 128.0);
  return out;
}

struct KeyframeBuilder {
  const Sequence& seq;
  const Undistorter& und;
  const TrackOnlyConfig& cfg;
  std::mt19937_64 rng;

  // The undistorted frame as CV_32F in [0, 1].
  cv::Mat image(std::size_t frame) const {
    cv::Mat f;
    und.undistortImage(seq.loadFrame(frame)).convertTo(f, CV_32F, 1.0 / 255.0);
    return f;
  }

  Keyframe make(int id, std::size_t frame, const SE3& T_w_kf, const cv::Mat& img) {
    Keyframe kf;
    kf.id = id;
    kf.t = seq.frames()[frame].t;
    kf.T_w_kf = T_w_kf;
    setKeyframeImage(kf, img, cfg.keyframe_image);
    const std::vector<cv::Point> pts = selectPoints(kf.grad_x, kf.grad_y, cfg.points);
    if (pts.empty())
      throw std::runtime_error("no points selected in frame " + seq.frames()[frame].path.string() +
                               " (flat image? lower --min-gradient)");
    const auto depth = seq.loadDepth(frame);
    if (!depth)
      throw InputError((seq.dir() / "depth" / seq.frames()[frame].path.filename()).string(),
                       "depth map not found: --depth-from-gt needs the sequence's depth/ maps");
    std::vector<double> zs;
    for (const cv::Point& p : pts) {
      // Depth maps are on the raw (distorted) grid; z is the same in the undistorted camera.
      const int xr = static_cast<int>(std::lround(und.mapX().at<float>(p.y, p.x)));
      const int yr = static_cast<int>(std::lround(und.mapY().at<float>(p.y, p.x)));
      double z = 0;
      if (xr >= 0 && yr >= 0 && xr < depth->cols && yr < depth->rows) z = depth->at<float>(yr, xr);
      KeyframePoint kp;
      kp.u = static_cast<float>(p.x);
      kp.v = static_cast<float>(p.y);
      kp.gx = kf.grad_x.at<float>(p.y, p.x);
      kp.gy = kf.grad_y.at<float>(p.y, p.x);
      kp.inv_depth = z > 0 ? 1.0 / z : 0.0;
      if (z > 0) zs.push_back(z);
      kf.points.push_back(kp);
    }
    if (zs.empty())
      throw InputError((seq.dir() / "depth" / seq.frames()[frame].path.filename()).string(),
                       "no selected point has a depth");
    std::nth_element(zs.begin(), zs.begin() + zs.size() / 2, zs.end());
    const double median = zs[zs.size() / 2];
    if (cfg.depth_noise > 0) {
      std::normal_distribution<double> noise(0.0, cfg.depth_noise * median);
      for (KeyframePoint& kp : kf.points)
        if (kp.inv_depth > 0) kp.inv_depth = 1.0 / std::max(0.05 * median, 1.0 / kp.inv_depth + noise(rng));
    }
    if (cfg.depth_median_px > 0) {
      std::vector<cv::Point2f> px;
      std::vector<double> rho;
      for (const KeyframePoint& kp : kf.points) px.emplace_back(kp.u, kp.v), rho.push_back(kp.inv_depth);
      medianFilterInverseDepth(px, rho, cfg.depth_median_px);
      for (std::size_t i = 0; i < rho.size(); ++i) kf.points[i].inv_depth = rho[i];
    }
    return kf;
  }
};

double medianDepth(const Keyframe& kf) {
  std::vector<double> z;
  for (const auto& p : kf.points)
    if (p.inv_depth > 0) z.push_back(1.0 / p.inv_depth);
  std::nth_element(z.begin(), z.begin() + z.size() / 2, z.end());
  return z[z.size() / 2];
}

// Median of the last five values (fewer when there are fewer).
double recentMedian(const std::vector<double>& v) {
  constexpr std::size_t kRecent = 5;
  std::array<double, kRecent> last{};
  const std::size_t n = std::min(v.size(), kRecent);
  std::copy(v.end() - static_cast<std::ptrdiff_t>(n), v.end(), last.begin());
  std::nth_element(last.begin(), last.begin() + n / 2, last.begin() + n);
  return last[n / 2];
}

}  // namespace

namespace {

// The tracking-only loop: event frames tracked against the current keyframe, a new keyframe from the
// newest frame when the policy (or a lost track) asks.
class TrackOnlyRun {
 public:
  TrackOnlyRun(const Sequence& seq, const TrackOnlyConfig& cfg, const Undistorter& und, TrackOnlyResult& res)
      : seq_(seq),
        cfg_(cfg),
        cam_(und.pinhole()),
        res_(res),
        tracker_(cam_, cfg.tracker),
        builder_{seq, und, cfg, std::mt19937_64(cfg.seed)},
        frame_tracker_(cam_, cfg.frame_tracker) {
    const Trajectory gt = seq.groundTruth();
    if (gt.empty()) throw InputError((seq.dir() / "groundtruth.txt").string(), "empty ground truth");
    kf_ = builder_.make(0, 0, poseAt(gt, seq.frames()[0].t), builder_.image(0));
    adoptKeyframe();
    res_.trajectory.push_back({kf_.t, kf_.T_w_kf});
  }

  // One event frame: a keyframe hand-over first if one is due, then the tracking.
  void process(const EventFrame& ef) {
    if (need_keyframe_) handOver(ef.t);
    track(ef);
  }

 private:
  void adoptKeyframe() {
    tracker_.setKeyframe(kf_);
    if (cfg_.refine_keyframes) frame_tracker_.setKeyframe(kf_);
    kf_median_depth_ = medianDepth(kf_);
    kf_in_view_ = tracker_.pointsInView(SE3(), cam_.width, cam_.height);
    ++res_.keyframes;
    res_.points_per_keyframe.push_back(static_cast<int>(tracker_.numPoints()));
  }

  // The newest frame not after t (and newer than the keyframe's) becomes the keyframe, at the event
  // pose refined by aligning the frame to the old keyframe: frames are sharper than event frames, so
  // this removes most of the error a hand-over would pass on. After a lost track the seed is the last
  // good pose, and the alignment is what recovers.
  void handOver(TimeNs t) {
    const auto& frames = seq_.frames();
    std::size_t f = kf_frame_;
    while (f + 1 < frames.size() && frames[f + 1].t <= t) ++f;
    if (f == kf_frame_) return;
    SE3 T_w_kf_new = poseAt(res_.trajectory, frames[f].t);
    const cv::Mat img = builder_.image(f);
    if (cfg_.refine_keyframes) {
      SE3 T_f_kf = T_w_kf_new.inverse() * kf_.T_w_kf;
      double alpha = 1.0, beta = 0.0;
      const auto t0 = Clock::now();
      const FrameTrackResult fr = frame_tracker_.track(img, T_f_kf, alpha, beta);
      res_.frame_track_ms.push_back(msSince(t0));
      if (fr.ok)
        T_w_kf_new = kf_.T_w_kf * T_f_kf.inverse();
      else
        res_.failures.push_back({frames[f].t, "frame alignment failed (rmse " + std::to_string(fr.rmse) +
                                                  "); keyframe keeps the event pose"});
    }
    const SE3 T_w_ef = kf_.T_w_kf * T_ef_kf_.inverse();
    const SE3 T_kfnew_kfold = T_w_kf_new.inverse() * kf_.T_w_kf;
    kf_ = builder_.make(static_cast<int>(res_.keyframes), f, T_w_kf_new, img);
    kf_frame_ = f;
    adoptKeyframe();
    T_ef_kf_ = T_w_ef.inverse() * T_w_kf_new;
    // ν is a twist in the keyframe's frame: rotate it into the new one.
    const Mat3 R = T_kfnew_kfold.rotationMatrix();
    nu_.head<3>() = R * nu_.head<3>();
    nu_.tail<3>() = R * nu_.tail<3>();
    if (lost_) nu_.setZero();
    t_prev_ = t_last_ = -1;
    need_keyframe_ = lost_ = false;
    recent_corr_.clear();
    recent_cost_.clear();
  }

  // Lost-track check: correlation far below, or cost far above, their recent level on this keyframe.
  std::string lostTrack(const TrackResult& tr) const {
    if (!tr.ok || recent_corr_.size() < 3) return tr.failure;
    const double corr_ref = recentMedian(recent_corr_), cost_ref = recentMedian(recent_cost_);
    if (cfg_.min_correlation_ratio > 0 && tr.correlation < cfg_.min_correlation_ratio * corr_ref)
      return "correlation " + std::to_string(tr.correlation) + " fell below " +
             std::to_string(cfg_.min_correlation_ratio) + " of its recent median " + std::to_string(corr_ref);
    if (cfg_.max_cost_ratio > 0 && tr.cost > cfg_.max_cost_ratio * cost_ref)
      return "cost " + std::to_string(tr.cost) + " rose above " + std::to_string(cfg_.max_cost_ratio) +
             " times its recent median " + std::to_string(cost_ref);
    return tr.failure;
  }

  void writeDebugImage(const EventFrame& ef, const SE3& T_ef_kf, const Vec6& nu) const {
    cv::Mat both;
    cv::hconcat(toGray8(ef.delta), toGray8(tracker_.predictedImage(T_ef_kf, nu, cam_.width, cam_.height)),
                both);
    char name[64];
    std::snprintf(name, sizeof name, "ef_%06zu.png", res_.event_frames - 1);
    cv::imwrite((cfg_.debug_dir / name).string(), both);
  }

  void track(const EventFrame& ef) {
    // Constant-velocity prediction from the last two event frames on this keyframe.
    SE3 T_est = T_ef_kf_;
    if (t_prev_ >= 0 && t_last_ > t_prev_) {
      const double alpha = static_cast<double>(ef.t - t_last_) / static_cast<double>(t_last_ - t_prev_);
      const SE3 T_step = T_ef_kf_ * T_prev_.inverse();  // previous -> last event frame
      T_est = SE3::exp(std::clamp(alpha, 0.0, 3.0) * T_step.log()) * T_ef_kf_;
    }
    const auto tt = Clock::now();
    Vec6 nu_est = nu_;
    // Coarse-to-fine only when the prediction is weak (first frames on a keyframe, after a failure).
    const TrackResult tr = tracker_.track(ef, T_est, nu_est, t_prev_ >= 0 ? 1 : 0);
    res_.track_ms.push_back(msSince(tt));
    if (!cfg_.debug_dir.empty()) writeDebugImage(ef, T_est, nu_est);
    const std::string failure = lostTrack(tr);
    if (!failure.empty()) {
      res_.failures.push_back({ef.t, failure});
      need_keyframe_ = lost_ = true;  // go on from the next keyframe
      return;
    }
    ++res_.tracked;
    recent_corr_.push_back(tr.correlation);
    recent_cost_.push_back(tr.cost);
    T_prev_ = T_ef_kf_;
    t_prev_ = t_last_;
    T_ef_kf_ = T_est;
    nu_ = nu_est;
    t_last_ = ef.t;
    res_.trajectory.push_back({ef.t, kf_.T_w_kf * T_ef_kf_.inverse()});
    const bool drop = tr.points_in_view < (1.0 - cfg_.policy.max_point_drop) * kf_in_view_;
    const bool rotated = T_ef_kf_.so3().angle() > cfg_.policy.max_rotation_deg * M_PI / 180.0;
    const bool moved = T_ef_kf_.translation().norm() > cfg_.policy.max_translation_ratio * kf_median_depth_;
    need_keyframe_ = drop || rotated || moved;
  }

  const Sequence& seq_;
  const TrackOnlyConfig& cfg_;
  const CameraModel& cam_;
  TrackOnlyResult& res_;
  EventTracker tracker_;
  KeyframeBuilder builder_;
  FrameTracker frame_tracker_;
  Keyframe kf_;
  std::size_t kf_frame_ = 0;
  double kf_median_depth_ = 1;
  int kf_in_view_ = 0;
  SE3 T_ef_kf_, T_prev_;  // current estimate and the one before it on this keyframe
  Vec6 nu_ = Vec6::Zero();
  TimeNs t_prev_ = -1, t_last_ = -1;
  bool need_keyframe_ = false, lost_ = false;
  // Correlations and costs of the event frames tracked on this keyframe (the lost-track check's reference).
  std::vector<double> recent_corr_, recent_cost_;
};

}  // namespace

TrackOnlyResult runTrackOnly(const Sequence& seq, const TrackOnlyConfig& cfg) {
  const auto wall0 = Clock::now();
  cfg.event_frame.validate();
  cfg.points.validate();
  if (!(cfg.min_correlation_ratio >= 0 && cfg.min_correlation_ratio < 1))
    throw std::invalid_argument("min_correlation_ratio must be in [0, 1) (0: no lost-track check)");
  if (!(cfg.max_cost_ratio == 0 || cfg.max_cost_ratio > 1))
    throw std::invalid_argument("max_cost_ratio must be 0 (off) or > 1");
  if (!seq.hasFrames())
    throw InputError((seq.dir() / "images.txt").string(), "tracking needs frames for keyframes");
  const Undistorter und(seq.camera());
  TrackOnlyResult res;
  TrackOnlyRun run(seq, cfg, und, res);
  EventFrameBuilder ef_builder(und, cfg.event_frame);
  const auto& frames = seq.frames();
  const TimeNs t_end =
      cfg.duration_s > 0 ? frames[0].t + fromSeconds(cfg.duration_s) : std::numeric_limits<TimeNs>::max();
  auto src = seq.openEvents();
  EventPacketStream packets(*src, static_cast<std::size_t>(cfg.event_frame.num_events),
                            cfg.event_frame.stride(), cfg.event_frame.lookahead());
  const EventArray* events = nullptr;
  std::size_t begin = 0;
  EventFrame ef;
  TimeNs last_ef_t = -1;
  while (packets.next(events, begin)) {
    const auto tb = Clock::now();
    ef_builder.build(*events, begin, ef, packets.base());
    if (ef.t < frames[0].t) continue;
    if (ef.t > t_end) break;
    res.build_ms.push_back(msSince(tb));
    ++res.event_frames;
    last_ef_t = ef.t;
    run.process(ef);
  }
  if (res.event_frames == 0)
    throw InputError(seq.eventsFile().string(), "no event frame after the first frame (too few events?)");
  res.sequence_s = toSeconds(last_ef_t - frames[0].t);
  res.wall_s = std::chrono::duration<double>(Clock::now() - wall0).count();
  return res;
}

void writeTrackSummary(const std::filesystem::path& file, const TrackOnlyResult& r, const std::string& mode,
                       const std::vector<std::pair<std::string, double>>& config) {
  nlohmann::json j;
  j["mode"] = mode;
  j["counts"] = {{"event_frames", r.event_frames},
                 {"tracked", r.tracked},
                 {"failures", r.failures.size()},
                 {"keyframes", r.keyframes},
                 {"poses", r.trajectory.size()}};
  j["points_per_keyframe"] = r.points_per_keyframe;
  j["timings_ms"] = {{"event_frame_build", timingStats(r.build_ms)},
                     {"track", timingStats(r.track_ms)},
                     {"keyframe_frame_alignment", timingStats(r.frame_track_ms)}};
  j["wall_s"] = r.wall_s;
  j["sequence_s"] = r.sequence_s;
  j["real_time_factor"] = r.sequence_s > 0 ? r.wall_s / r.sequence_s : 0.0;
  nlohmann::json fails = nlohmann::json::array();
  for (const auto& f : r.failures) fails.push_back({{"t", toSeconds(f.t)}, {"reason", f.reason}});
  j["failures"] = fails;
  for (const auto& [name, value] : config) j["config"][name] = value;
  writeTextFile(file, j.dump(2) + "\n");
}

void writeTrackSummary(const std::filesystem::path& file, const TrackOnlyResult& r,
                       const TrackOnlyConfig& cfg) {
  writeTrackSummary(file, r, "track --depth-from-gt",
                    {{"events_per_frame", cfg.event_frame.num_events},
                     {"overlap", cfg.event_frame.overlap},
                     {"tile", cfg.points.tile},
                     {"point_fraction", cfg.points.fraction},
                     {"max_points", cfg.points.max_points},
                     {"depth_noise", cfg.depth_noise},
                     {"seed", static_cast<double>(cfg.seed)}});
}

}  // namespace eds
