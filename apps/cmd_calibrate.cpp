// `eds calibrate SEQUENCE --out DIR [--trajectory FILE]`: lens self-calibration from the sequence's
// frames. Without --trajectory, a frames-only odometry pass gives the initial poses. Writes DIR/calib.txt
// (for `eds run --calib`) and DIR/calibration.json.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "commands.hpp"
#include "io/output_file.hpp"
#include "recording_options.hpp"
#include "sim/writer.hpp"
#include "system/lens_calibration.hpp"
#include "system/odometry.hpp"
#include "system/odometry_config_io.hpp"

namespace eds::app {

namespace {

struct CalibrateArgs {
  std::string sequence, out = "calib_out", trajectory, calib;
  RecordingArgs recording;
  double max_sigma_px = 0.25;
  LensCalibrationConfig cfg;
};

void runCalibrate(CalibrateArgs& a) {
  Sequence seq(a.sequence, a.recording.options());
  if (!a.calib.empty()) seq.setCamera(readCameraFile(a.calib), a.calib);
  if (!seq.hasFrames())
    throw std::invalid_argument(a.sequence + ": lens calibration needs frames (images.txt or a recording's)");
  const std::filesystem::path out(a.out);
  requireWritableDir(out);
  Trajectory T_w_c;
  if (!a.trajectory.empty()) {
    T_w_c = readTum(a.trajectory);
  } else {
    std::printf("no --trajectory: a frames-only odometry pass gives the initial poses\n");
    OdometryConfig ocfg = defaultOdometryConfig(seq.camera().width, seq.camera().height);
    ocfg.use_events = false;
    const OdometryResult r = runOdometry(seq, ocfg);
    if (!r.initialized) throw std::invalid_argument(a.sequence + ": the odometry pass never initialized");
    T_w_c = r.frames_refined;
  }
  const LensCalibrationReport rep = calibrateLens(seq, T_w_c, a.cfg);
  const LensRefineResult& r = rep.result;
  sim::writeEcdCalib(out / "calib.txt", r.camera);
  Trajectory refined;
  for (std::size_t i = 0; i < r.T_w_c.size(); ++i)
    if (r.T_w_c[i]) refined.push_back({seq.frames()[i].t, *r.T_w_c[i]});
  writeTum(out / "trajectory_ba.txt", refined);
  const CameraModel& c0 = seq.camera();
  nlohmann::json j;
  auto cam = [](const CameraModel& c) {
    return nlohmann::json{{"fx", c.fx},   {"fy", c.fy},   {"cx", c.cx},   {"cy", c.cy},  {"k1", c.k[0]},
                          {"k2", c.k[1]}, {"p1", c.k[2]}, {"p2", c.k[3]}, {"k3", c.k[4]}};
  };
  j["given"] = cam(c0);
  j["refined"] = cam(r.camera);
  j["frames"] = rep.frames;
  j["posed_frames"] = rep.posed_frames;
  j["tracks"] = rep.tracks;
  j["mean_track_length"] = rep.mean_track_length;
  j["tracks_used"] = r.tracks_used;
  j["observations"] = r.observations;
  j["rms_given_px"] = r.rms_fixed_px;
  j["rms_refined_px"] = r.rms_refined_px;
  j["converged"] = r.converged;
  j["lens_sigma_px"] = std::isfinite(r.lens_sigma_px) ? nlohmann::json(r.lens_sigma_px) : nlohmann::json();
  j["lens_sigma_covariance_px"] =
      std::isfinite(r.lens_sigma_cov_px) ? nlohmann::json(r.lens_sigma_cov_px) : nlohmann::json();
  j["lens_sigma_split_px"] = r.lens_sigma_split_px;
  j["k_sigma"] = r.k_sigma;
  const bool determined = std::isfinite(r.lens_sigma_px) && r.lens_sigma_px <= a.max_sigma_px;
  j["determined"] = determined;
  writeTextFile(out / "calibration.json", j.dump(2) + "\n");
  std::printf("%zu of %zu frames posed; %zu tracks (mean length %.1f frames), %zu used, %zu observations\n",
              rep.posed_frames, rep.frames, rep.tracks, rep.mean_track_length, r.tracks_used, r.observations);
  std::printf("reprojection RMS: %.3f px with the given lens, %.3f px refined%s\n", r.rms_fixed_px,
              r.rms_refined_px, r.converged ? "" : " (solver stopped before converging)");
  std::printf("k1 k2 p1 p2 k3: given  %+.5f %+.5f %+.6f %+.6f %+.5f\n", c0.k[0], c0.k[1], c0.k[2], c0.k[3],
              c0.k[4]);
  std::printf("               refined %+.5f %+.5f %+.6f %+.6f %+.5f\n", r.camera.k[0], r.camera.k[1],
              r.camera.k[2], r.camera.k[3], r.camera.k[4]);
  std::printf("               sigma   %.5f %.5f %.6f %.6f %.5f\n", r.k_sigma[0], r.k_sigma[1], r.k_sigma[2],
              r.k_sigma[3], r.k_sigma[4]);
  std::printf(
      "lens uncertainty at the image border: %.2f px from the covariance, %.2f px from %d groups of tracks\n",
      r.lens_sigma_cov_px, r.lens_sigma_split_px, a.cfg.refine.split_groups);
  if (!std::isfinite(r.lens_sigma_px))
    std::printf("warning: the lens's uncertainty could not be computed: the refined lens is unchecked\n");
  else if (!determined)
    std::printf(
        "warning: the refined lens is uncertain by %.2f px at the image border (more than %.2f px): this\n"
        "         sequence does not determine it; keep the given calibration\n",
        r.lens_sigma_px, a.max_sigma_px);
  else
    std::printf("the refined lens is determined to %.2f px at the image border\n", r.lens_sigma_px);
  if (a.cfg.refine.refine_projection)
    std::printf("fx fy cx cy: given %.3f %.3f %.3f %.3f, refined %.3f %.3f %.3f %.3f\n", c0.fx, c0.fy, c0.cx,
                c0.cy, r.camera.fx, r.camera.fy, r.camera.cx, r.camera.cy);
  std::printf(
      "wrote %s/{calib.txt, trajectory_ba.txt, calibration.json} (use: eds run %s --calib %s/calib.txt)\n",
      a.out.c_str(), a.sequence.c_str(), a.out.c_str());
}

}  // namespace

void addCalibrateCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "calibrate",
      "Refine the lens distortion from the sequence's frames (feature tracks + bundle adjustment)");
  auto a = std::make_shared<CalibrateArgs>();
  cmd->add_option("sequence", a->sequence,
                  "Sequence folder or recording file (needs frames and a calibration to start from)")
      ->required();
  cmd->add_option("--calib", a->calib, "The calibration to start from instead of the sequence's own")
      ->check(CLI::ExistingFile);
  addRecordingOptions(cmd, a->recording);
  cmd->add_option("--out", a->out, "Output folder")->capture_default_str();
  cmd->add_option("--trajectory", a->trajectory,
                  "Initial poses (TUM, e.g. trajectory_frames.txt of `eds run`); default: a frames-only run")
      ->check(CLI::ExistingFile);
  LensRefineConfig& r = a->cfg.refine;
  cmd->add_flag("!--fixed-radial", r.refine_radial, "Keep k1, k2 as given");
  cmd->add_flag("--refine-k3", r.refine_k3, "Also refine k3");
  cmd->add_flag("--refine-tangential", r.refine_tangential, "Also refine p1, p2");
  cmd->add_flag("--refine-projection", r.refine_projection,
                "Also refine fx, fy, cx, cy (needs rotation in the motion; a slide does not observe them)");
  cmd->add_option("--huber", r.huber_px, "Huber threshold, px")->capture_default_str();
  cmd->add_option(
         "--max-sigma", a->max_sigma_px,
         "Largest uncertainty at the image border (px) for which the refined lens counts as determined")
      ->capture_default_str();
  cmd->add_option("--max-features", a->cfg.tracks.max_features, "Features tracked at once")
      ->capture_default_str();
  cmd->callback([a] { runCalibrate(*a); });
}

}  // namespace eds::app
