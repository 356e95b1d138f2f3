#include "system/odometry.hpp"

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "core/undistorter.hpp"
#include "io/ply.hpp"

namespace eds {

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

double peakRssMb() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return ru.ru_maxrss / 1024.0;  // kB on Linux
}

// RMS pixel flow of the keyframe's points under T_f_kf, and of its translation alone; the fraction
// of points still in view.
struct Flow {
  double rt = 0, t = 0, in_view = 0;
};
Flow flowOf(const std::vector<KeyframePoint>& pts, const SE3& T_f_kf, const CameraModel& cam) {
  Flow f;
  const Mat3 R = T_f_kf.rotationMatrix();
  const Vec3 t = T_f_kf.translation();
  double ss_rt = 0, ss_t = 0;
  int n = 0, in = 0;
  for (const KeyframePoint& p : pts) {
    if (!(p.inv_depth > 0)) continue;
    const Vec3 x((p.u - cam.cx) / cam.fx, (p.v - cam.cy) / cam.fy, 1.0);
    const Vec3 q_rt = R * x + t * p.inv_depth, q_t = x + t * p.inv_depth;  // scaled by ρ
    ++n;
    if (q_rt.z() <= 1e-9 || q_t.z() <= 1e-9) continue;
    const double u = cam.fx * q_rt.x() / q_rt.z() + cam.cx, v = cam.fy * q_rt.y() / q_rt.z() + cam.cy;
    const double ut = cam.fx * q_t.x() / q_t.z() + cam.cx, vt = cam.fy * q_t.y() / q_t.z() + cam.cy;
    ss_rt += (u - p.u) * (u - p.u) + (v - p.v) * (v - p.v);
    ss_t += (ut - p.u) * (ut - p.u) + (vt - p.v) * (vt - p.v);
    in += u >= 0 && v >= 0 && u <= cam.width - 1 && v <= cam.height - 1;
  }
  if (n == 0) return f;
  f.rt = std::sqrt(ss_rt / n), f.t = std::sqrt(ss_t / n), f.in_view = static_cast<double>(in) / n;
  return f;
}

class FramesOdometry {
 public:
  FramesOdometry(const CameraModel& cam, const OdometryConfig& cfg, OdometryResult& res)
      : cam_(cam),
        cfg_(cfg),
        res_(res),
        worker_(cam, cfg.mapping, cfg.backend, cfg.threaded_backend),
        tracker_(cam, cfg.frame_tracker) {}

  // Hands a keyframe to the back-end (mapping + BA). Returns the pose of the keyframe's frame: the
  // optimized one when the back-end ran at once (synchronous), else the given one.
  SE3 addKeyframe(TimeNs t, const cv::Mat& img, const SE3& T_w_new, double a, double b,
                  std::vector<KeyframePoint> pts_with_depth = {}) {
    worker_.submit({t, img, T_w_new, a, b, std::move(pts_with_depth)});
    if (cfg_.threaded_backend) return T_w_new;
    adoptReference(false);
    return T_w_kf_;
  }

  // Tracks a frame; returns its pose. Adds a keyframe when the policy asks.
  SE3 track(TimeNs t, const cv::Mat& img) {
    adoptReference(!has_ref_);
    const auto t0 = Clock::now();
    SE3 T_f_kf;
    double alpha = 1, beta = 0;
    FrameTrackResult tr = align(img, T_f_kf, alpha, beta);
    Flow fl = flowOf(ref_.points, T_f_kf, cam_);
    bool new_kf = wantKeyframe(fl, alpha);
    if (new_kf && worker_.busy()) {
      // The back-end is still mapping the previous keyframe: wait for it (so that an offline run cannot
      // run away from its map), take the new reference and track again against it.
      adoptReference(true);
      tr = align(img, T_f_kf, alpha, beta);
      fl = flowOf(ref_.points, T_f_kf, cam_);
      new_kf = wantKeyframe(fl, alpha);
    }
    res_.track_ms.push_back(msSince(t0));
    if (tr.ok) {
      ++res_.tracked;
    } else {
      res_.failures.push_back({t, "frame alignment failed (rmse " + std::to_string(tr.rmse) + ", " +
                                      std::to_string(tr.residuals) + " residuals)"});
      if (!(alpha > 0)) alpha = alpha_, beta = beta_;
    }
    const SE3 T_w_f = T_w_kf_ * T_f_kf.inverse();
    // α, β relate the frame to the keyframe (I_f = α I_kf + β); the window's per-frame (a, b) are
    // absolute: α = e^{a_f − a_kf}, β = b_f − α b_kf.
    a_last_ = a_kf_ + std::log(alpha), b_last_ = beta + alpha * b_kf_;
    alpha_ = alpha, beta_ = beta;
    SE3 T_w_out = T_w_f;
    if (new_kf) T_w_out = addKeyframe(t, img, T_w_f, a_last_, b_last_);
    setLast(T_w_out);
    return T_w_out;
  }

