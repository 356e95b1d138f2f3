// `eds info PATH [--json]`: what a sequence folder or recording file holds.
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>

#include "commands.hpp"
#include "io/sequence_stats.hpp"
#include "recording_options.hpp"

namespace eds::app {

namespace {

struct InfoArgs {
  std::string path;
  bool json = false;
  RecordingArgs recording;
};

void printText(const Sequence& seq, const SequenceStats& s) {
  std::printf("input        %s (%s)\n", seq.dir().c_str(), seq.format().c_str());
  if (s.width > 0)
    std::printf("resolution   %d x %d\n", s.width, s.height);
  else
    std::printf("resolution   unknown (give it with --resolution WxH)\n");
  if (seq.hasCalibration()) {
    const CameraModel& c = seq.camera();
    std::printf("camera       fx %.3f fy %.3f cx %.3f cy %.3f, distortion %s (from %s)\n", c.fx, c.fy, c.cx,
                c.cy, toString(c.distortion), seq.calibrationSource().c_str());
  } else {
    std::printf("camera       no calibration\n");
  }
  if (seq.hasEvents()) {
    std::printf("events       %zu (%s)\n", s.events, seq.eventsFile().filename().c_str());
    std::printf("  span       %.6f .. %.6f s (%.3f s)\n", toSeconds(s.events_t0), toSeconds(s.events_t1),
                toSeconds(s.events_t1 - s.events_t0));
    std::printf("  rate       mean %.3f M events/s, peak %.3f M events/s (%g ms windows)\n",
                s.events_per_s_mean * 1e-6, s.events_per_s_peak * 1e-6, toSeconds(s.peak_window_ns) * 1e3);
    std::printf("  polarity   %.1f%% positive\n", s.events ? 100.0 * s.positive / s.events : 0.0);
    if (s.triggers > 0) std::printf("triggers     %zu\n", s.triggers);
  } else {
    std::printf("events       none\n");
  }
  if (s.frames > 0)
    std::printf("frames       %zu, %.6f .. %.6f s, %.3f Hz\n", s.frames, toSeconds(s.frames_t0),
                toSeconds(s.frames_t1), s.frame_rate);
  else
    std::printf("frames       none\n");
  if (s.frames_with_exposure > 0)
    std::printf("exposure     %.3f .. %.3f ms recorded for %zu frames (used to deblur them)\n",
                s.exposure_min / 1e6, s.exposure_max / 1e6, s.frames_with_exposure);
  if (seq.imuSamples() > 0)
    std::printf("imu          %llu samples (not used by the odometry yet)\n",
                static_cast<unsigned long long>(seq.imuSamples()));
  if (s.gt_poses > 0)
    std::printf("ground truth %zu poses, %.6f .. %.6f s (%.3f s)\n", s.gt_poses, toSeconds(s.gt_t0),
                toSeconds(s.gt_t1), toSeconds(s.gt_t1 - s.gt_t0));
  else
    std::printf("ground truth none\n");
}

// One object; counts are integers and times integer nanoseconds.
void printJson(const Sequence& seq, const SequenceStats& s) {
  nlohmann::ordered_json j;
  j["path"] = seq.dir().string();
  j["format"] = seq.format();
  j["width"] = s.width;
  j["height"] = s.height;
  j["events"] = s.events;
  j["events_on"] = s.positive;
  j["t_first_ns"] = s.events > 0 ? nlohmann::json(s.events_t0) : nlohmann::json(nullptr);
  j["t_last_ns"] = s.events > 0 ? nlohmann::json(s.events_t1) : nlohmann::json(nullptr);
  j["frames"] = s.frames;
  j["frames_t_first_ns"] = s.frames > 0 ? nlohmann::json(s.frames_t0) : nlohmann::json(nullptr);
  j["frames_t_last_ns"] = s.frames > 0 ? nlohmann::json(s.frames_t1) : nlohmann::json(nullptr);
  j["frames_with_exposure"] = s.frames_with_exposure;
  j["exposure_min_ns"] =
      s.frames_with_exposure > 0 ? nlohmann::json(s.exposure_min) : nlohmann::json(nullptr);
  j["exposure_max_ns"] =
      s.frames_with_exposure > 0 ? nlohmann::json(s.exposure_max) : nlohmann::json(nullptr);
  j["imu"] = seq.imuSamples();
  j["triggers"] = s.triggers;
  j["ground_truth"] = s.gt_poses;
  j["calibration"] = seq.hasCalibration();
  if (seq.hasCalibration()) j["calibration_source"] = seq.calibrationSource();
  std::printf("%s\n", j.dump(2).c_str());
}

void runInfo(const InfoArgs& a) {
  const Sequence seq(a.path, a.recording.options());
  const SequenceStats s = computeStats(seq);
  if (a.json)
    printJson(seq, s);
  else
    printText(seq, s);
}

}  // namespace

void addInfoCommand(CLI::App& app) {
  auto* cmd =
      app.add_subcommand("info", "Print what a sequence or recording holds (format, sizes, counts, spans)");
  auto a = std::make_shared<InfoArgs>();
  cmd->add_option(
         "path", a->path,
         "Sequence folder (ECD layout) or recording: AEDAT 4.0, Prophesee .raw/.dat, ROS 1 .bag, rosbag2 "
         ".db3/.mcap (or its folder), HDF5 (DSEC, TUM-VIE, VECtor, MVSEC, M3ED, eds)")
      ->required();
  cmd->add_flag("--json", a->json, "One JSON object (counts as integers, times as integer ns)");
  addRecordingOptions(cmd, a->recording);
  cmd->callback([a] { runInfo(*a); });
}

}  // namespace eds::app
