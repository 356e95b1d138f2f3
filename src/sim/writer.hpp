#pragma once
// Writes a simulated sequence in the ECD folder layout (what io/sequence.hpp reads): events.txt or
// events.txt.gz, images.txt + images/, depth/ (uint16 mm), calib.txt, groundtruth.txt.
#include <cstdio>
#include <filesystem>
#include <vector>

#include "core/camera.hpp"
#include "sim/simulator.hpp"

namespace eds::sim {

// A fault of the frames only (the events see the true scene): frames with times in [t0, t1) have their
// exposure scaled by `gain` and clipped, as a hand over the lens (gain 0.05) or a blown-out exposure
// (gain 4) would leave them.
struct FrameGain {
  TimeNs t0 = 0, t1 = 0;
  double gain = 1.0;
};

class EcdWriter : public SimSink {
 public:
  // Creates `dir` (and images/, depth/). Throws InputError if it cannot.
  EcdWriter(const std::filesystem::path& dir, bool gzip, bool write_depth);
  ~EcdWriter() override;
  void onEvents(const EventArray& events) override;
  void onFrame(TimeNs t, const cv::Mat& intensity, const cv::Mat& depth) override;
  // Flushes and closes the event file and images.txt; call once at the end.
  void finish();
  void setFrameGains(std::vector<FrameGain> gains) { frame_gains_ = std::move(gains); }

 private:
  void flushText();
  std::filesystem::path dir_;
  bool write_depth_;
  std::FILE* events_ = nullptr;
  void* gz_ = nullptr;
  std::FILE* images_ = nullptr;
  std::vector<char> text_;
  std::size_t frame_index_ = 0;
  std::vector<FrameGain> frame_gains_;
};

// calib.txt: `fx fy cx cy k1 k2 p1 p2 k3` (radtan or none only: the ECD line has no other model).
void writeEcdCalib(const std::filesystem::path& file, const CameraModel& camera);
// camchain.yaml (Kalibr) for any model, with resolution: what io/sequence.hpp prefers to calib.txt.
void writeKalibrCamchain(const std::filesystem::path& file, const CameraModel& camera);
// The rate simulated sequences write their ground truth at. Trajectory evaluation pairs each pose with
// the nearest ground-truth stamp without interpolating (rpg_trajectory_evaluation's convention): at
// 200 Hz an event-rate pose was compared with the truth 1.3 ms away in the median, which at hand-held
// speeds was most of its measured error. Frame times fall on this grid for rates that divide it.
constexpr double kGroundTruthRateHz = 1000.0;

// groundtruth.txt at `rate_hz` over [t0, t1] from the motion.
void writeGroundTruth(const std::filesystem::path& file, const Motion& motion, TimeNs t0, TimeNs t1,
                      double rate_hz);

}  // namespace eds::sim
