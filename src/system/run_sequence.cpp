// The recorded-sequence driver of the odometry: frames and events read from a sequence and pushed
// into `Odometry` in time order, and the run's output files.
#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "io/ply.hpp"
#include "system/odometry.hpp"
#include "system/run_stats.hpp"

namespace eds {

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

namespace {

// Pushes the selected frames and the events up to t_end into the odometry: each frame right after the
// events up to its time stamp (the order the odometry processes them in, whatever the chunk size).
class SequenceFeeder {
 public:
  SequenceFeeder(const Sequence& seq, const std::vector<std::size_t>& idx, TimeNs t_end, Odometry& odo)
      : seq_(seq), idx_(idx), t_end_(t_end), odo_(odo) {}

  void run(bool use_events, const std::function<void(TimeNs)>& report) {
    if (use_events) {
      auto src = seq_.openEvents();
      EventArray chunk;
      bool done = false;
      while (!done) {
        chunk.clear();
        if (src->read(chunk, 1 << 18) == 0) break;
        std::size_t a = 0;
        while (a < chunk.size()) {
          // Events up to the next frame (or the end of the time range), then the frame.
          const TimeNs stop = next_ < idx_.size() ? std::min(frameTime(next_), t_end_) : t_end_;
          const auto last = std::upper_bound(chunk.t.begin() + a, chunk.t.end(), stop);
          const auto b = static_cast<std::size_t>(last - chunk.t.begin());
          odo_.addEvents(chunk, a, b);
          a = b;
          if (a == chunk.size()) break;
          if (next_ < idx_.size() && frameTime(next_) <= t_end_) {
            pushFrame(report);
          } else {
            done = true;
            break;
          }
        }
        if (!chunk.empty()) report(chunk.t[a == 0 ? 0 : a - 1]);
      }
    }
    while (next_ < idx_.size()) pushFrame(report);
  }

 private:
  TimeNs frameTime(std::size_t k) const { return seq_.frames()[idx_[k]].t; }
  void pushFrame(const std::function<void(TimeNs)>& report) {
    const TimeNs t = frameTime(next_);
    odo_.addFrame(t, seq_.loadFrame(idx_[next_++]));
    report(t);
  }
  const Sequence& seq_;
  const std::vector<std::size_t>& idx_;
  TimeNs t_end_;
  Odometry& odo_;
  std::size_t next_ = 0;
};

}  // namespace

OdometryResult runOdometry(const Sequence& seq, const OdometryConfig& cfg, const ProgressFn& progress) {
  if (!seq.hasFrames())
    throw InputError((seq.dir() / "images.txt").string(),
                     "the odometry needs frames (keyframes come from them)");
  if (cfg.use_events && !seq.hasEvents())
    throw InputError((seq.dir() / "events.txt").string(),
                     "no events in the sequence: run with --frames-only, or add events");
  if (cfg.frame_rate < 0 || cfg.start_s < 0 || cfg.duration_s < 0)
    throw std::invalid_argument("run: frame rate, start and duration must not be negative");
  const std::vector<std::size_t> idx =
      selectFrames(seq.frames(), cfg.start_s, cfg.duration_s, cfg.frame_rate);
  if (idx.empty())
    throw InputError((seq.dir() / "images.txt").string(), "no frame in the requested time range");
  Odometry odo(seq.camera(), cfg);
  const TimeNs first_t = seq.frames()[idx.front()].t;
  const TimeNs t_end =
      cfg.duration_s > 0 ? first_t + fromSeconds(cfg.duration_s) : std::numeric_limits<TimeNs>::max();
  const double total_s = toSeconds(std::min(seq.frames()[idx.back()].t, t_end) - first_t);
  TimeNs t_reported = first_t;
  auto report = [&](TimeNs t) {
    if (!progress || t - t_reported < fromSeconds(0.1)) return;
    t_reported = t;
    progress(std::clamp(toSeconds(t - first_t), 0.0, total_s), total_s);
  };
  SequenceFeeder(seq, idx, t_end, odo).run(cfg.use_events, report);
  if (progress) progress(total_s, total_s);
  return odo.finish();
}

void writeOdometryOutputs(const std::filesystem::path& dir, const OdometryResult& r,
                          const OdometryConfig& cfg) {
  std::filesystem::create_directories(dir);
  // The main files hold each pose through its keyframe's final pose (as DSO's results); *_live.txt the
  // poses as they were tracked, what a live user had at the time.
  writeTum(dir / "trajectory_frames.txt", r.frames_refined);
  writeTum(dir / "trajectory_frames_live.txt", r.frames);
  if (cfg.use_events) {
    writeTum(dir / "trajectory_events.txt", r.events_refined);
    writeTum(dir / "trajectory_events_live.txt", r.events);
  }
  writeTum(dir / "keyframes.txt", r.keyframes);
  PointCloud pc;
  for (const MapPoint& p : r.map) {
    pc.xyz.push_back(p.p_w.cast<float>());
    pc.intensity.push_back(p.intensity);
  }
  writePly(dir / "map.ply", pc);
  nlohmann::json j;
  j["mode"] = cfg.use_events ? "run (events + frames)" : "run --frames-only";
  j["initialized"] = r.initialized;
  j["initialization"] = {{"t", r.initialized ? toSeconds(r.init_t) : 0.0},
                         {"seconds_after_first_frame", r.initialized ? toSeconds(r.init_t - r.first_t) : 0.0},
                         {"frames_used", r.init_frames},
                         {"restarts", r.init_restarts}};
  j["counts"] = {{"frames", r.frames_in},          {"poses", r.frames.size()},
                 {"tracked", r.tracked},           {"failures", r.failures.size()},
                 {"event_frames", r.event_frames}, {"event_frames_tracked", r.events_tracked},
                 {"event_poses", r.events.size()}, {"keyframes", r.keyframes.size()},
                 {"map_points", r.map.size()},     {"backend_waits", r.backend_waits}};
  j["timings_ms"] = {{"frame_tracking", timingStats(r.track_ms)},
                     {"event_tracking", timingStats(r.event_track_ms)},
                     {"mapping", timingStats(r.mapping_ms)},
                     {"backend_per_keyframe", timingStats(r.ba_ms)}};
  std::vector<double> wp(r.window_points.begin(), r.window_points.end());
  j["window_points"] = timingStats(wp);
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
