#include "io/kalibr.hpp"

#include <yaml-cpp/yaml.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <utility>

#include "core/error.hpp"

namespace eds {
namespace {

// 1-based line of a node, 0 when yaml-cpp has none (a node created in memory).
std::size_t lineOf(const YAML::Mark& mark) {
  return mark.line >= 0 ? static_cast<std::size_t>(mark.line) + 1 : 0;
}

// Parses one camera entry; every error names the file and the line of the offending node.
class CameraParser {
 public:
  CameraParser(const std::string& path, std::string camera) : path_(path), camera_(std::move(camera)) {}

  KalibrCamera parse(const YAML::Node& node) {
    if (!node.IsMap()) fail(node, "is not a mapping of keys");
    KalibrCamera cam;
    cam.name = camera_;

    const std::string model = text(require(node, "camera_model"), "camera_model");
    if (model != "pinhole") {
      fail(node["camera_model"], "unsupported camera_model '" + model + "' (only pinhole)");
    }
    const YAML::Node intr = require(node, "intrinsics");
    const std::vector<double> k = numbers(intr, "intrinsics");
    if (k.size() != 4) fail(intr, "intrinsics must have 4 values [fu, fv, pu, pv]");
    if (k[0] <= 0 || k[1] <= 0) fail(intr, "focal lengths must be positive");
    cam.fx = k[0];
    cam.fy = k[1];
    cam.cx = k[2];
    cam.cy = k[3];

    const YAML::Node res = require(node, "resolution");
    if (!res.IsSequence() || res.size() != 2) fail(res, "resolution must be [width, height]");
    cam.width = positiveInt(res[0], "resolution width");
    cam.height = positiveInt(res[1], "resolution height");

    const YAML::Node dist_model = require(node, "distortion_model");
    cam.distortion_model = text(dist_model, "distortion_model");
    const YAML::Node coeffs = node["distortion_coeffs"];
    if (coeffs) cam.distortion_coeffs = numbers(coeffs, "distortion_coeffs");
    const std::size_t count = cam.distortion_coeffs.size();
    const YAML::Node& where = coeffs ? coeffs : node;
    if (cam.distortion_model == "radtan") {
      if (!coeffs) require(node, "distortion_coeffs");
      if (count != 4 && count != 5) {
        fail(where, "radtan needs 4 or 5 distortion_coeffs (k1 k2 p1 p2 [k3]), got " + std::to_string(count));
      }
    } else if (cam.distortion_model == "equidistant") {
      if (!coeffs) require(node, "distortion_coeffs");
      if (count != 4) {
        fail(where, "equidistant needs 4 distortion_coeffs (k1 k2 k3 k4), got " + std::to_string(count));
      }
    } else if (cam.distortion_model == "none") {
      if (count != 0) fail(where, "distortion_model none takes no distortion_coeffs");
    } else {
      fail(dist_model,
           "unknown distortion_model '" + cam.distortion_model + "' (radtan, equidistant or none)");
    }

    if (const YAML::Node t = node["T_cn_cnm1"]) cam.T_cn_cnm1 = transform(t, "T_cn_cnm1");
    if (const YAML::Node t = node["T_cam_imu"]) cam.T_cam_imu = transform(t, "T_cam_imu");
    return cam;
  }

 private:
  [[noreturn]] void fail(const YAML::Node& node, const std::string& what) const {
    throw InputError(path_, lineOf(node.Mark()), camera_ + ": " + what);
  }

  YAML::Node require(const YAML::Node& parent, const char* key) const {
    YAML::Node value = parent[key];
    if (!value) fail(parent, std::string("missing key '") + key + "'");
    return value;
  }

  std::string text(const YAML::Node& node, const std::string& what) const {
    if (!node.IsScalar()) fail(node, what + " must be a word");
    return node.Scalar();
  }

  double number(const YAML::Node& node, const std::string& what) const {
    double v = 0;
    // yaml-cpp throws for text that is not a number; .nan and .inf parse and are checked below.
    try {
      v = node.as<double>();
    } catch (const YAML::Exception&) {
      fail(node, what + ": '" + (node.IsScalar() ? node.Scalar() : "") + "' is not a number");
    }
    if (!std::isfinite(v)) fail(node, what + " is not finite");
    return v;
  }