  void setLast(const SE3& T_w_f) {
    if (has_last_) prev_T_w_f_ = last_T_w_f_, has_prev_ = true;
    last_T_w_f_ = T_w_f;
    has_last_ = true;
  }
  void setLastBrightness(double a, double b) { a_last_ = a, b_last_ = b; }

  BackendWorker& worker() { return worker_; }

 private:
  // Takes the newest reference the back-end published (waiting for it if asked).
  void adoptReference(bool wait) {
    if (wait) worker_.waitIdle();
    std::optional<TrackingReference> ref = worker_.takeReference();
    if (!ref) return;
    T_w_kf_ = ref->kf.T_w_kf;
    a_kf_ = ref->a, b_kf_ = ref->b;
    ref_ = std::move(ref->kf);
    has_ref_ = !ref_.points.empty();
    if (has_ref_) tracker_.setKeyframe(ref_);
    // The last frame's brightness, relative to the new reference.
    alpha_ = std::exp(a_last_ - a_kf_), beta_ = b_last_ - alpha_ * b_kf_;
  }

  bool wantKeyframe(const Flow& fl, double alpha) const {
    const double wh = cam_.width + cam_.height;
    return fl.t > cfg_.policy.flow_t * wh || fl.rt > cfg_.policy.flow_rt * wh ||
           fl.in_view < cfg_.policy.min_in_view || std::abs(std::log(alpha)) > cfg_.policy.max_log_alpha;
  }

  // Aligns the frame to the reference from a constant-velocity prediction, trying DSO's other starting
  // points when that fails.
  FrameTrackResult align(const cv::Mat& img, SE3& T_f_kf, double& alpha, double& beta) {
    SE3 T_w_pred = last_T_w_f_;
    if (has_prev_) T_w_pred = last_T_w_f_ * (prev_T_w_f_.inverse() * last_T_w_f_);
    T_f_kf = T_w_pred.inverse() * T_w_kf_;
    alpha = alpha_, beta = beta_;
    if (!has_ref_) return {};
    FrameTrackResult tr = tracker_.track(img, T_f_kf, alpha, beta);
    if (!tr.ok) {
      // No motion since the last frame, then half the velocity.
      for (const SE3& T_w_try : {last_T_w_f_, interpolateGeodesic(last_T_w_f_, T_w_pred, 0.5)}) {
        SE3 T_try = T_w_try.inverse() * T_w_kf_;
        double a_try = alpha_, b_try = beta_;
        const FrameTrackResult tr2 = tracker_.track(img, T_try, a_try, b_try);
        if (tr2.ok || tr2.rmse < tr.rmse) {
          T_f_kf = T_try, alpha = a_try, beta = b_try, tr = tr2;
          if (tr.ok) break;
        }
      }
    }
    return tr;
  }

