#include "io/trajectory_io.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string_view>

#include "core/error.hpp"
#include "io/line_reader.hpp"
#include "io/output_file.hpp"
#include "io/text_parse.hpp"

namespace eds {
namespace {

// Parses a double field; from_chars is locale-independent and exact (shortest round trip).
const char* parseDouble(const char* p, const char* end, double& v) {
  p = text::skipSpaces(p, end);
  if (p < end && *p == '+') ++p;
  const auto r = std::from_chars(p, end, v);
  if (r.ec != std::errc() || !text::atFieldEnd(r.ptr, end)) return nullptr;
  return r.ptr;
}

constexpr std::string_view kSegmentMark = "# segment ";

bool isCommentOrBlank(std::string_view line) {
  const char* p = text::skipSpaces(line.data(), line.data() + line.size());
  return p == line.data() + line.size() || *p == '#';
}

}  // namespace

Trajectory readTum(const std::filesystem::path& file, bool allow_unsorted,
                   std::vector<std::size_t>* segment_starts) {
  LineReader reader(file);
  Trajectory traj;
  std::string_view line;
  while (reader.next(line)) {
    if (isCommentOrBlank(line)) {
      if (segment_starts && line.starts_with(kSegmentMark)) segment_starts->push_back(traj.size());
      continue;
    }
    const char* p = line.data();
    const char* end = p + line.size();
    const std::size_t ln = reader.lineNumber();
    p = text::skipSpaces(p, end);
    TimeNs t = 0;
    const char* q = text::parseSecondsNs(p, end, t);
    if (!q || !text::atFieldEnd(q, end)) {
      // Fall back to a general number (exponent notation); negative times are rejected.
      double ts = 0;
      q = parseDouble(p, end, ts);
      if (!q || !std::isfinite(ts))
        throw InputError(reader.fileName(), ln, "malformed timestamp in '" + std::string(line) + "'");
      if (ts < 0) throw InputError(reader.fileName(), ln, "negative timestamp");
      t = fromSeconds(ts);
    }
    p = q;
    double v[7];
    for (int i = 0; i < 7; ++i) {
      p = parseDouble(p, end, v[i]);
      if (!p)
        throw InputError(reader.fileName(), ln,
                         "expected 8 numbers 't tx ty tz qx qy qz qw', got '" + std::string(line) + "'");
      if (!std::isfinite(v[i])) throw InputError(reader.fileName(), ln, "non-finite value");
    }
    if (text::skipSpaces(p, end) != end)
      throw InputError(reader.fileName(), ln, "more than 8 fields in '" + std::string(line) + "'");
    const Quat q_w_c(v[6], v[3], v[4], v[5]);  // file order is x y z w
    const double qn = q_w_c.norm();
    if (qn < 1e-6) throw InputError(reader.fileName(), ln, "zero quaternion");
    if (std::abs(qn - 1.0) > 1e-2)
      throw InputError(reader.fileName(), ln, "quaternion is not unit (norm " + std::to_string(qn) + ")");
    if (!allow_unsorted && !traj.empty() && t < traj.back().t)
      throw InputError(reader.fileName(), ln,
                       "timestamp decreases (" + std::to_string(toSeconds(t)) + " s after " +
                           std::to_string(toSeconds(traj.back().t)) + " s)");
    traj.push_back({t, SE3(q_w_c, Vec3(v[0], v[1], v[2]))});
  }
  return traj;
}

void writeTum(const std::filesystem::path& file, const Trajectory& traj,
              const std::vector<std::size_t>& segment_starts) {
  OutputFile out(file);
  std::FILE* f = std::fopen(out.temporary().c_str(), "w");
  if (!f) throw InputError(file.string(), "cannot open for writing");
  std::fprintf(f, "# t tx ty tz qx qy qz qw (T_w_c, camera-to-world)\n");
  std::size_t next_segment = 0;
  for (std::size_t i = 0; i < traj.size(); ++i) {
    for (; next_segment < segment_starts.size() && segment_starts[next_segment] <= i; ++next_segment)
      std::fprintf(f, "%.*s%zu: a new map from here on (its own world frame and scale)\n",
                   static_cast<int>(kSegmentMark.size()), kSegmentMark.data(), next_segment + 1);
    const StampedPose& s = traj[i];
    const Vec3& p = s.T_w_c.translation();
    const Quat& q = s.T_w_c.quaternion();
    const long long sec = s.t / kNsPerSec;
    const long long ns = s.t % kNsPerSec;
    std::fprintf(f, "%lld.%09lld %.9f %.9f %.9f %.9f %.9f %.9f %.9f\n", sec, ns, p.x(), p.y(), p.z(), q.x(),
                 q.y(), q.z(), q.w());
  }
  if (std::fclose(f) != 0) throw InputError(file.string(), "write failed");
  out.commit();
}

std::vector<std::size_t> indicesFrom(const Trajectory& traj, const std::vector<TimeNs>& times) {
  std::vector<std::size_t> out;
  for (const TimeNs t : times)
    out.push_back(std::lower_bound(traj.begin(), traj.end(), t,
                                   [](const StampedPose& p, TimeNs u) { return p.t < u; }) -
                  traj.begin());
  return out;
}

}  // namespace eds
