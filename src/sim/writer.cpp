#include "sim/writer.hpp"

#include <zlib.h>

#include <cmath>
#include <cstring>
#include <opencv2/imgcodecs.hpp>

#include "core/error.hpp"
#include "io/output_file.hpp"

namespace eds::sim {

namespace fs = std::filesystem;

EcdWriter::EcdWriter(const fs::path& dir, bool gzip, bool write_depth)
    : dir_(dir), write_depth_(write_depth) {
  std::error_code ec;
  fs::create_directories(dir / "images", ec);
  if (ec) throw InputError(dir.string(), "cannot create output folder: " + ec.message());
  if (write_depth) fs::create_directories(dir / "depth", ec);
  if (gzip) {
    gz_ = gzopen((dir / "events.txt.gz").c_str(), "wb1");  // level 1: text compresses ~4x even so
    if (!gz_) throw InputError((dir / "events.txt.gz").string(), "cannot open for writing");
  } else {
    events_ = std::fopen((dir / "events.txt").c_str(), "wb");
    if (!events_) throw InputError((dir / "events.txt").string(), "cannot open for writing");
  }
  images_ = std::fopen((dir / "images.txt").c_str(), "wb");
  if (!images_) throw InputError((dir / "images.txt").string(), "cannot open for writing");
  text_.reserve(1 << 22);
}

EcdWriter::~EcdWriter() {
  if (events_ || gz_ || images_) {
    try {
      finish();
    } catch (...) {
      // Destructors must not throw; finish() reports errors when called explicitly.
    }
  }
}

void EcdWriter::flushText() {
  if (text_.empty()) return;
  if (gz_) {
    if (gzwrite(static_cast<gzFile>(gz_), text_.data(), static_cast<unsigned>(text_.size())) == 0)
      throw InputError((dir_ / "events.txt.gz").string(), "write failed");
  } else if (std::fwrite(text_.data(), 1, text_.size(), events_) != text_.size()) {
    throw InputError((dir_ / "events.txt").string(), "write failed (disk full?)");
  }
  text_.clear();
}

namespace {
// Appends the decimal digits of v (>= 0), zero-padded to `width`.
char* putUint(char* p, std::uint64_t v, int width = 0) {
  char tmp[24];
  int n = 0;
  do {
    tmp[n++] = static_cast<char>('0' + v % 10);
    v /= 10;
  } while (v);
  while (n < width) tmp[n++] = '0';
  while (n) *p++ = tmp[--n];
  return p;
}
}  // namespace

void EcdWriter::onEvents(const EventArray& events) {
  // "t x y p" with 9 decimals, formatted by hand: snprintf would cost more than the simulation.
  char line[64];
  for (std::size_t i = 0; i < events.size(); ++i) {
    char* p = putUint(line, static_cast<std::uint64_t>(events.t[i] / kNsPerSec));
    *p++ = '.';
    p = putUint(p, static_cast<std::uint64_t>(events.t[i] % kNsPerSec), 9);
    *p++ = ' ';
    p = putUint(p, events.x[i]);
    *p++ = ' ';
    p = putUint(p, events.y[i]);
    *p++ = ' ';
    *p++ = events.p[i] > 0 ? '1' : '0';
    *p++ = '\n';
    text_.insert(text_.end(), line, p);
  }
  if (text_.size() > (1u << 22) - 4096) flushText();
}

void EcdWriter::onFrame(TimeNs t, const cv::Mat& intensity, const cv::Mat& depth) {
  char name[64];
  std::snprintf(name, sizeof name, "frame_%08zu.png", frame_index_++);
  double gain = 1.0;
  for (const FrameGain& g : frame_gains_)
    if (t >= g.t0 && t < g.t1) gain *= g.gain;
  cv::Mat img8;
  intensity.convertTo(img8, CV_8U, 255.0 * gain);  // rounds and saturates
  if (!cv::imwrite((dir_ / "images" / name).string(), img8))
    throw InputError((dir_ / "images" / name).string(), "cannot write image");
  if (write_depth_) {
    cv::Mat mm;
    depth.convertTo(mm, CV_16U, 1000.0);
    if (!cv::imwrite((dir_ / "depth" / name).string(), mm))
      throw InputError((dir_ / "depth" / name).string(), "cannot write depth map");
  }
  std::fprintf(images_, "%lld.%09lld images/%s\n", static_cast<long long>(t / kNsPerSec),
               static_cast<long long>(t % kNsPerSec), name);
}

void EcdWriter::finish() {
  flushText();
  if (gz_) {
    if (gzclose(static_cast<gzFile>(gz_)) != Z_OK)
      throw InputError((dir_ / "events.txt.gz").string(), "close failed");
    gz_ = nullptr;
  }
  if (events_) {
    if (std::fclose(events_) != 0) throw InputError((dir_ / "events.txt").string(), "close failed");
    events_ = nullptr;
  }
  if (images_) {
    std::fclose(images_);
    images_ = nullptr;
  }
}

void writeEcdCalib(const fs::path& file, const CameraModel& c) {
  if (c.distortion == Distortion::kEquidistant)
    throw std::invalid_argument("calib.txt cannot hold an equidistant model; write a Kalibr camchain");
  OutputFile out(file);
  std::FILE* f = std::fopen(out.temporary().c_str(), "w");
  if (!f) throw InputError(file.string(), "cannot open for writing");
  std::fprintf(f, "%.9f %.9f %.9f %.9f %.12g %.12g %.12g %.12g %.12g\n", c.fx, c.fy, c.cx, c.cy, c.k[0],
               c.k[1], c.k[2], c.k[3], c.k[4]);
  if (std::fclose(f) != 0) throw InputError(file.string(), "write failed");
  out.commit();
}

void writeKalibrCamchain(const fs::path& file, const CameraModel& c) {
  OutputFile out(file);
  std::FILE* f = std::fopen(out.temporary().c_str(), "w");
  if (!f) throw InputError(file.string(), "cannot open for writing");
  const int n = c.distortion == Distortion::kRadTan ? 5 : c.distortion == Distortion::kEquidistant ? 4 : 0;
  std::fprintf(f, "cam0:\n  camera_model: pinhole\n  intrinsics: [%.9f, %.9f, %.9f, %.9f]\n", c.fx, c.fy,
               c.cx, c.cy);
  std::fprintf(f, "  distortion_model: %s\n  distortion_coeffs: [", toString(c.distortion));
  for (int i = 0; i < n; ++i) std::fprintf(f, i ? ", %.12g" : "%.12g", c.k[i]);
  std::fprintf(f, "]\n  resolution: [%d, %d]\n", c.width, c.height);
  if (std::fclose(f) != 0) throw InputError(file.string(), "write failed");
  out.commit();
}

void writeGroundTruth(const fs::path& file, const Motion& motion, TimeNs t0, TimeNs t1, double rate_hz) {
  Trajectory gt;
  const auto period = static_cast<TimeNs>(std::llround(1e9 / rate_hz));
  for (TimeNs t = t0; t <= t1; t += period) gt.push_back({t, motion.pose(t)});
  writeTum(file, gt);
}

}  // namespace eds::sim
