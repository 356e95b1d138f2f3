// `eds track SEQUENCE --depth-from-gt --out DIR`: event tracking against keyframes with true depth;
// `eds track SEQUENCE --reference RUN_DIR --out DIR`: against the keyframes of a previous `eds run`.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "commands.hpp"
#include "io/output_file.hpp"
#include "recording_options.hpp"
#include "system/odometry_config_io.hpp"
#include "system/track_only.hpp"
#include "system/track_reference.hpp"

namespace eds::app {

namespace {

struct TrackArgs {
  std::string sequence, out = "track_out", calib, reference, config;
  bool depth_from_gt = false, debug_images = false;
  RecordingArgs recording;
  TrackOnlyConfig cfg;
  CLI::Option *events = nullptr, *overlap = nullptr, *duration = nullptr;
};

void printSummary(const TrackOnlyResult& r, const std::filesystem::path& out) {
  std::printf(
      "tracked %zu of %zu event frames, %zu keyframes, %zu failures; %.2f s wall for %.2f s (real-time "
      "factor %.2f)\n",
      r.tracked, r.event_frames, r.keyframes, r.failures.size(), r.wall_s, r.sequence_s,
      r.sequence_s > 0 ? r.wall_s / r.sequence_s : 0.0);
  std::printf("wrote %s/trajectory_events.txt and summary.json\n", out.string().c_str());
}

// Against a run's keyframes: the event front-end of `eds run` with the run's parameters for the
// sensor's size, the --config file, then --events / --overlap / --duration.
void runTrackReference(TrackArgs& a, const Sequence& seq, const std::filesystem::path& out) {
  const ReferenceRun ref = readReferenceRun(a.reference);
  OdometryConfig cfg = defaultOdometryConfig(seq.camera().width, seq.camera().height);
  if (!a.config.empty()) loadOdometryConfig(a.config, cfg);
  if (a.events->count() > 0) cfg.event_frame.num_events = a.cfg.event_frame.num_events;
  if (a.overlap->count() > 0) cfg.event_frame.overlap = a.cfg.event_frame.overlap;
  if (a.duration->count() > 0) cfg.duration_s = a.cfg.duration_s;
  const TrackOnlyResult r = trackAgainstReference(seq, ref, cfg);
  writeTum(out / "trajectory_events.txt", r.trajectory);
  writeTrackSummary(out / "summary.json", r, "track --reference",
                    {{"events_per_frame", cfg.event_frame.num_events},
                     {"overlap", cfg.event_frame.overlap},
                     {"reference_keyframes", static_cast<double>(ref.keyframes.size())}});
  printSummary(r, out);
}

void runTrack(TrackArgs& a) {
  if (a.depth_from_gt == !a.reference.empty())
    throw std::invalid_argument(
        "eds track needs one of --depth-from-gt (depth maps of a simulated sequence) or --reference RUN_DIR "
        "(the keyframes of an `eds run`)");
  Sequence seq(a.sequence, a.recording.options());
  if (!a.calib.empty()) seq.setCamera(readCameraFile(a.calib), a.calib);
  const std::filesystem::path out(a.out);
  requireWritableDir(out);
  if (!a.reference.empty()) return runTrackReference(a, seq, out);
  if (a.debug_images) {
    a.cfg.debug_dir = out / "debug";
    std::filesystem::create_directories(a.cfg.debug_dir);
  }
  const TrackOnlyResult r = runTrackOnly(seq, a.cfg);
  writeTum(out / "trajectory_events.txt", r.trajectory);
  writeTrackSummary(out / "summary.json", r, a.cfg);
  printSummary(r, out);
}

}  // namespace

void addTrackCommand(CLI::App& app) {
  auto* cmd =
      app.add_subcommand("track", "Track events against keyframes with known depth (tracking-only mode)");
  auto a = std::make_shared<TrackArgs>();
  cmd->add_option("sequence", a->sequence, "Sequence folder (needs events, frames, depth/ and ground truth)")
      ->required();
  cmd->add_flag("--depth-from-gt", a->depth_from_gt, "Keyframe depth from the sequence's depth maps");
  cmd->add_option("--reference", a->reference,
                  "Track against the keyframes of this `eds run` output folder (its keyframes/)")
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--config", a->config,
                  "With --reference: YAML parameters of the event front-end (as eds run)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", a->out, "Output folder")->capture_default_str();
  cmd->add_option("--calib", a->calib,
                  "Calibration instead of the sequence's own (ECD calib.txt or Kalibr YAML)")
      ->check(CLI::ExistingFile);
  addRecordingOptions(cmd, a->recording);
  a->events = cmd->add_option("--events", a->cfg.event_frame.num_events, "Events per event frame (N)")
                  ->capture_default_str();
  a->overlap =
      cmd->add_option("--overlap", a->cfg.event_frame.overlap, "Overlap of consecutive event frames, [0, 1)")
          ->capture_default_str();
  cmd->add_option("--tile", a->cfg.events.points.tile, "Point selection tile size, px")
      ->capture_default_str();
  cmd->add_option("--points-fraction", a->cfg.events.points.fraction,
                  "Fraction of each tile's pixels selected")
      ->capture_default_str();
  cmd->add_option("--max-points", a->cfg.events.points.max_points, "Cap on points per keyframe (0: none)")
      ->capture_default_str();
  cmd->add_option("--min-gradient", a->cfg.events.points.min_gradient, "Minimum log-gradient of a point")
      ->capture_default_str();
  cmd->add_option("--depth-noise", a->cfg.depth_noise, "Depth noise sigma, fraction of the median depth")
      ->capture_default_str();
  cmd->add_option("--depth-median", a->cfg.events.depth_median_px,
                  "Median-filter keyframe inverse depths over this radius, px (0: off)")
      ->capture_default_str();
  cmd->add_option("--seed", a->cfg.seed, "Seed of the depth noise")->capture_default_str();
  a->duration =
      cmd->add_option("--duration", a->cfg.duration_s, "Seconds to process from the first frame (0: all)")
          ->capture_default_str();
  cmd->add_option("--kf-rotation", a->cfg.policy.max_rotation_deg, "New keyframe above this rotation, deg")
      ->capture_default_str();
  cmd->add_option("--kf-translation", a->cfg.policy.max_translation_ratio,
                  "New keyframe above this translation / median depth")
      ->capture_default_str();
  cmd->add_option("--kf-point-drop", a->cfg.policy.max_point_drop,
                  "New keyframe when this fraction of points left view")
      ->capture_default_str();
  cmd->add_flag(
      "!--no-frame-refine", a->cfg.refine_keyframes,
      "Keyframe poses from events only (default: refined by aligning the frame to the previous keyframe)");
  cmd->add_option(
         "--min-correlation-ratio", a->cfg.events.lost_track.min_correlation_ratio,
         "Lost track when an event frame's correlation falls below this fraction of its recent median "
         "(0: off)")
      ->capture_default_str();
  cmd->add_option(
         "--max-cost-ratio", a->cfg.events.lost_track.max_cost_ratio,
         "Lost track when an event frame's cost rises above this multiple of its recent median (0: off)")
      ->capture_default_str();
  cmd->add_flag("!--no-reversal-compensation", a->cfg.event_frame.reversal_compensation,
                "Event frames without the events a DVS loses at each brightness turn put back "
                "(--depth-from-gt; with --reference as eds run has it: off from 640x480 on)");
  cmd->add_option("--compensation-lookahead", a->cfg.event_frame.compensation_lookahead,
                  "Events after each packet searched for its pending turns, in units of N")
      ->capture_default_str();
  cmd->add_flag("--debug-images", a->debug_images, "Write event frame | EGM prediction PNGs to OUT/debug");
  cmd->callback([a] { runTrack(*a); });
}

}  // namespace eds::app
