#pragma once
// Kalibr camchain YAML (camchain-*.yaml): per camera `camera_model` (pinhole), `intrinsics`
// [fu, fv, pu, pv], `distortion_model` (radtan: k1 k2 p1 p2 [k3]; equidistant: k1..k4; none),
// `distortion_coeffs`, `resolution` [w, h], optional `T_cn_cnm1` and `T_cam_imu` (4x4 rows).
#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

namespace eds {

struct KalibrCamera {
  std::string name;  // cam0, cam1, ...
  int width = 0;
  int height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  std::string distortion_model;  // "radtan", "equidistant" or "none"
  std::vector<double> distortion_coeffs;
  std::optional<Eigen::Matrix4d> T_cn_cnm1;  // this camera from the previous one in the chain
  std::optional<Eigen::Matrix4d> T_cam_imu;  // this camera from the IMU
};

// Reads one camera (default cam0). Throws InputError naming the file, and the line where the
// problem is, for a missing file, malformed YAML, missing keys or bad values.
KalibrCamera readKalibrCamera(const std::string& path, const std::string& camera = "cam0");

// Reads one camera of a DSEC cam_to_cam.yaml (`intrinsics: {cam0: {camera_matrix: [fx, fy, cx, cy],
// distortion_model, distortion_coeffs, resolution}, camRect0: ...}`); cam0 is the left event camera.
KalibrCamera readDsecCamera(const std::string& path, const std::string& camera = "cam0");
// True when the YAML file has DSEC's top-level `intrinsics` map (not a Kalibr camchain).
bool isDsecCamToCam(const std::string& path);

// Reads every camN entry (cam0, cam1, ... in order).
std::vector<KalibrCamera> readKalibrCamchain(const std::string& path);

}  // namespace eds
