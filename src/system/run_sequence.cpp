// The recorded-sequence driver of the odometry: frames and events read from a sequence and pushed
// into `Odometry` in time order, and the run's output files.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <thread>

#include "core/bounded_queue.hpp"
#include "core/error.hpp"
#include "io/merged_stream.hpp"
#include "io/output_file.hpp"
#include "io/ply.hpp"
#include "system/clock_offset.hpp"
#include "system/event_snapshots.hpp"
#include "system/odometry.hpp"
#include "system/reference_run.hpp"
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

// A decoded frame or a chunk of events, from the reading thread to the odometry.
struct InputItem {
  bool frame = false;
  std::size_t index = 0;  // frames: into seq.frames()
  cv::Mat image;
  EventArray events;
};

// The reading thread: the selected frames (decoded) and the events up to t_end, in time order, each
// frame right after the events up to its time stamp.
void readSequence(const Sequence& seq, const std::vector<std::size_t>& idx, TimeNs t_end, bool use_events,
                  BoundedQueue<InputItem>& queue) {
  MergedStream stream(seq, 1 << 16, use_events);
  std::size_t next = 0;  // the next selected frame (index into idx)
  InputItem item;
  for (auto kind = stream.next(item.events, item.index); kind != MergedStream::Kind::kEnd;
       kind = stream.next(item.events, item.index)) {
    item.frame = kind == MergedStream::Kind::kFrame;
    bool past_range = false;
    if (item.frame) {
      if (next == idx.size() || idx[next] != item.index) continue;
      ++next;
      item.image = seq.loadFrame(item.index);
    } else {
      const EventArray& ev = item.events;
      const auto end =
          static_cast<std::size_t>(std::upper_bound(ev.t.begin(), ev.t.end(), t_end) - ev.t.begin());
      past_range = end < ev.size() && next == idx.size();
      item.events.resize(end);
    }
    if ((item.frame || !item.events.empty()) && !queue.push(std::move(item))) return;
    item = InputItem{};
    if (past_range) break;
  }
}

// Pushes what the reading thread reads into the odometry. Reading and decoding run beside the
// tracking, up to 16 items ahead (each at most 65536 events, under 1 MB): with 4 the reader fell behind
// whenever the back-end's solves took both cores, and the tracking thread then waited for it.
// Returns the last input time fed when `stop` ended the feeding early, nullopt at the end of the input.
std::optional<TimeNs> feedSequence(const Sequence& seq, const std::vector<std::size_t>& idx, TimeNs t_end,
                                   bool use_events, Odometry& odo, const std::function<void(TimeNs)>& report,
                                   const std::atomic<bool>* stop) {
  BoundedQueue<InputItem> queue(16);
  std::thread reader([&] {
    try {
      readSequence(seq, idx, t_end, use_events, queue);
      queue.close();
    } catch (...) {
      queue.fail(std::current_exception());
    }
  });
  // Whatever ends the feeding (the end, a stop, an exception here or from the reader), the reader is
  // told to stop and joined.
  struct Joiner {
    BoundedQueue<InputItem>& q;
    std::thread& t;
    ~Joiner() {
      q.cancel();
      t.join();
    }
  } joiner{queue, reader};
  TimeNs fed = seq.frames()[idx.front()].t;
  InputItem item;
  while (queue.pop(item)) {
    if (stop != nullptr && stop->load(std::memory_order_relaxed)) return fed;
    if (item.frame) {
      fed = seq.frames()[item.index].t;
      odo.addFrame(fed, item.image, seq.frames()[item.index].exposure);
    } else {
      odo.addEvents(item.events, 0, item.events.size());
      fed = std::max(fed, item.events.t.back());
    }
    report(fed);
  }
  return std::nullopt;
}

}  // namespace

RunPlan planRun(const Sequence& seq, const OdometryConfig& cfg) {
  if (!seq.hasFrames())
    throw InputError(seq.framesSource().string(),
                     "the odometry needs frames (keyframes come from them); this " + seq.format() +
                         " input holds none (`eds info` shows what it holds)");
  if (cfg.use_events && !seq.hasEvents())
    throw InputError((seq.dir() / "events.txt").string(),
                     "no events in the sequence: run with --frames-only, or add events");
  if (cfg.frame_rate < 0 || cfg.start_s < 0 || cfg.duration_s < 0)
    throw std::invalid_argument("run: frame rate, start and duration must not be negative");
  const std::vector<std::size_t> idx =
      selectFrames(seq.frames(), cfg.start_s, cfg.duration_s, cfg.frame_rate);
  if (idx.empty())
    throw InputError((seq.dir() / "images.txt").string(), "no frame in the requested time range");
  RunPlan plan;
  plan.frames = idx;
  plan.first_t = seq.frames()[idx.front()].t;
  plan.t_end =
      cfg.duration_s > 0 ? plan.first_t + fromSeconds(cfg.duration_s) : std::numeric_limits<TimeNs>::max();
  plan.total_s = toSeconds(std::min(seq.frames()[idx.back()].t, plan.t_end) - plan.first_t);
  return plan;
}

