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
#include "frontend/point_selection.hpp"
#include "io/output_file.hpp"
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

  // The frame's selected pixels with the depth map's depth there (plus noise); the event front-end
  // median-filters the inverse depths.
  Keyframe make(int id, std::size_t frame, const SE3& T_w_kf, const cv::Mat& img) {
    Keyframe kf;
    kf.id = id;
    kf.t = seq.frames()[frame].t;
    kf.T_w_kf = T_w_kf;
    setKeyframeImage(kf, img);
    const std::vector<cv::Point> pts = selectPoints(kf.grad_x, kf.grad_y, cfg.events.points);
    const std::string depth_file = (seq.dir() / "depth" / seq.frames()[frame].path.filename()).string();
    if (pts.empty())
      throw std::runtime_error("no points selected in frame " + seq.frames()[frame].path.string() +
                               " (flat image? lower --min-gradient)");
    const auto depth = seq.loadDepth(frame);
    if (!depth)
      throw InputError(depth_file, "depth map not found: --depth-from-gt needs the sequence's depth/ maps");
    std::vector<double> zs;
    for (const cv::Point& p : pts) {
      // Depth maps are on the raw (distorted) grid; z is the same in the undistorted camera.
      const int xr = static_cast<int>(std::lround(und.mapX().at<float>(p.y, p.x)));
      const int yr = static_cast<int>(std::lround(und.mapY().at<float>(p.y, p.x)));
      double z = 0;
      if (xr >= 0 && yr >= 0 && xr < depth->cols && yr < depth->rows) z = depth->at<float>(yr, xr);
      if (!(z > 0)) continue;
      KeyframePoint kp;
      kp.u = static_cast<float>(p.x);
      kp.v = static_cast<float>(p.y);
      kp.inv_depth = 1.0 / z;
      zs.push_back(z);
      kf.points.push_back(kp);
    }
    if (zs.empty()) throw InputError(depth_file, "no selected point has a depth");
    std::nth_element(zs.begin(), zs.begin() + zs.size() / 2, zs.end());
    const double median = zs[zs.size() / 2];
    if (cfg.depth_noise > 0) {
      std::normal_distribution<double> noise(0.0, cfg.depth_noise * median);
      for (KeyframePoint& kp : kf.points)
        kp.inv_depth = 1.0 / std::max(0.05 * median, 1.0 / kp.inv_depth + noise(rng));
    }
    return kf;
  }
};

}  // namespace

namespace {

// The tracking-only loop: the event front-end tracks event frames against the current keyframe; a
// new keyframe comes from the newest frame when the policy (or a lost track) asks.
class TrackOnlyRun {
 public:
  TrackOnlyRun(const Sequence& seq, const TrackOnlyConfig& cfg, const Undistorter& und, TrackOnlyResult& res)
      : seq_(seq),
        cfg_(cfg),
        cam_(und.pinhole()),
        res_(res),
        front_(cam_, cfg.events),
        builder_{seq, und, cfg, std::mt19937_64(cfg.seed)},
        frame_tracker_(cam_, cfg.frame_tracker) {
    const Trajectory gt = seq.groundTruth();
    if (gt.empty()) throw InputError((seq.dir() / "groundtruth.txt").string(), "empty ground truth");
    adopt(builder_.make(0, 0, poseAt(gt, seq.frames()[0].t), builder_.image(0)));
    res_.trajectory.push_back({front_.reference().t, front_.T_w_kf()});
  }

  // One event frame: a keyframe hand-over first if one is due, then the tracking.
  void process(const EventFrame& ef) {
    if (need_keyframe_) handOver(ef.t);
    track(ef);
  }

