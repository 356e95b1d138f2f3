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
#include "system/frame_frontend.hpp"

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
  FrameFrontend odo(cam, cfg, res);
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