OdometryResult runOdometry(const Sequence& seq, const OdometryConfig& cfg, const ProgressFn& progress,
                           const std::atomic<bool>* stop, OdometryListener* listener) {
  const RunPlan plan = planRun(seq, cfg);
  const std::vector<std::size_t>& idx = plan.frames;
  const TimeNs first_t = plan.first_t, t_end = plan.t_end;
  const double total_s = plan.total_s;
  Odometry odo(seq.camera(), cfg, listener);
  TimeNs t_reported = first_t;
  auto report = [&](TimeNs t) {
    if (!progress || t - t_reported < fromSeconds(0.1)) return;
    t_reported = t;
    progress(std::clamp(toSeconds(t - first_t), 0.0, total_s), total_s);
  };
  const std::optional<TimeNs> stopped_at = feedSequence(seq, idx, t_end, cfg.use_events, odo, report, stop);
  if (progress && !stopped_at) progress(total_s, total_s);
  odo.finish();
  OdometryResult r = odo.takeResult();
  if (stopped_at) {
    r.interrupted = true;
    r.interrupted_t = *stopped_at;
  }
  return r;
}

namespace {

// Seconds by stage (those that took any time), and the share of the thread's time they account for.
nlohmann::json stagesJson(const StageSeconds& s) {
  nlohmann::json seconds = nlohmann::json::object();
  double total = 0;
  for (std::size_t i = 0; i < kStageCount; ++i) {
    total += s[i];
    if (s[i] > 0) seconds[stageName(static_cast<Stage>(i))] = std::round(s[i] * 1e4) / 1e4;
  }
  const double unaccounted = s[static_cast<std::size_t>(Stage::kUnaccounted)];
  return {{"seconds", seconds}, {"accounted_fraction", total > 0 ? 1.0 - unaccounted / total : 0.0}};
}

// Every stage's time per item (ms, to 0.01 ms), for distributions in reports.
void writeTimings(const std::filesystem::path& file, const OdometryResult& r) {
  const auto rounded = [](const std::vector<double>& v) {
    nlohmann::json a = nlohmann::json::array();
    for (double x : v) a.push_back(std::round(x * 100) / 100);
    return a;
  };
  nlohmann::json j = {{"frame_tracking", rounded(r.track_ms)},
                      {"event_tracking", rounded(r.event_track_ms)},
                      {"mapping", rounded(r.mapping_ms)},
                      {"backend_per_keyframe", rounded(r.ba_ms)}};
  if (r.realtime.on) j["realtime_latency"] = rounded(r.realtime.latency_ms);
  writeTextFile(file, j.dump() + "\n");
}

}  // namespace

