#include "system/reference_run.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "core/log.hpp"
#include "io/line_reader.hpp"
#include "io/output_file.hpp"
#include "io/sequence.hpp"
#include "io/text_parse.hpp"
#include "io/trajectory_io.hpp"

namespace eds {

namespace {

std::filesystem::path keyframeFile(const std::filesystem::path& dir, std::size_t i, const char* ext) {
  return numberedFile(dir, "kf_", i, 6, std::string(".") + ext);
}

std::filesystem::path retiredFile(const std::filesystem::path& kdir, int id, const char* ext) {
  return kdir / ("retired_" + std::to_string(id) + "." + ext);
}

void writeKeyframeFiles(const std::filesystem::path& png, const std::filesystem::path& txt,
                        const RetiredKeyframe& k) {
  writeImageFile(png, k.image);
  std::ostringstream pts;
  pts << "# u v inv_depth (pixels of the undistorted image; inverse depth in map units)\n";
  pts.precision(9);
  for (const KeyframePoint& p : k.points) pts << p.u << " " << p.v << " " << p.inv_depth << "\n";
  writeTextFile(txt, pts.str());
}

// A keyframe that ReferenceKeyframeWriter wrote as it retired: its files take the row's names.
void renameRetired(const std::filesystem::path& kdir, const RetiredKeyframe& k, std::size_t row) {
  for (const char* ext : {"png", "txt"})
    std::filesystem::rename(retiredFile(kdir, k.id, ext), keyframeFile(kdir, row, ext));
}

// Every keyframe either holds its image and points or was written by ReferenceKeyframeWriter; a
// listener of its own may have taken them elsewhere.
bool keyframesAvailable(const std::filesystem::path& kdir, const std::vector<RetiredKeyframe>& keyframes) {
  const auto written = [&](int id) {
    return std::filesystem::exists(retiredFile(kdir, id, "png")) &&
           std::filesystem::exists(retiredFile(kdir, id, "txt"));
  };
  for (const RetiredKeyframe& k : keyframes)
    if (k.image.empty() && !written(k.id)) {
      logf(LogLevel::kWarn, "keyframes/ not written: keyframe %d's image and points are not in the result",
           k.id);
      return false;
    }
  return true;
}

std::vector<KeyframePoint> readPoints(const std::filesystem::path& file, int width, int height) {
  LineReader reader(file);
  std::vector<KeyframePoint> pts;
  std::string_view line;
  while (reader.next(line)) {
    const char* p = text::skipSpaces(line.data(), line.data() + line.size());
    const char* end = line.data() + line.size();
    if (p == end || *p == '#') continue;
    double v[3];
    for (double& x : v) {
      p = text::skipSpaces(p, end);
      const auto r = std::from_chars(p, end, x);
      if (r.ec != std::errc() || !text::atFieldEnd(r.ptr, end) || !std::isfinite(x))
        throw InputError(file.string(), reader.lineNumber(),
                         "expected 'u v inv_depth', got '" + std::string(line) + "'");
      p = r.ptr;
    }
    if (v[0] < 0 || v[1] < 0 || v[0] > width - 1 || v[1] > height - 1 || !(v[2] > 0))
      throw InputError(file.string(), reader.lineNumber(),
                       "point outside the " + std::to_string(width) + "x" + std::to_string(height) +
                           " image or without a positive inverse depth");
    KeyframePoint kp;
    kp.u = static_cast<float>(v[0]), kp.v = static_cast<float>(v[1]), kp.inv_depth = v[2];
    pts.push_back(kp);
  }
  return pts;
}

}  // namespace

void writeReferenceKeyframes(const std::filesystem::path& dir, const CameraModel& pinhole,
                             const std::vector<RetiredKeyframe>& keyframes) {
  const std::filesystem::path kdir = dir / "keyframes";
  if (!keyframesAvailable(kdir, keyframes)) return;
  std::filesystem::create_directories(kdir);
  std::ostringstream cam;
  cam.precision(17);
  cam << pinhole.fx << " " << pinhole.fy << " " << pinhole.cx << " " << pinhole.cy << "\n";
  writeTextFile(kdir / "camera.txt", cam.str());
  Trajectory index;
  for (std::size_t i = 0; i < keyframes.size(); ++i) {
    const RetiredKeyframe& k = keyframes[i];
    index.push_back({k.t, k.T_w_kf});
    if (k.image.empty())
      renameRetired(kdir, k, i);
    else
      writeKeyframeFiles(keyframeFile(kdir, i, "png"), keyframeFile(kdir, i, "txt"), k);
  }
  writeTum(kdir / "index.txt", index);
}

ReferenceKeyframeWriter::ReferenceKeyframeWriter(const std::filesystem::path& dir)
    : kdir_(dir / "keyframes") {
  std::filesystem::create_directories(kdir_);
}

bool ReferenceKeyframeWriter::onKeyframeRetired(const RetiredKeyframe& kf) {
  writeKeyframeFiles(retiredFile(kdir_, kf.id, "png"), retiredFile(kdir_, kf.id, "txt"), kf);
  return true;
}

Trajectory readReferenceIndex(const std::filesystem::path& dir) {
  const std::filesystem::path kdir = dir / "keyframes";
  if (!std::filesystem::is_directory(kdir))
    throw InputError(kdir.string(), "no keyframes folder: give the output folder of `eds run`");
  Trajectory index = readTum(kdir / "index.txt");
  if (index.empty()) throw InputError((kdir / "index.txt").string(), "no keyframe");
  return index;
}

CameraModel readReferenceCamera(const std::filesystem::path& dir) {
  const std::filesystem::path kdir = dir / "keyframes";
  CameraModel pinhole = readEcdCalib(kdir / "camera.txt");
  if (pinhole.distortion != Distortion::kNone)
    throw InputError((kdir / "camera.txt").string(), "expected a pinhole camera 'fx fy cx cy'");
  const std::filesystem::path png = keyframeFile(kdir, 0, "png");
  const cv::Mat img8 = cv::imread(png.string(), cv::IMREAD_GRAYSCALE);
  if (img8.empty()) throw InputError(png.string(), "missing or unreadable keyframe image");
  pinhole.width = img8.cols, pinhole.height = img8.rows;
  return pinhole;
}

Keyframe readReferenceKeyframe(const std::filesystem::path& dir, const CameraModel& pinhole,
                               const Trajectory& index, std::size_t i) {
  const std::filesystem::path kdir = dir / "keyframes";
  const std::filesystem::path png = keyframeFile(kdir, i, "png");
  const cv::Mat img8 = cv::imread(png.string(), cv::IMREAD_GRAYSCALE);
  if (img8.empty()) throw InputError(png.string(), "missing or unreadable keyframe image");
  if (img8.cols != pinhole.width || img8.rows != pinhole.height)
    throw InputError(png.string(), "image size differs from the first keyframe's");
  Keyframe kf;
  kf.id = static_cast<int>(i);
  kf.t = index.at(i).t;
  kf.T_w_kf = index[i].T_w_c;
  img8.convertTo(kf.image, CV_32F, 1.0 / 255.0);
  kf.points = readPoints(keyframeFile(kdir, i, "txt"), img8.cols, img8.rows);
  return kf;
}

ReferenceRun readReferenceRun(const std::filesystem::path& dir) {
  ReferenceRun run;
  const Trajectory index = readReferenceIndex(dir);
  run.pinhole = readReferenceCamera(dir);
  for (std::size_t i = 0; i < index.size(); ++i)
    run.keyframes.push_back(readReferenceKeyframe(dir, run.pinhole, index, i));
  return run;
}

}  // namespace eds
