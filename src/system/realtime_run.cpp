#include "system/realtime_run.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <functional>
#include <stdexcept>
#include <thread>

#include "io/merged_stream.hpp"
#include "system/release_queue.hpp"

namespace eds {

namespace {

using Clock = ReleasedItem::Clock;

// The camera: releases the selected frames and the events up to the plan's end at their times.
void releaseAll(const Sequence& seq, const RunPlan& plan, bool use_events,
                const std::function<Clock::time_point(TimeNs)>& release, const std::function<bool()>& stopped,
                ReleaseQueue& queue) {
  MergedStream stream(seq, 2000, use_events);  // about a USB transfer's worth of events
  std::size_t next = 0;
  ReleasedItem item;
  for (auto kind = stream.next(item.events, item.index); kind != MergedStream::Kind::kEnd;
       kind = stream.next(item.events, item.index)) {
    if (stopped()) break;
    item.frame = kind == MergedStream::Kind::kFrame;
    if (item.frame) {
      if (next == plan.frames.size() || plan.frames[next] != item.index) continue;
      ++next;
      item.image = seq.loadFrame(item.index);
      item.t = seq.frames()[item.index].t;
      std::this_thread::sleep_until(release(item.t));
    } else {
      const auto end =
          std::upper_bound(item.events.t.begin(), item.events.t.end(), plan.t_end) - item.events.t.begin();
      const auto n = static_cast<std::size_t>(end);
      item.events.t.resize(n);
      item.events.x.resize(n);
      item.events.y.resize(n);
      item.events.p.resize(n);
      if (item.events.empty()) {
        if (next == plan.frames.size()) break;  // past the range
        continue;
      }
      std::this_thread::sleep_until(release(item.events.t.back()));
    }
    item.released = Clock::now();
    queue.push(std::move(item));
    item = ReleasedItem{};
  }
}

// The producer thread's body: any error (a damaged recording) goes to the consumer, never terminate().
void produce(const Sequence& seq, const RunPlan& plan, bool use_events,
             const std::function<Clock::time_point(TimeNs)>& release, const std::function<bool()>& stopped,
             ReleaseQueue& queue) {
  try {
    releaseAll(seq, plan, use_events, release, stopped, queue);
    queue.close();
  } catch (...) {
    queue.fail(std::current_exception());
  }
}

using ReleaseFn = std::function<Clock::time_point(TimeNs)>;

// The event pose latencies of poses produced since the last call.
void recordLatencies(const OdometryResult& now, const ReleaseFn& release, std::vector<double>& latency_ms) {
  for (std::size_t k = latency_ms.size(); k < now.events.size(); ++k)
    latency_ms.push_back(
        std::chrono::duration<double, std::milli>(Clock::now() - release(now.event_last_t[k])).count());
}

// Behind, the processing sheds event frames before it drops whole chunks of events: every 50 ms the
// longest wait of the items taken meanwhile decides, the stride of the event frames it tracks doubling
// (up to kMaxStride) above a quarter of the latency bound and halving under a twentieth. The window
// lets a change show in the waits before the next, and one item behind a keyframe does not decide.
class StrideControl {
 public:
  static constexpr int kMaxStride = 8;
  explicit StrideControl(double max_latency_s) : max_latency_s_(max_latency_s) {}

  void update(double waited_s, Odometry& odo, OdometryResult::Realtime& rt) {
    longest_s_ = std::max(longest_s_, waited_s);
    const Clock::time_point now = Clock::now();
    if (now - decided_ < std::chrono::milliseconds(50)) return;
    int next = stride_;
    if (longest_s_ > 0.25 * max_latency_s_)
      next = std::min(2 * stride_, kMaxStride);
    else if (longest_s_ < 0.05 * max_latency_s_)
      next = std::max(stride_ / 2, 1);
    decided_ = now, longest_s_ = 0;
    if (next == stride_) return;
    stride_ = next;
    odo.setEventFrameStride(stride_);
    rt.max_event_frame_stride = std::max(rt.max_event_frame_stride, stride_);
  }

 private:
  double max_latency_s_;
  int stride_ = 1;
  double longest_s_ = 0;
  Clock::time_point decided_{};
};

// The processing: what was released, unless it waited too long (chunks) or is stale (frames).
void consume(const Sequence& seq, const RealtimeOptions& options, const ReleaseFn& release,
             ReleaseQueue& queue, Odometry& odo, OdometryResult::Realtime& rt) {
  ReleasedItem item;
  bool newer_frame = false;
  const auto max_wait = std::chrono::duration<double>(options.max_latency_s);
  StrideControl stride(options.max_latency_s);
  FramePacer pacer(options.min_frame_rate_hz);
  while (queue.pop(item, newer_frame)) {
    stride.update(std::chrono::duration<double>(Clock::now() - item.released).count(), odo, rt);
    if (item.frame) {
      const FrameRef& f = seq.frames()[item.index];
      if (pacer.take(f.t, newer_frame))
        odo.addFrame(f.t, item.image, f.exposure);
      else
        ++rt.frames_skipped;
    } else if (Clock::now() - item.released > max_wait) {
      rt.events_skipped += item.events.size();
    } else {
      odo.addEvents(item.events);
    }
    recordLatencies(odo.result(), release, rt.latency_ms);
  }
}

}  // namespace

OdometryResult runOdometryRealtime(const Sequence& seq, const OdometryConfig& cfg,
                                   const RealtimeOptions& options, const std::atomic<bool>* stop,
                                   OdometryListener* listener) {
  if (!(options.speed > 0) || !(options.max_latency_s > 0) || !(options.min_frame_rate_hz > 0) ||
      options.max_queued_frames < 1)
    throw std::invalid_argument(
        "realtime: speed, max_latency_s, min_frame_rate_hz and max_queued_frames must be > 0");
  const RunPlan plan = planRun(seq, cfg);
  Odometry odo(seq.camera(), cfg, listener);
  const Clock::time_point wall0 = Clock::now();
  const ReleaseFn release = [&](TimeNs t) {
    return wall0 +
           std::chrono::nanoseconds(std::llround(static_cast<double>(t - plan.first_t) / options.speed));
  };
  ReleaseQueue queue(options.max_queued_events, options.max_queued_frames);
  std::atomic<bool> failed{false};  // the processing threw: the producer stops too
  const std::function<bool()> stopped = [&] { return failed.load() || (stop != nullptr && stop->load()); };
  std::thread camera(produce, std::cref(seq), std::cref(plan), cfg.use_events, std::cref(release),
                     std::cref(stopped), std::ref(queue));
  OdometryResult::Realtime rt;
  try {
    consume(seq, options, release, queue, odo, rt);
  } catch (...) {
    failed = true;
    camera.join();
    throw;
  }
  camera.join();
  if (const std::exception_ptr error = queue.error()) std::rethrow_exception(error);
  odo.setEventFrameStride(1);  // no more input: nothing left to catch up with
  odo.finish();                // may track the last buffered event frames
  OdometryResult r = odo.takeResult();
  recordLatencies(r, release, rt.latency_ms);
  rt.on = true;
  rt.speed = options.speed;
  rt.events_skipped += queue.droppedEvents();
  rt.frames_skipped += queue.droppedFrames();
  r.realtime = std::move(rt);
  if (stop != nullptr && stop->load()) {
    r.interrupted = true;
    r.interrupted_t = r.events.empty() ? plan.first_t : r.events.back().t;
  }
  return r;
}

}  // namespace eds