  std::vector<double> numbers(const YAML::Node& node, const std::string& what) const {
    if (!node.IsSequence()) fail(node, what + " must be a list of numbers");
    std::vector<double> out;
    out.reserve(node.size());
    for (std::size_t i = 0; i < node.size(); ++i) {
      out.push_back(number(node[i], what + "[" + std::to_string(i) + "]"));
    }
    return out;
  }

  int positiveInt(const YAML::Node& node, const std::string& what) const {
    int v = 0;
    try {
      v = node.as<int>();
    } catch (const YAML::Exception&) {
      fail(node, what + " is not an integer");
    }
    if (v <= 0) fail(node, what + " must be positive");
    return v;
  }

  // A rigid transform as 4 rows of 4: the last row must be [0 0 0 1] and the rotation orthonormal,
  // which also catches a matrix written transposed or with a row missing.
  Eigen::Matrix4d transform(const YAML::Node& node, const std::string& what) const {
    if (!node.IsSequence() || node.size() != 4) fail(node, what + " must have 4 rows");
    Eigen::Matrix4d m;
    for (int r = 0; r < 4; ++r) {
      const std::vector<double> row = numbers(node[r], what + " row " + std::to_string(r));
      if (row.size() != 4) fail(node[r], what + " row " + std::to_string(r) + " needs 4 values");
      for (int c = 0; c < 4; ++c) m(r, c) = row[static_cast<std::size_t>(c)];
    }
    if (!m.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1), 1e-9)) {
      fail(node, what + ": last row must be [0, 0, 0, 1]");
    }
    const Eigen::Matrix3d r = m.topLeftCorner<3, 3>();
    if ((r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-3 ||
        r.determinant() < 0) {
      fail(node, what + ": the rotation part is not a rotation matrix");
    }
    return m;
  }

  const std::string& path_;
  std::string camera_;
};

YAML::Node loadFile(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError(path, "file does not exist");
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::ParserException& e) {
    throw InputError(path, lineOf(e.mark), "malformed YAML: " + e.msg);
  } catch (const YAML::Exception& e) {
    throw InputError(path, lineOf(e.mark), "cannot read YAML: " + e.msg);
  }
  if (!root.IsMap()) throw InputError(path, "not a Kalibr camchain (expected cam0: ...)");
  return root;
}

}  // namespace

KalibrCamera readKalibrCamera(const std::string& path, const std::string& camera) {
  const YAML::Node root = loadFile(path);
  const YAML::Node node = root[camera];
  if (!node) throw InputError(path, "no camera '" + camera + "' in the camchain");
  return CameraParser(path, camera).parse(node);
}

KalibrCamera readDsecCamera(const std::string& path, const std::string& camera) {
  const YAML::Node root = loadFile(path);
  const YAML::Node intrinsics = root["intrinsics"];
  if (!intrinsics || !intrinsics.IsMap())
    throw InputError(path, "not a DSEC cam_to_cam.yaml (no intrinsics map)");
  const YAML::Node node = intrinsics[camera];
  if (!node) throw InputError(path, "no camera '" + camera + "' under intrinsics");
  if (!node.IsMap()) throw InputError(path, lineOf(node.Mark()), "camera '" + camera + "' is not a map");
  // DSEC names Kalibr's `intrinsics` list `camera_matrix`; the rest is Kalibr's.
  YAML::Node kalibr = YAML::Clone(node);
  if (kalibr["camera_matrix"]) kalibr["intrinsics"] = kalibr["camera_matrix"];
  return CameraParser(path, camera).parse(kalibr);
}

bool isDsecCamToCam(const std::string& path) {
  try {
    const YAML::Node root = YAML::LoadFile(path);
    return root.IsMap() && root["intrinsics"] && root["intrinsics"].IsMap();
  } catch (const YAML::Exception&) {
    return false;
  }
}

std::vector<KalibrCamera> readKalibrCamchain(const std::string& path) {
  const YAML::Node root = loadFile(path);
  std::vector<KalibrCamera> cams;
  for (int i = 0;; ++i) {
    const std::string name = "cam" + std::to_string(i);
    const YAML::Node node = root[name];
    if (!node) break;
    cams.push_back(CameraParser(path, name).parse(node));
  }
  if (cams.empty()) throw InputError(path, "no camera entries (expected cam0: ...)");
  return cams;
}

}  // namespace eds