  CameraModel cam_;
  const OdometryConfig& cfg_;
  OdometryResult& res_;
  BackendWorker worker_;
  FrameTracker tracker_;
  Keyframe ref_;
  bool has_ref_ = false;
  SE3 T_w_kf_;
  double a_kf_ = 0, b_kf_ = 0, alpha_ = 1.0, beta_ = 0.0;
  double a_last_ = 0, b_last_ = 0;  // absolute brightness of the last frame
  SE3 last_T_w_f_, prev_T_w_f_;
  bool has_last_ = false, has_prev_ = false;
};

}  // namespace

std::vector<std::size_t> selectFrames(const std::vector<FrameRef>& frames, double start_s, double duration_s,
                                      double frame_rate) {
  std::vector<std::size_t> out;
  if (frames.empty()) return out;
  const TimeNs t0 = frames.front().t + fromSeconds(start_s);
  const TimeNs t1 = duration_s > 0 ? t0 + fromSeconds(duration_s) : std::numeric_limits<TimeNs>::max();
  std::vector<std::size_t> in;
  for (std::size_t i = 0; i < frames.size(); ++i)
    if (frames[i].t >= t0 && frames[i].t <= t1) in.push_back(i);
  if (!(frame_rate > 0) || in.empty()) return in;
  const TimeNs step = fromSeconds(1.0 / frame_rate);
  std::size_t j = 0;
  for (TimeNs target = frames[in.front()].t; target <= frames[in.back()].t + step / 2; target += step) {
    while (j + 1 < in.size() &&
           std::llabs(frames[in[j + 1]].t - target) <= std::llabs(frames[in[j]].t - target))
      ++j;
    if (out.empty() || out.back() != in[j]) out.push_back(in[j]);
  }
  return out;
}

OdometryResult runOdometry(const Sequence& seq, const OdometryConfig& cfg) {
  const auto wall0 = Clock::now();
  if (!seq.hasFrames())
    throw InputError((seq.dir() / "images.txt").string(), "frames-only odometry needs frames");
  if (cfg.frame_rate < 0 || cfg.start_s < 0 || cfg.duration_s < 0)
    throw std::invalid_argument("run: frame rate, start and duration must not be negative");
  const Undistorter und(seq.camera());
  const CameraModel& cam = und.pinhole();
  OdometryResult res;
  FramesOdometry odo(cam, cfg, res);
  Bootstrap boot(cam, cfg.bootstrap);
  const std::vector<std::size_t> idx =
      selectFrames(seq.frames(), cfg.start_s, cfg.duration_s, cfg.frame_rate);
  if (idx.empty())
    throw InputError((seq.dir() / "images.txt").string(), "no frame in the requested time range");
  res.first_t = seq.frames()[idx.front()].t;
  TimeNs last_t = res.first_t;
  for (std::size_t i : idx) {
    const TimeNs t = seq.frames()[i].t;
    cv::Mat img;
    und.undistortImage(seq.loadFrame(i)).convertTo(img, CV_32F, 1.0 / 255.0);
    ++res.frames_in;
    last_t = t;
    if (!res.initialized) {
      if (!boot.add(t, img)) continue;
      res.initialized = true;
      res.init_t = t;
      res.init_frames = static_cast<int>(boot.frames().size());
      res.init_restarts = boot.restarts();
      // Keyframe 0 is the reference with the bootstrap's depths; keyframe 1 the frame that completed it.
      const Keyframe& ref = boot.reference();
      odo.addKeyframe(ref.t, ref.image, SE3(), 0.0, 0.0, ref.points);
      const BootstrapFrame& last = boot.frames().back();
      for (std::size_t k = 0; k + 1 < boot.frames().size(); ++k)
        res.frames.push_back({boot.frames()[k].t, boot.frames()[k].T_ref_c});
      odo.setLast(boot.frames()[boot.frames().size() - 2].T_ref_c);
      odo.setLastBrightness(last.a, last.b);
      const SE3 T_w_f = odo.addKeyframe(t, img, last.T_ref_c, last.a, last.b);
      odo.setLast(T_w_f);
      res.frames.push_back({t, T_w_f});
      res.tracked += boot.frames().size();
      continue;
    }
    res.frames.push_back({t, odo.track(t, img)});
  }
  odo.worker().waitIdle();
  SlidingWindow& window = odo.worker().window();
  window.flush();
  const BackendTimings& bt = odo.worker().timings();
  res.mapping_ms = bt.mapping_ms;
  res.ba_ms = bt.ba_ms;
  res.window_points = bt.window_points;
  for (const RetiredKeyframe& k : window.retiredKeyframes()) res.keyframes.push_back({k.t, k.T_w_kf});
  std::sort(res.keyframes.begin(), res.keyframes.end(),
            [](const auto& a, const auto& b) { return a.t < b.t; });
  res.map = window.retiredPoints();
  res.sequence_s = toSeconds(last_t - res.first_t);
  res.wall_s = std::chrono::duration<double>(Clock::now() - wall0).count();
  res.peak_rss_mb = peakRssMb();
  return res;
}

