// `eds info SEQUENCE`: what a sequence holds.
#include <cstdio>
#include <string>

#include "commands.hpp"
#include "io/sequence_stats.hpp"

namespace eds::app {

namespace {

void printInfo(const std::string& dir) {
  const Sequence seq(dir);
  const SequenceStats s = computeStats(seq);
  std::printf("sequence     %s\n", dir.c_str());
  if (s.width > 0)
    std::printf("resolution   %d x %d\n", s.width, s.height);
  else
    std::printf("resolution   unknown (no images and no Kalibr calibration)\n");
  if (seq.hasCalibration()) {
    const CameraModel& c = seq.camera();
    std::printf("camera       fx %.3f fy %.3f cx %.3f cy %.3f, distortion %s\n", c.fx, c.fy, c.cx, c.cy,
                toString(c.distortion));
  } else {
    std::printf("camera       no calibration file\n");
  }
  if (seq.hasEvents()) {
    std::printf("events       %zu (%s)\n", s.events, seq.eventsFile().filename().c_str());
    std::printf("  span       %.6f .. %.6f s (%.3f s)\n", toSeconds(s.events_t0), toSeconds(s.events_t1),
                toSeconds(s.events_t1 - s.events_t0));
    std::printf("  rate       mean %.3f M events/s, peak %.3f M events/s (%g ms windows)\n",
                s.events_per_s_mean * 1e-6, s.events_per_s_peak * 1e-6, toSeconds(s.peak_window_ns) * 1e3);
    std::printf("  polarity   %.1f%% positive\n", s.events ? 100.0 * s.positive / s.events : 0.0);
  } else {
    std::printf("events       none\n");
  }
  if (s.frames > 0) {
    std::printf("frames       %zu, %.6f .. %.6f s, %.3f Hz\n", s.frames, toSeconds(s.frames_t0),
                toSeconds(s.frames_t1), s.frame_rate);
  } else {
    std::printf("frames       none\n");
  }
  if (s.gt_poses > 0)
    std::printf("ground truth %zu poses, %.6f .. %.6f s (%.3f s)\n", s.gt_poses, toSeconds(s.gt_t0),
                toSeconds(s.gt_t1), toSeconds(s.gt_t1 - s.gt_t0));
  else
    std::printf("ground truth none\n");
}

}  // namespace

void addInfoCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("info", "Print what a sequence holds (sizes, counts, rates, spans)");
  auto dir = std::make_shared<std::string>();
  cmd->add_option("sequence", *dir, "Sequence folder (ECD layout)")->required();
  cmd->callback([dir] { printInfo(*dir); });
}

}  // namespace eds::app
