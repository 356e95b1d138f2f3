// `eds convert PATH --out OUT.h5`: any recording eds reads, rewritten in eds's own HDF5 layout
// (events, frames, calibration, ground truth, IMU, triggers), the fastest input to read again and
// one that keeps every time to the nanosecond.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>

#include "commands.hpp"
#include "io/convert.hpp"
#include "recording_options.hpp"

namespace eds::app {

namespace {

struct ConvertArgs {
  std::string path, out, calib;
  bool compress = false;
  RecordingArgs recording;
};

void runConvert(const ConvertArgs& a) {
  const auto start = std::chrono::steady_clock::now();
  Sequence seq(a.path, a.recording.options());
  if (!a.calib.empty()) seq.setCamera(readCameraFile(a.calib), a.calib);
  const ConvertCounts n = convertToEdsHdf5(seq, a.out, a.compress);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf(
      "wrote %s (%.1f MB in %.2f s): %zu events, %zu frames, %s, %zu ground-truth poses, %zu IMU "
      "samples, %zu triggers\n",
      a.out.c_str(), static_cast<double>(std::filesystem::file_size(a.out)) / 1e6, seconds, n.events,
      n.frames, n.calibration ? "calibration" : "no calibration", n.ground_truth, n.imu, n.triggers);
}

}  // namespace

void addConvertCommand(CLI::App& app) {
  auto* cmd =
      app.add_subcommand("convert",
                         "Rewrite a sequence or recording as one eds HDF5 file (events, frames, calibration, "
                         "ground truth, IMU, triggers) that `eds run` reads fastest");
  auto a = std::make_shared<ConvertArgs>();
  cmd->add_option("path", a->path, "Sequence folder or recording file (any format `eds info` reads)")
      ->required();
  cmd->add_option("--out", a->out, "The HDF5 file to write")->required();
  cmd->add_option("--calib", a->calib, "Calibration to store instead of the recording's own")
      ->check(CLI::ExistingFile);
  cmd->add_flag("--compress", a->compress,
                "gzip (level 1) the events and frames: about a third of the size, slower to read");
  addRecordingOptions(cmd, a->recording);
  cmd->callback([a] { runConvert(*a); });
}

}  // namespace eds::app