 private:
  // Makes kf the reference; a keyframe with too few points with a depth is not taken (the first one
  // must be).
  void adopt(Keyframe kf) {
    front_.setDenseReference(kf, kf.T_w_kf);
    if (front_.referenceId() != kf.id) {
      const std::string why =
          "keyframe at " + std::to_string(toSeconds(kf.t)) + " s: too few points with a depth";
      if (!front_.hasReference()) throw std::runtime_error(why);
      res_.failures.push_back({kf.t, why + "; tracking goes on against the previous keyframe"});
      return;
    }
    // With the front-end's filtered depths: the frame alignment uses them too.
    if (cfg_.refine_keyframes) frame_tracker_.setKeyframe(front_.reference());
    kf_in_view_ = front_.pointsInView(SE3());
    ++res_.keyframes;
    res_.points_per_keyframe.push_back(front_.numPoints());
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
      SE3 T_f_kf = T_w_kf_new.inverse() * front_.T_w_kf();
      double alpha = 1.0, beta = 0.0;
      const auto t0 = Clock::now();
      const FrameTrackResult fr = frame_tracker_.track(img, T_f_kf, alpha, beta);
      res_.frame_track_ms.push_back(msSince(t0));
      if (fr.ok)
        T_w_kf_new = front_.T_w_kf() * T_f_kf.inverse();
      else
        res_.failures.push_back({frames[f].t, "frame alignment failed (rmse " + std::to_string(fr.rmse) +
                                                  "); keyframe keeps the event pose"});
    }
    adopt(builder_.make(static_cast<int>(res_.keyframes), f, T_w_kf_new, img));
    kf_frame_ = f;  // also when not taken: the next hand-over waits for a newer frame
    if (lost_) front_.restartFrom(res_.trajectory.back().T_w_c);
    need_keyframe_ = lost_ = false;
  }

  void writeDebugImage(const EventFrame& ef) const {
    cv::Mat both;
    cv::hconcat(toGray8(ef.delta), toGray8(front_.lastPrediction()), both);
    char name[64];
    std::snprintf(name, sizeof name, "ef_%06zu.png", res_.event_frames - 1);
    cv::imwrite((cfg_.debug_dir / name).string(), both);
  }

  void track(const EventFrame& ef) {
    const auto tt = Clock::now();
    std::string failure;
    const std::optional<SE3> T_w_ef = front_.track(ef, nullptr, &failure);
    res_.track_ms.push_back(msSince(tt));
    if (!cfg_.debug_dir.empty()) writeDebugImage(ef);
    if (!T_w_ef) {
      res_.failures.push_back({ef.t, failure});
      need_keyframe_ = lost_ = true;  // go on from the next keyframe
      return;
    }
    ++res_.tracked;
    res_.trajectory.push_back({ef.t, *T_w_ef});
    res_.correlations.push_back(front_.lastCorrelation());
    const SE3& T_ef_kf = front_.T_ef_kf();
    const KeyframePolicyConfig& pc = cfg_.policy;
    const bool drop = front_.lastPointsInView() < (1.0 - pc.max_point_drop) * kf_in_view_;
    const bool rotated = T_ef_kf.so3().angle() > pc.max_rotation_deg * M_PI / 180.0;
    const bool moved =
        T_ef_kf.translation().norm() > pc.max_translation_ratio * front_.referenceMedianDepth();
    need_keyframe_ = drop || rotated || moved;
  }

  const Sequence& seq_;
  const TrackOnlyConfig& cfg_;
  const CameraModel& cam_;
  TrackOnlyResult& res_;
  EventFrontend front_;
  KeyframeBuilder builder_;
  FrameTracker frame_tracker_;
  std::size_t kf_frame_ = 0;
  int kf_in_view_ = 0;
  bool need_keyframe_ = false, lost_ = false;
};

}  // namespace

TrackOnlyResult runTrackOnly(const Sequence& seq, const TrackOnlyConfig& cfg) {
  const auto wall0 = Clock::now();
  cfg.event_frame.validate();
  cfg.events.points.validate();
  cfg.events.lost_track.validate();
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
  EventPacketStream packets(*src, cfg.event_frame);
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
                     {"tile", cfg.events.points.tile},
                     {"point_fraction", cfg.events.points.fraction},
                     {"max_points", cfg.events.points.max_points},
                     {"depth_noise", cfg.depth_noise},
                     {"seed", static_cast<double>(cfg.seed)}});
}

}  // namespace eds
