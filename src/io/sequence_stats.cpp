#include "io/sequence_stats.hpp"

#include <algorithm>

namespace eds {

SequenceStats computeStats(const Sequence& seq) {
  SequenceStats s;
  s.width = seq.width();
  s.height = seq.height();
  if (seq.hasEvents()) {
    auto src = seq.openEvents();
    EventArray chunk;
    chunk.reserve(1 << 20);
    // Peak rate: events per fixed window of peak_window_ns, counted in the stream's own pass.
    TimeNs window_start = -1;
    std::size_t in_window = 0, peak = 0;
    while (true) {
      chunk.clear();
      if (src->read(chunk, 1 << 20) == 0) break;
      if (s.events == 0) s.events_t0 = chunk.t.front();
      for (std::size_t i = 0; i < chunk.size(); ++i) {
        const TimeNs t = chunk.t[i];
        if (window_start < 0 || t >= window_start + s.peak_window_ns) {
          peak = std::max(peak, in_window);
          s.triggers = src->triggers().size();
          window_start =
              window_start < 0 ? t : window_start + (t - window_start) / s.peak_window_ns * s.peak_window_ns;
          in_window = 0;
        }
        ++in_window;
        s.positive += chunk.p[i] > 0;
      }
      s.events += chunk.size();
      s.events_t1 = chunk.t.back();
    }
    peak = std::max(peak, in_window);
    s.triggers = src->triggers().size();
    const double span = toSeconds(s.events_t1 - s.events_t0);
    s.events_per_s_mean = span > 0 ? static_cast<double>(s.events) / span : 0.0;
    s.events_per_s_peak = static_cast<double>(peak) / toSeconds(s.peak_window_ns);
  }
  const auto& frames = seq.frames();
  s.frames = frames.size();
  if (!frames.empty()) {
    s.frames_t0 = frames.front().t;
    s.frames_t1 = frames.back().t;
    if (frames.size() > 1) s.frame_rate = (frames.size() - 1) / toSeconds(s.frames_t1 - s.frames_t0);
    for (const FrameRef& f : frames) {
      if (f.exposure <= 0) continue;
      s.exposure_min = s.frames_with_exposure == 0 ? f.exposure : std::min(s.exposure_min, f.exposure);
      s.exposure_max = std::max(s.exposure_max, f.exposure);
      ++s.frames_with_exposure;
    }
  }
  if (seq.hasGroundTruth()) {
    const Trajectory gt = seq.groundTruth();
    s.gt_poses = gt.size();
    if (!gt.empty()) {
      s.gt_t0 = gt.front().t;
      s.gt_t1 = gt.back().t;
    }
  }
  return s;
}

}  // namespace eds