namespace {
nlohmann::json stats(std::vector<double> v) {
  if (v.empty()) return nullptr;
  std::sort(v.begin(), v.end());
  const auto pct = [&](double q) {
    return v[std::min(v.size() - 1, static_cast<std::size_t>(q * (v.size() - 1) + 0.5))];
  };
  double sum = 0;
  for (double x : v) sum += x;
  return {{"median", pct(0.5)}, {"p95", pct(0.95)}, {"mean", sum / v.size()}, {"max", v.back()}};
}
}  // namespace

void writeOdometryOutputs(const std::filesystem::path& dir, const OdometryResult& r,
                          const OdometryConfig& cfg) {
  std::filesystem::create_directories(dir);
  writeTum(dir / "trajectory_frames.txt", r.frames);
  writeTum(dir / "keyframes.txt", r.keyframes);
  PointCloud pc;
  for (const MapPoint& p : r.map) {
    pc.xyz.push_back(p.p_w.cast<float>());
    pc.intensity.push_back(p.intensity);
  }
  writePly(dir / "map.ply", pc);
  nlohmann::json j;
  j["mode"] = "run --frames-only";
  j["initialized"] = r.initialized;
  j["initialization"] = {{"t", r.initialized ? toSeconds(r.init_t) : 0.0},
                         {"seconds_after_first_frame", r.initialized ? toSeconds(r.init_t - r.first_t) : 0.0},
                         {"frames_used", r.init_frames},
                         {"restarts", r.init_restarts}};
  j["counts"] = {
      {"frames", r.frames_in},         {"poses", r.frames.size()},        {"tracked", r.tracked},
      {"failures", r.failures.size()}, {"keyframes", r.keyframes.size()}, {"map_points", r.map.size()}};
  j["timings_ms"] = {{"frame_tracking", stats(r.track_ms)},
                     {"mapping", stats(r.mapping_ms)},
                     {"backend_per_keyframe", stats(r.ba_ms)}};
  std::vector<double> wp(r.window_points.begin(), r.window_points.end());
  j["window_points"] = stats(wp);
  j["wall_s"] = r.wall_s;
  j["sequence_s"] = r.sequence_s;
  j["real_time_factor"] = r.sequence_s > 0 ? r.wall_s / r.sequence_s : 0.0;
  j["peak_rss_mb"] = r.peak_rss_mb;
  nlohmann::json fails = nlohmann::json::array();
  for (const auto& f : r.failures) fails.push_back({{"t", toSeconds(f.t)}, {"reason", f.reason}});
  j["failures"] = fails;
  j["config"] = {{"frame_rate", cfg.frame_rate},
                 {"start_s", cfg.start_s},
                 {"duration_s", cfg.duration_s},
                 {"window", cfg.backend.window},
                 {"points_per_keyframe", cfg.backend.points_per_keyframe},
                 {"marginalize", cfg.backend.marginalize},
                 {"threaded_backend", cfg.threaded_backend}};
  std::ofstream out(dir / "summary.json");
  if (!out) throw InputError((dir / "summary.json").string(), "cannot open for writing");
  out << j.dump(2) << "\n";
}

}  // namespace eds
