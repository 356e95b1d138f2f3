#pragma once
// A run's keyframes as a reference map for later tracking (`eds track --reference RUN_DIR`): every
// keyframe the run made, at its final pose, with its undistorted image and the window's points seen
// from it (inverse depths). Layout, under RUN_DIR/keyframes/:
//   camera.txt          fx fy cx cy of the undistorted pinhole grid the images and points are on
//   index.txt           one TUM line per keyframe (t, T_w_kf), in time order
//   kf_NNNNNN.png       the keyframe's image (8-bit), NNNNNN = its row in index.txt
//   kf_NNNNNN.txt       its points, `u v inv_depth` per line
#include <filesystem>
#include <vector>

#include "backend/sliding_window.hpp"
#include "core/camera.hpp"
#include "io/trajectory_io.hpp"
#include "map/keyframe.hpp"
#include "system/odometry.hpp"

namespace eds {

struct ReferenceRun {
  CameraModel pinhole;              // with the images' size
  std::vector<Keyframe> keyframes;  // image (CV_32F in [0, 1]), points (u, v, inv_depth), t, T_w_kf
};

// Writes the keyframes (sorted by time) under dir/keyframes/. Those without an image were written
// there by a ReferenceKeyframeWriter as they retired; their files are renamed to their rows. When a
// keyframe is in neither place (another listener took it), nothing is written and a warning says so.
void writeReferenceKeyframes(const std::filesystem::path& dir, const CameraModel& pinhole,
                             const std::vector<RetiredKeyframe>& keyframes);

// Writes each keyframe's image and points under dir/keyframes/ as the run retires it (named by its
// id until writeReferenceKeyframes gives them their rows), so that a long run does not hold them.
class ReferenceKeyframeWriter : public OdometryListener {
 public:
  explicit ReferenceKeyframeWriter(const std::filesystem::path& dir);
  bool onKeyframeRetired(const RetiredKeyframe& kf) override;

 private:
  std::filesystem::path kdir_;
};
// Reads dir/keyframes/; InputError naming the file (and line) for anything missing or malformed.
ReferenceRun readReferenceRun(const std::filesystem::path& dir);
// The parts, for readers that need only a few keyframes: the pinhole camera (size from the first
// image), the index (t, T_w_kf per keyframe), and keyframe i (row i of the index).
CameraModel readReferenceCamera(const std::filesystem::path& dir);
Trajectory readReferenceIndex(const std::filesystem::path& dir);
Keyframe readReferenceKeyframe(const std::filesystem::path& dir, const CameraModel& pinhole,
                               const Trajectory& index, std::size_t i);

}  // namespace eds
