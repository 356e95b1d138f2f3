// `eds run SEQUENCE --frames-only --out DIR`: visual odometry on a sequence.
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "commands.hpp"
#include "system/odometry.hpp"

namespace eds::app {

namespace {

struct RunArgs {
  std::string sequence, out = "run_out";
  bool frames_only = false;
  OdometryConfig cfg;
};

void runRun(RunArgs& a) {
  a.cfg.use_events = !a.frames_only;
  const Sequence seq(a.sequence);
  const OdometryResult r = runOdometry(seq, a.cfg);
  writeOdometryOutputs(a.out, r, a.cfg);
  if (!r.initialized)
    std::printf("never initialized over %zu frames (not enough texture or parallax)\n", r.frames_in);
  else
    std::printf(
        "initialized at %.2f s after %d frames; %zu poses, %zu keyframes, %zu map points, %zu failures\n",
        toSeconds(r.init_t - r.first_t), r.init_frames, r.frames.size(), r.keyframes.size(), r.map.size(),
        r.failures.size());
  std::printf("%.2f s wall for %.2f s of sequence (real-time factor %.2f)\n", r.wall_s, r.sequence_s,
              r.sequence_s > 0 ? r.wall_s / r.sequence_s : 0.0);
  if (a.cfg.use_events)
    std::printf("%zu of %zu event frames tracked (event-rate poses)\n", r.events_tracked, r.event_frames);
  std::printf("wrote %s/{%strajectory_frames.txt, keyframes.txt, map.ply, summary.json}\n", a.out.c_str(),
              a.cfg.use_events ? "trajectory_events.txt, " : "");
}

}  // namespace

void addRunCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("run", "Run the odometry on a sequence");
  auto a = std::make_shared<RunArgs>();
  cmd->add_option("sequence", a->sequence, "Sequence folder")->required();
  cmd->add_flag("--frames-only", a->frames_only,
                "Frames alone: bootstrap, frame tracking, mapping, back-end");
  cmd->add_option("--out", a->out, "Output folder")->capture_default_str();
  cmd->add_option("--frame-rate", a->cfg.frame_rate, "Keep the frames nearest this rate, Hz (0: all)")
      ->capture_default_str();
  cmd->add_option("--start", a->cfg.start_s, "Seconds to skip from the first frame")->capture_default_str();
  cmd->add_option("--duration", a->cfg.duration_s, "Seconds to process (0: to the end)")
      ->capture_default_str();
  cmd->add_option("--window", a->cfg.backend.window, "Keyframes in the back-end window")
      ->capture_default_str();
  cmd->add_option("--points-per-keyframe", a->cfg.backend.points_per_keyframe,
                  "Points each keyframe hosts in the back-end")
      ->capture_default_str();
  cmd->add_option("--init-parallax", a->cfg.bootstrap.min_parallax_px,
                  "Bootstrap: RMS pixel parallax of translation needed to initialize")
      ->capture_default_str();
  cmd->add_option("--init-levels", a->cfg.bootstrap.ba_levels,
                  "Bootstrap: pyramid levels of the two-frame BA")
      ->capture_default_str();
  cmd->add_option("--init-depth-prior", a->cfg.bootstrap.depth_prior_weight,
                  "Bootstrap: weight of the prior holding inverse depths at 1 while parallax is short")
      ->capture_default_str();
  cmd->add_option("--ba-iterations", a->cfg.backend.ba.iterations, "Back-end iterations per keyframe")
      ->capture_default_str();
  cmd->add_option("--min-gradient", a->cfg.mapping.points.min_gradient,
                  "Keyframe points: minimum intensity gradient per pixel (intensity in [0, 1])")
      ->capture_default_str();
  cmd->add_flag("!--no-epipolar-search", a->cfg.mapping.epipolar_search,
                "New keyframe points take the depth of the nearest projected map point only");
  cmd->add_option("--kf-flow-t", a->cfg.policy.flow_t,
                  "New keyframe when the RMS flow of the translation exceeds this fraction of width + height")
      ->capture_default_str();
  cmd->add_option(
         "--kf-flow-rt", a->cfg.policy.flow_rt,
         "New keyframe when the RMS flow of the whole motion exceeds this fraction of width + height")
      ->capture_default_str();
  cmd->add_option("--prior-levels", a->cfg.prior_levels,
                  "Pyramid levels of the frame alignment seeded by the event pose (0: all)")
      ->capture_default_str();
  cmd->add_flag("!--sync-backend", a->cfg.threaded_backend,
                "Run the back-end after each keyframe in the tracking thread (deterministic results)");
  cmd->add_flag("--marginalization", a->cfg.backend.marginalize,
                "Keep old keyframes' information as a prior (experimental: no first-estimate Jacobians yet)");
  cmd->callback([a] { runRun(*a); });
}

}  // namespace eds::app
