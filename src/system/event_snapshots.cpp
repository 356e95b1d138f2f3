#include "system/event_snapshots.hpp"

#include <cmath>
#include <cstdio>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "io/line_reader.hpp"
#include "io/output_file.hpp"

namespace eds {

namespace {

std::filesystem::path snapshotFile(const std::filesystem::path& dir, std::size_t i, const char* what) {
  return numberedFile(dir, "ef_", i, 2, std::string("_") + what + ".png");
}

// Signed values to 16 bits around 32768; returns the scale (the largest magnitude, 1 for an empty image).
double encode(const cv::Mat& x, cv::Mat& out16) {
  double lo = 0, hi = 0;
  cv::minMaxLoc(x, &lo, &hi);
  const double scale = std::max(std::abs(lo), std::abs(hi)) > 0 ? std::max(std::abs(lo), std::abs(hi)) : 1.0;
  x.convertTo(out16, CV_16U, 32767.0 / scale, 32768.0);
  return scale;
}

cv::Mat decode(const std::filesystem::path& file, double scale) {
  const cv::Mat raw = cv::imread(file.string(), cv::IMREAD_UNCHANGED);
  if (raw.empty() || raw.type() != CV_16U)
    throw InputError(file.string(), "missing, unreadable or not a 16-bit image");
  cv::Mat x;
  raw.convertTo(x, CV_32F, scale / 32767.0, -32768.0 * scale / 32767.0);
  return x;
}

}  // namespace

void writeEventSnapshots(const std::filesystem::path& dir, const std::vector<EventFrameSnapshot>& shots) {
  if (shots.empty()) return;
  const std::filesystem::path sdir = dir / "event_frames";
  std::filesystem::create_directories(sdir);
  std::ostringstream index;
  index << "# t_ns kf_id correlation scale_delta scale_predicted\n";
  index.precision(12);
  for (std::size_t i = 0; i < shots.size(); ++i) {
    cv::Mat d16, p16;
    const double sd = encode(shots[i].delta, d16), sp = encode(shots[i].predicted, p16);
    writeImageFile(snapshotFile(sdir, i, "delta"), d16);
    writeImageFile(snapshotFile(sdir, i, "model"), p16);
    index << shots[i].t << " " << shots[i].kf_id << " " << shots[i].correlation << " " << sd << " " << sp
          << "\n";
  }
  writeTextFile(sdir / "index.txt", index.str());
}

std::vector<EventFrameSnapshot> readEventSnapshots(const std::filesystem::path& dir) {
  const std::filesystem::path sdir = dir / "event_frames";
  std::vector<EventFrameSnapshot> shots;
  if (!std::filesystem::is_directory(sdir)) return shots;
  LineReader reader(sdir / "index.txt");
  std::string_view line;
  while (reader.next(line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream in{std::string(line)};
    double sd = 0, sp = 0;
    EventFrameSnapshot s;
    if (!(in >> s.t >> s.kf_id >> s.correlation >> sd >> sp) || !(sd > 0) || !(sp > 0))
      throw InputError(
          (sdir / "index.txt").string(), reader.lineNumber(),
          "expected 't_ns kf_id correlation scale_delta scale_predicted', got '" + std::string(line) + "'");
    s.delta = decode(snapshotFile(sdir, shots.size(), "delta"), sd);
    s.predicted = decode(snapshotFile(sdir, shots.size(), "model"), sp);
    if (s.delta.size() != s.predicted.size())
      throw InputError(snapshotFile(sdir, shots.size(), "model").string(),
                       "size differs from the event frame's");
    shots.push_back(std::move(s));
  }
  return shots;
}

}  // namespace eds
