// `eds run SEQUENCE --out DIR [--frames-only] [--config FILE] [options]`: visual odometry on a sequence.
// Parameters: defaults, then the YAML file of --config, then the options given on the command line.
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "commands.hpp"
#include "core/log.hpp"
#include "interrupt.hpp"
#include "io/output_file.hpp"
#include "recording_options.hpp"
#include "report/html_report.hpp"
#include "system/odometry.hpp"
#include "system/odometry_config_io.hpp"
#include "system/realtime_run.hpp"
#include "system/reference_run.hpp"
#include "system/run_stats.hpp"

namespace eds::app {

namespace {

struct RunArgs {
  std::string sequence, out = "run_out", config, calib;
  bool frames_only = false;
  RecordingArgs recording;
  OdometryConfig cli;                                      // what the options wrote
  std::vector<std::pair<CLI::Option*, std::string>> keys;  // option -> parameter name
  std::vector<std::string> sets;                           // --set KEY=VALUE, in order
  bool realtime = false;
  RealtimeOptions realtime_options;
  bool report = false;
};

void printRealtime(const OdometryResult& r) {
  const OdometryResult::Realtime& rt = r.realtime;
  const nlohmann::json s = timingStats(rt.latency_ms);  // as summary.json reports it
  const auto at = [&](const char* key) { return s.is_null() ? 0.0 : s[key].get<double>(); };
  std::printf(
      "real time at x%.2f: event pose latency %.1f ms median, %.1f ms p95, %.1f ms max; skipped %zu events, "
      "%zu frames; %zu event frames shed (stride up to %d)\n",
      rt.speed, at("median"), at("p95"), at("max"), rt.events_skipped, rt.frames_skipped, r.event_frames_shed,
      rt.max_event_frame_stride);
}

void runRun(RunArgs& a) {
  Sequence seq(a.sequence, a.recording.options());
  if (!a.calib.empty()) seq.setCamera(readCameraFile(a.calib), a.calib);
  // Defaults for the sensor's size, then the file, then the command line.
  OdometryConfig cfg = defaultOdometryConfig(seq.width(), seq.height());
  if (a.realtime) cfg.wait_for_keyframe = false;  // a live camera cannot wait for the back-end
  if (!a.config.empty()) loadOdometryConfig(a.config, cfg);
  for (const auto& [opt, key] : a.keys)
    if (opt->count() > 0) copyOdometryParameter(a.cli, cfg, key);
  for (const std::string& kv : a.sets) setOdometryParameter(cfg, kv);
  if (a.frames_only) cfg.use_events = false;
  requireWritableDir(a.out);
  // A progress bar on a terminal (stderr), nothing when it is a file or a pipe.
  ProgressFn bar;
  if (isatty(fileno(stderr))) {
    bar = [](double done_s, double total_s) {
      constexpr int kWidth = 30;
      const double f = total_s > 0 ? std::clamp(done_s / total_s, 0.0, 1.0) : 1.0;
      const int n = static_cast<int>(f * kWidth + 0.5);
      std::fprintf(stderr, "\r[%s%s] %3.0f %%  %.1f / %.1f s", std::string(n, '#').c_str(),
                   std::string(kWidth - n, '.').c_str(), 100 * f, done_s, total_s);
      if (f >= 1.0) std::fprintf(stderr, "\n");
      std::fflush(stderr);
    };
  }
  logf(LogLevel::kInfo, "running on %s (Ctrl-C finishes early and keeps the outputs so far)",
       a.sequence.c_str());
  // The keyframes go to the output folder as they retire, not into memory until the end.
  ReferenceKeyframeWriter keyframes(a.out);
  const OdometryResult r =
      a.realtime ? runOdometryRealtime(seq, cfg, a.realtime_options, &listenForInterrupt(), &keyframes)
                 : runOdometry(seq, cfg, bar, &listenForInterrupt(), &keyframes);
  if (r.interrupted && bar) std::fprintf(stderr, "\n");
  RunInputs inputs{a.sequence, seq.format(), {}};
  if (seq.hasGroundTruth()) inputs.groundtruth = seq.groundTruth();
  writeOdometryOutputs(a.out, r, cfg, inputs);
  saveOdometryConfig(std::filesystem::path(a.out) / "config_used.yaml", cfg);
  if (!r.initialized)
    std::printf("never initialized over %zu frames (not enough texture or parallax)\n", r.frames_in);
  else
    std::printf(
        "initialized at %.2f s after %d frames; %zu poses, %zu keyframes, %zu map points, %zu failures\n",
        toSeconds(r.init_t - r.first_t), r.init_frames, r.frames.size(), r.keyframes.size(), r.map.size(),
        r.failures.size());
  for (const TrackLoss& l : r.losses) {
    std::printf("track lost at %.2f s (%s): ", toSeconds(l.t_lost - r.first_t), l.cause.c_str());
    if (l.t_recovered >= 0)
      std::printf("recovered at %.2f s, %s\n", toSeconds(l.t_recovered - r.first_t), l.recovery.c_str());
    else
      std::printf("not recovered\n");
  }
  if (r.segments.size() > 1)
    std::printf(
        "%zu map segments, each with its own world frame and scale ('# segment' lines in the "
        "trajectory files)\n",
        r.segments.size());
  if (r.interrupted)
    std::printf("interrupted at %.2f s of the sequence: the outputs hold what was computed until then\n",
                toSeconds(r.interrupted_t - r.first_t));
  std::printf("%.2f s wall for %.2f s of sequence (real-time factor %.2f)\n", r.wall_s, r.sequence_s,
              r.sequence_s > 0 ? r.wall_s / r.sequence_s : 0.0);
  if (cfg.use_events)
    std::printf("%zu of %zu event frames tracked (event-rate poses)\n", r.events_tracked, r.event_frames);
  if (r.realtime.on) printRealtime(r);
  std::printf(
      "wrote %s/{%strajectory_frames[_live].txt, keyframes.txt, map.ply, summary.json, config_used.yaml}\n",
      a.out.c_str(), cfg.use_events ? "trajectory_events[_live].txt, " : "");
  if (a.report) {
    const std::filesystem::path html = std::filesystem::path(a.out) / "report.html";
    report::writeReport({a.out}, {}, html);
    std::printf("wrote %s\n", html.string().c_str());
  }
}

}  // namespace

void addRunCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("run", "Run the odometry on a sequence (events + frames, or frames only)");
  auto a = std::make_shared<RunArgs>();
  OdometryConfig& c = a->cli;
  cmd->add_option("sequence", a->sequence, "Sequence folder")->required();
  cmd->add_option("--out", a->out, "Output folder")->capture_default_str();
  cmd->add_option("--config", a->config, "YAML file of parameters (as config_used.yaml writes them)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--calib", a->calib,
                  "Calibration instead of the sequence's own (ECD calib.txt, e.g. from `eds calibrate`, or "
                  "Kalibr YAML)")
      ->check(CLI::ExistingFile);
  addRecordingOptions(cmd, a->recording);
  cmd->add_option("--set", a->sets,
                  "KEY=VALUE: any parameter by its name in config_used.yaml (e.g. --set "
                  "events.tracker.levels=4 --set backend.removal=oldest); applied last");
  cmd->add_flag("--frames-only", a->frames_only,
                "Frames alone (no events): bootstrap, frame tracking, mapping, back-end");
  cmd->add_flag(
      "--realtime", a->realtime,
      "Feed the sequence on the wall clock as a camera would; when processing falls behind, late event "
      "chunks and stale frames are dropped (summary.json: latency, what was skipped)");
  cmd->add_flag("--report", a->report,
                "Also write DIR/report.html (eds report: plots, keyframe and event-frame images, 3D map; "
                "accuracy when the sequence has ground truth)");
  cmd->add_option("--speed", a->realtime_options.speed, "With --realtime: sensor seconds per wall second")
      ->capture_default_str();
  cmd->add_option("--max-latency", a->realtime_options.max_latency_s,
                  "With --realtime: an event chunk waiting longer than this (s) is dropped")
      ->capture_default_str();
  cmd->add_option(
         "--min-frame-rate", a->realtime_options.min_frame_rate_hz,
         "With --realtime: frames are dropped for newer ones only down to this rate (Hz, sensor time)")
      ->capture_default_str();
  // Options that set a parameter: registered with its name, so that they override the --config file.
  const auto param = [&](const std::string& name, auto& field, const std::string& key,
                         const std::string& help) {
    a->keys.emplace_back(cmd->add_option(name, field, help)->capture_default_str(), key);
  };
  const auto flag = [&](const std::string& name, bool& field, const std::string& key,
                        const std::string& help) {
    a->keys.emplace_back(cmd->add_flag(name, field, help), key);
  };
  param("--frame-rate", c.frame_rate, "frame_rate", "Keep the frames nearest this rate, Hz (0: all)");
  param("--start", c.start_s, "start_s", "Seconds to skip from the first frame");
  param("--duration", c.duration_s, "duration_s", "Seconds to process (0: to the end)");
  param("--exposure", c.deblur.exposure_s, "deblur.exposure_s",
        "The frames' exposure time, s, stamped at its middle: keyframes are deblurred with the events "
        "of their exposure for the event tracker (0: unknown, estimated from the first frames with "
        "motion and their events; --set deblur.estimate=false: no deblurring)");
  // Defaults that depend on the sensor's size (defaultOdometryConfig) say so instead of one number.
  const auto sized = [&](const std::string& name, auto& field, const std::string& key,
                         const std::string& help, const std::string& defaults) {
    a->keys.emplace_back(cmd->add_option(name, field, help)->default_str(defaults), key);
  };
  sized("--events", c.event_frame.num_events, "event_frame.num_events", "Events per event frame (N)",
        "20000 up to 240x180, 80000 from 640x480, scaled with the pixels between");
  sized("--overlap", c.event_frame.overlap, "event_frame.overlap",
        "Overlap of consecutive event frames, [0, 1)", "0.5 up to 240x180, 0.6 from 640x480");
  param("--window", c.backend.window, "backend.window", "Keyframes in the back-end window");
  param("--points-per-keyframe", c.backend.points_per_keyframe, "backend.points_per_keyframe",
        "Points each keyframe hosts in the back-end");
  {
    std::map<std::string, WindowRemoval> names;
    for (const auto& [v, name] : enumNames(WindowRemoval{})) names.emplace(name, v);
    a->keys.emplace_back(cmd->add_option("--window-removal", c.backend.removal,
                                         "Keyframe that leaves a full window: dso, DSO's rule (keeps a long "
                                         "baseline), or oldest")
                             ->transform(CLI::CheckedTransformer(names))
                             ->default_str("dso"),
                         "backend.removal");
  }
  param("--ba-iterations", c.backend.ba.iterations, "backend.ba.iterations",
        "Back-end iterations per keyframe");
  param("--init-parallax", c.bootstrap.min_parallax_px, "bootstrap.min_parallax_px",
        "Bootstrap: RMS pixel parallax of translation needed to initialize");
  param("--init-levels", c.bootstrap.ba_levels, "bootstrap.ba_levels",
        "Bootstrap: pyramid levels of the two-frame BA");
  param("--init-depth-prior", c.bootstrap.depth_prior_weight, "bootstrap.depth_prior_weight",
        "Bootstrap: weight of the prior holding inverse depths at 1 while parallax is short");
  param("--min-gradient", c.mapping.points.min_gradient, "mapping.points.min_gradient",
        "Keyframe points: minimum intensity gradient per pixel (intensity in [0, 1])");
  param("--kf-flow-t", c.policy.flow_t, "policy.flow_t",
        "New keyframe when the RMS flow of the translation exceeds this fraction of width + height");
  param("--kf-flow-rt", c.policy.flow_rt, "policy.flow_rt",
        "New keyframe when the RMS flow of the whole motion exceeds this fraction of width + height");
  param("--prior-levels", c.prior_levels, "prior_levels",
        "Pyramid levels of the frame alignment seeded by the event pose (0: all)");
  flag("!--no-epipolar-search", c.mapping.epipolar_search, "mapping.epipolar_search",
       "New keyframe points take the depth of the nearest projected map point only");
  flag("!--sync-backend", c.threaded_backend, "threaded_backend",
       "Run the back-end after each keyframe in the tracking thread (deterministic results)");
  flag("!--no-keyframe-wait", c.wait_for_keyframe, "wait_for_keyframe",
       "Threaded back-end: tracking never waits for a new keyframe to be mapped, and a keyframe wanted "
       "while the back-end is busy is left to a later frame unless the frame is far from its reference "
       "(live cameras; always on with --realtime)");
  flag("!--no-reversal-compensation", c.event_frame.reversal_compensation,
       "event_frame.reversal_compensation",
       "Event frames without the events a DVS loses at each brightness turn put back (the default "
       "from 640x480 on; --set event_frame.reversal_compensation=true puts them back there)");
  flag("--marginalization", c.backend.marginalize, "backend.marginalize",
       "Keep old keyframes' information as a prior (first-estimate Jacobians; off by default)");
  cmd->callback([a] { runRun(*a); });
}

}  // namespace eds::app