void writeOdometryOutputs(const std::filesystem::path& dir, const OdometryResult& r,
                          const OdometryConfig& cfg, const RunInputs& inputs) {
  std::filesystem::create_directories(dir);
  // The main files hold each pose through its keyframe's final pose (as DSO's results); *_live.txt the
  // poses as they were tracked, what a live user had at the time.
  // A line "# segment K" before the first pose of each new map segment.
  const auto tum = [&](const char* name, const Trajectory& traj) {
    writeTum(dir / name, traj, indicesFrom(traj, segmentStartTimes(r)));
  };
  tum("trajectory_frames.txt", r.frames_refined);
  tum("trajectory_frames_live.txt", r.frames);
  if (cfg.use_events) {
    tum("trajectory_events.txt", r.events_refined);
    tum("trajectory_events_live.txt", r.events);
  }
  tum("keyframes.txt", r.keyframes);
  writeReferenceKeyframes(dir, r.pinhole, r.keyframe_maps);
  writeEventSnapshots(dir, r.event_snapshots);
  if (!inputs.groundtruth.empty()) writeTum(dir / "groundtruth.txt", inputs.groundtruth);
  PointCloud pc;
  for (const MapPoint& p : r.map) {
    pc.xyz.push_back(p.p_w.cast<float>());
    pc.intensity.push_back(p.intensity);
  }
  writePly(dir / "map.ply", pc);
  nlohmann::json j;
  j["mode"] = cfg.use_events ? "run (events + frames)" : "run --frames-only";
  if (!inputs.sequence.empty()) j["inputs"] = {{"sequence", inputs.sequence}, {"format", inputs.format}};
  j["initialized"] = r.initialized;
  j["interrupted"] = r.interrupted;
  if (r.interrupted) j["interrupted_at_s"] = toSeconds(r.interrupted_t);
  j["initialization"] = {{"t", r.initialized ? toSeconds(r.init_t) : 0.0},
                         {"seconds_after_first_frame", r.initialized ? toSeconds(r.init_t - r.first_t) : 0.0},
                         {"frames_used", r.init_frames},
                         {"restarts", r.init_restarts}};
  j["counts"] = {{"frames", r.frames_in},
                 {"frames_rejected", r.frames_rejected},
                 {"frames_tracked_only", r.frames_tracked_only},
                 {"poses", r.frames.size()},
                 {"tracked", r.tracked},
                 {"failures", r.failures.size()},
                 {"event_frames", r.event_frames},
                 {"event_frames_shed", r.event_frames_shed},
                 {"events_flicker_dropped", r.events_flicker_dropped},
                 {"event_frames_tracked", r.events_tracked},
                 {"event_poses", r.events.size()},
                 {"keyframes", r.keyframes.size()},
                 {"map_points", r.map.size()},
                 {"backend_waits", r.backend_waits},
                 {"keyframes_deferred", r.keyframes_deferred},
                 {"early_references", r.early_references},
                 {"feature_starts", r.feature_starts},
                 {"event_poses_retracked", r.events_retracked},
                 {"bootstrap_event_frames_thinned", r.buffered_thinned}};
  j["deblur"] = {{"exposure_s", r.exposure_s},
                 {"estimated", r.exposure_estimated},
                 {"recorded", r.exposure_recorded},
                 {"pairs_scored", r.exposure_pairs},
                 {"keyframes_deblurred", r.deblurred}};
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
  // The thread that fed the odometry; the back-end's own thread, when it has one, runs beside it.
  j["stages"] = stagesJson(r.stages_s);
  if (cfg.threaded_backend) j["backend_thread_stages"] = stagesJson(r.backend_stages_s);
  if (r.event_thread) j["event_thread_stages"] = stagesJson(r.event_stages_s);
  if (cfg.use_events) {
    const ClockOffsetEstimate off = estimateEventClockOffset(r.frames, r.events);
    if (off.valid)
      j["event_clock_offset"] = {{"estimate_ms", off.offset_ms},
                                 {"rotation_rms_deg_at_zero", off.rms_deg_at_zero},
                                 {"rotation_rms_deg_at_estimate", off.rms_deg_at_best},
                                 {"suggests_offset", off.suggestsOffset()}};
  }
  if (r.realtime.on)
    j["realtime"] = {{"speed", r.realtime.speed},
                     {"latency_ms", timingStats(r.realtime.latency_ms)},
                     {"events_skipped", r.realtime.events_skipped},
                     {"frames_skipped", r.realtime.frames_skipped},
                     {"max_event_frame_stride", r.realtime.max_event_frame_stride}};
  nlohmann::json fails = nlohmann::json::array();
  for (const auto& f : r.failures) fails.push_back({{"t", toSeconds(f.t)}, {"reason", f.reason}});
  j["failures"] = fails;
  nlohmann::json losses = nlohmann::json::array();
  for (const TrackLoss& l : r.losses)
    losses.push_back(
        {{"t_lost", toSeconds(l.t_lost)},
         {"t_recovered", l.t_recovered >= 0 ? nlohmann::json(toSeconds(l.t_recovered)) : nullptr},
         {"cause", l.cause},
         {"recovery", l.recovery},
         {"frames_tried", l.attempts},
         {"event_poses_backfilled", l.event_poses_backfilled}});
  j["losses"] = losses;
  nlohmann::json segments = nlohmann::json::array();
  for (const MapSegment& s : r.segments)
    segments.push_back({{"id", s.id},
                        {"t_start", toSeconds(s.t_start)},
                        {"t_init", s.t_init >= 0 ? nlohmann::json(toSeconds(s.t_init)) : nullptr},
                        {"cause", s.cause}});
  j["segments"] = segments;
  j["config"] = {{"frame_rate", cfg.frame_rate},
                 {"start_s", cfg.start_s},
                 {"duration_s", cfg.duration_s},
                 {"window", cfg.backend.window},
                 {"points_per_keyframe", cfg.backend.points_per_keyframe},
                 {"marginalize", cfg.backend.marginalize},
                 {"threaded_backend", cfg.threaded_backend}};
  writeTextFile(dir / "summary.json", j.dump(2) + "\n");
  writeTimings(dir / "timings.json", r);
}

}  // namespace eds
