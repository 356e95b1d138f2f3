// `eds simulate`: an event-camera simulator (ESIM-style) writing a sequence in the ECD layout.
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "core/error.hpp"
#include "io/kalibr.hpp"
#include "io/sequence.hpp"
#include "sim/event_faults.hpp"
#include "sim/presets.hpp"
#include "sim/writer.hpp"

namespace eds::app {

namespace {

struct SimulateArgs {
  std::string preset = "room";
  std::string scene_file, scene_txt, texture_dir, trajectory, out = "sim_out", resolution = "240x180", calib;
  double t_start = 0, duration = 5.0, smooth = 0.0;
  std::uint64_t seed = 1;
  double C = 0.2, C_pos = 0, C_neg = 0, contrast_noise = 0, noise_rate = 0, refractory = 0;
  double hot_fraction = 0, hot_rate = 100;
  double fps = 25, exposure = 0, render_hz = 0, max_px = 0.5;
  int supersample = 2;
  bool gzip = false, quantize = false, no_depth = false;
  // Faults, as FROM:TO[:VALUE] with times in seconds from the start.
  std::vector<std::string> frame_gains, event_gaps, noise_bursts, flicker;
  double event_offset = 0;
};

// "FROM:TO" or "FROM:TO:VALUE" (seconds from the start of the sequence; VALUE >= 0) as a time window.
sim::EventFaults::Window parseWindow(const std::string& text, const char* option, bool with_value,
                                     TimeNs start) {
  double from = 0, to = 0, value = 0;
  char tail = 0;
  const int n = with_value ? std::sscanf(text.c_str(), "%lf:%lf:%lf%c", &from, &to, &value, &tail)
                           : std::sscanf(text.c_str(), "%lf:%lf%c", &from, &to, &tail);
  if (n != (with_value ? 3 : 2) || !(to > from) || !(value >= 0))
    throw std::invalid_argument(std::string(option) + " '" + text + "': expected FROM:TO" +
                                (with_value ? ":VALUE" : "") + " with FROM < TO" +
                                (with_value ? ", VALUE >= 0" : ""));
  return {start + fromSeconds(from), start + fromSeconds(to), value};
}

std::vector<sim::EventFaults::Window> parseWindows(const std::vector<std::string>& texts, const char* option,
                                                   bool with_value, TimeNs start) {
  std::vector<sim::EventFaults::Window> out;
  for (const std::string& t : texts) out.push_back(parseWindow(t, option, with_value, start));
  return out;
}

CameraModel makeCamera(const SimulateArgs& a) {
  if (!a.calib.empty()) {
    const bool yaml = a.calib.size() > 5 && a.calib.substr(a.calib.size() - 5) == ".yaml";
    if (yaml) return cameraFromKalibr(readKalibrCamera(a.calib), a.calib);
    CameraModel cam = readEcdCalib(a.calib);
    int w = 0, h = 0;
    if (std::sscanf(a.resolution.c_str(), "%dx%d", &w, &h) != 2 || w <= 0 || h <= 0)
      throw std::invalid_argument("--resolution must be WIDTHxHEIGHT, got '" + a.resolution + "'");
    cam.width = w, cam.height = h;
    return cam;
  }
  int w = 0, h = 0;
  if (std::sscanf(a.resolution.c_str(), "%dx%d", &w, &h) != 2 || w <= 0 || h <= 0 || w > 4096 || h > 4096)
    throw std::invalid_argument("--resolution must be WIDTHxHEIGHT (e.g. 240x180), got '" + a.resolution +
                                "'");
  return sim::defaultCamera(w, h);
}

void runSimulate(const SimulateArgs& a) {
  if (!(a.C > 0)) throw std::invalid_argument("--C must be > 0");
  if (a.C_pos < 0 || a.C_neg < 0) throw std::invalid_argument("--C-pos/--C-neg must be > 0");
  if (!(a.duration > 0)) throw std::invalid_argument("--duration must be > 0");
  // Motion: smoothed first, then cut, so the window's ends are smoothed with real neighbours.
  Trajectory traj;
  if (!a.trajectory.empty()) {
    traj = readTum(a.trajectory);
    if (a.smooth > 0) traj = sim::smoothTrajectory(traj, a.smooth);
    traj = sim::cutTrajectory(traj, a.t_start, a.duration, a.trajectory);
  } else {
    traj = sim::handheldMotion(a.duration, a.seed);
  }
  const sim::Motion motion(traj);
  sim::Scene scene;
  std::filesystem::path tex_base;
  if (!a.scene_file.empty()) {
    scene = sim::readSceneYaml(a.scene_file);
    tex_base = std::filesystem::path(a.scene_file).parent_path();
  } else if (!a.scene_txt.empty()) {
    scene = sim::readEsimSceneTxt(a.scene_txt, a.texture_dir);
  } else {
    scene = sim::makePreset(a.preset, motion, a.seed);
  }
  scene.loadTextures(tex_base);
  const CameraModel cam = makeCamera(a);
  cam.validate("camera");

  sim::SimConfig cfg;
  cfg.events.C_pos = a.C_pos > 0 ? a.C_pos : a.C;
  cfg.events.C_neg = a.C_neg > 0 ? a.C_neg : a.C;
  cfg.events.sigma_C = a.contrast_noise;
  cfg.events.refractory_s = a.refractory;
  cfg.events.noise_rate_hz = a.noise_rate;
  cfg.events.hot_pixel_fraction = a.hot_fraction;
  cfg.events.hot_pixel_rate_hz = a.hot_rate;
  cfg.events.seed = a.seed;
  cfg.render.supersample = a.supersample;
  cfg.fps = a.fps;
  cfg.exposure_s = a.exposure;
  cfg.render_hz = a.render_hz;
  cfg.max_px_per_step = a.max_px;
  cfg.quantize_8bit = a.quantize;

  const std::filesystem::path out(a.out);
  sim::EcdWriter writer(out, a.gzip, !a.no_depth);
  std::vector<sim::FrameGain> gains;
  for (const auto& w : parseWindows(a.frame_gains, "--frame-gain", true, motion.start()))
    gains.push_back({w.t0, w.t1, w.value});
  writer.setFrameGains(std::move(gains));
  sim::EventFaults faults;
  faults.gaps = parseWindows(a.event_gaps, "--event-gap", false, motion.start());
  faults.bursts = parseWindows(a.noise_bursts, "--noise-burst", true, motion.start());
  faults.flicker = parseWindows(a.flicker, "--flicker", true, motion.start());
  faults.offset = fromSeconds(a.event_offset);
  faults.seed = a.seed;
  sim::EventFaultSink faulty(writer, faults, cam.width, cam.height);
  if (cam.distortion == Distortion::kEquidistant)
    sim::writeKalibrCamchain(out / "camchain.yaml", cam);
  else
    sim::writeEcdCalib(out / "calib.txt", cam);
  sim::writeSceneYaml(out / "scene.yaml", scene);
  const TimeNs t0 = motion.start(), t1 = motion.end();
  sim::writeGroundTruth(out / "groundtruth.txt", motion, t0, t1, sim::kGroundTruthRateHz);
  sim::Simulator simulator(scene, cam, motion, cfg);
  const sim::SimStats st = faults.any() ? simulator.run(t0, t1, faulty) : simulator.run(t0, t1, writer);
  writer.finish();
  const double span = toSeconds(t1 - t0);
  std::printf(
      "simulated %.3f s: %zu events (%.3f M events/s), %zu frames, %zu renders, %.1f s wall (%.2fx real "
      "time)\n",
      span, st.events, st.events / span * 1e-6, st.frames, st.renders, st.wall_s, st.wall_s / span);
  std::printf("wrote %s\n", out.string().c_str());
}

}  // namespace

void addSimulateCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("simulate", "Simulate an event camera (and frames, depth, ground truth)");
  auto a = std::make_shared<SimulateArgs>();
  cmd->add_option("--preset", a->preset, std::string("Built-in scene: ") + sim::presetNames())
      ->capture_default_str();
  cmd->add_option("--scene", a->scene_file, "Scene YAML file (instead of a preset)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--esim-scene", a->scene_txt, "ESIM scene.txt (as in esim_poster6dof_planar)")
      ->check(CLI::ExistingFile);
  cmd->add_option("--texture-dir", a->texture_dir, "Folder of the textures named in --esim-scene");
  cmd->add_option("--trajectory", a->trajectory,
                  "TUM/ECD trajectory file (default: built-in hand-held motion)");
  cmd->add_option("--t-start", a->t_start, "Start of the window in the trajectory file, s")
      ->capture_default_str();
  cmd->add_option("--duration", a->duration, "Duration, s")->capture_default_str();
  cmd->add_option("--smooth", a->smooth, "Gaussian smoothing of the trajectory, sigma in s")
      ->capture_default_str();
  cmd->add_option("--out", a->out, "Output folder (ECD layout)")->capture_default_str();
  cmd->add_option("--seed", a->seed, "Random seed (scene layout, noise)")->capture_default_str();
  cmd->add_option("--C", a->C, "Contrast threshold (log intensity)")->capture_default_str();
  cmd->add_option("--C-pos", a->C_pos, "Positive threshold (default --C)");
  cmd->add_option("--C-neg", a->C_neg, "Negative threshold (default --C)");
  cmd->add_option("--contrast-noise", a->contrast_noise, "Std-dev of each crossing's threshold")
      ->capture_default_str();
  cmd->add_option("--noise-rate", a->noise_rate, "Background events per pixel per second")
      ->capture_default_str();
  cmd->add_option("--refractory", a->refractory, "Refractory period, s")->capture_default_str();
  cmd->add_option("--hot-pixels", a->hot_fraction, "Fraction of hot pixels")->capture_default_str();
  cmd->add_option("--hot-rate", a->hot_rate, "Hot pixel event rate, Hz")->capture_default_str();
  cmd->add_option("--fps", a->fps, "Frame rate (0: no frames)")->capture_default_str();
  cmd->add_option("--exposure", a->exposure, "Frame exposure time for motion blur, s")->capture_default_str();
  cmd->add_option(
      "--frame-gain", a->frame_gains,
      "FROM:TO:GAIN: frames from FROM to TO s (from the start) exposed GAIN times, clipped (0.05: "
      "covered lens; 4: blown out); the events are unaffected. Repeatable");
  cmd->add_option("--event-gap", a->event_gaps, "FROM:TO: no events in this window (a USB drop). Repeatable");
  cmd->add_option("--noise-burst", a->noise_bursts,
                  "FROM:TO:RATE: extra background noise, RATE events per pixel per second. Repeatable");
  cmd->add_option(
      "--flicker", a->flicker,
      "FROM:TO:HZ: a light flickering at HZ over a quarter-size patch of the upper left. Repeatable");
  cmd->add_option("--event-offset", a->event_offset,
                  "Added to every event time, s (the event clock's offset from the frames')")
      ->capture_default_str();
  cmd->add_option("--render-hz", a->render_hz, "Fixed render rate (0: adaptive)")->capture_default_str();
  cmd->add_option("--max-px-per-step", a->max_px, "Adaptive rendering: pixel motion per render")
      ->capture_default_str();
  cmd->add_option("--supersample", a->supersample, "Anti-aliasing rays per pixel per axis")
      ->capture_default_str();
  cmd->add_option("--resolution", a->resolution, "WIDTHxHEIGHT")->capture_default_str();
  cmd->add_option("--calib", a->calib, "Camera: ECD calib.txt (with --resolution) or Kalibr camchain YAML");
  cmd->add_flag("--gzip", a->gzip, "Write events.txt.gz");
  cmd->add_flag("--quantize-8bit", a->quantize, "Events from 8-bit images (like ESIM on stored frames)");
  cmd->add_flag("--no-depth", a->no_depth, "Do not write depth maps");
  cmd->callback([a] { runSimulate(*a); });
}

}  // namespace eds::app
