#include "system/lens_calibration.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace eds {

std::vector<std::optional<SE3>> posesAtFrames(const std::vector<FrameRef>& frames, const Trajectory& T_w_c,
                                              double max_gap_s) {
  std::vector<std::optional<SE3>> out(frames.size());
  const TimeNs max_gap = static_cast<TimeNs>(std::llround(max_gap_s * 1e9));
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const TimeNs t = frames[i].t;
    auto it = std::lower_bound(T_w_c.begin(), T_w_c.end(), t,
                               [](const StampedPose& p, TimeNs v) { return p.t < v; });
    const StampedPose* best = nullptr;
    if (it != T_w_c.end()) best = &*it;
    if (it != T_w_c.begin() && (!best || t - std::prev(it)->t < best->t - t)) best = &*std::prev(it);
    if (best && std::llabs(best->t - t) <= max_gap) out[i] = best->T_w_c;
  }
  return out;
}

LensCalibrationReport calibrateLens(const Sequence& seq, const Trajectory& T_w_c,
                                    const LensCalibrationConfig& cfg) {
  LensCalibrationReport rep;
  const auto& frames = seq.frames();
  rep.frames = frames.size();
  const std::vector<std::optional<SE3>> poses = posesAtFrames(frames, T_w_c, cfg.max_pose_gap_s);
  rep.posed_frames = static_cast<std::size_t>(
      std::count_if(poses.begin(), poses.end(), [](const auto& p) { return p.has_value(); }));
  if (rep.posed_frames < 2)
    throw std::invalid_argument("lens calibration: the trajectory gives a pose (within " +
                                std::to_string(cfg.max_pose_gap_s * 1e3) + " ms) to " +
                                std::to_string(rep.posed_frames) + " of " + std::to_string(frames.size()) +
                                " frames; it needs at least two (is it this sequence's trajectory?)");
  // Only frames from the first posed one to the last are tracked: the rest cannot be used.
  const auto first = std::find_if(poses.begin(), poses.end(), [](const auto& p) { return p.has_value(); });
  const auto last = std::find_if(poses.rbegin(), poses.rend(), [](const auto& p) { return p.has_value(); });
  const std::size_t i0 = static_cast<std::size_t>(first - poses.begin());
  const std::size_t i1 = frames.size() - static_cast<std::size_t>(last - poses.rbegin());
  std::vector<cv::Mat> images(frames.size());
  for (std::size_t i = i0; i < i1; ++i) images[i] = seq.loadFrame(i);
  const std::vector<FeatureTrack> tracks = trackFeatures(images, cfg.tracks);
  rep.tracks = tracks.size();
  double len = 0;
  for (const auto& t : tracks) len += static_cast<double>(t.frames.size());
  rep.mean_track_length = tracks.empty() ? 0 : len / static_cast<double>(tracks.size());
  rep.result = refineLens(seq.camera(), tracks, poses, cfg.refine);
  return rep;
}

}  // namespace eds
