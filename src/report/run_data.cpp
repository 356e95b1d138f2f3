#include "report/run_data.hpp"

#include <algorithm>
#include <fstream>
#include <stdexcept>

#include "core/error.hpp"
#include "system/event_snapshots.hpp"

namespace eds::report {

namespace {

nlohmann::json readJson(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file.string(), "missing or unreadable");
  try {
    return nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(file.string(), std::string("not valid JSON: ") + e.what());
  }
}

// Unsorted stamps are allowed, as `eds eval` allows them.
Trajectory readSorted(const std::filesystem::path& file, std::vector<std::size_t>* segments = nullptr) {
  Trajectory t = readTum(file, /*allow_unsorted=*/true, segments);
  // Sorting would move poses across their segments' marks.
  if (!segments || segments->empty())
    std::stable_sort(t.begin(), t.end(),
                     [](const StampedPose& a, const StampedPose& b) { return a.t < b.t; });
  return t;
}

Trajectory readIfExists(const std::filesystem::path& file, std::vector<std::size_t>* segments = nullptr) {
  return std::filesystem::exists(file) ? readTum(file, false, segments) : Trajectory{};
}

}  // namespace

RunData loadRun(const std::filesystem::path& path) {
  RunData r;
  r.dir = path;
  r.name = path.filename().string();
  if (r.name.empty()) r.name = path.parent_path().filename().string();
  if (std::filesystem::is_regular_file(path)) {
    r.frames = readSorted(path, &r.frame_segments);
    if (r.frames.empty()) throw InputError(path.string(), "no pose in the trajectory");
    return r;
  }
  if (!std::filesystem::is_directory(path))
    throw InputError(path.string(), "no such run folder or trajectory file");
  if (!std::filesystem::exists(path / "summary.json"))
    throw InputError((path / "summary.json").string(), "missing: give the output folder of `eds run`");
  r.is_run = true;
  r.summary = readJson(path / "summary.json");
  if (std::filesystem::exists(path / "timings.json")) r.timings = readJson(path / "timings.json");
  r.events = readIfExists(path / "trajectory_events.txt", &r.event_segments);
  r.frames = readIfExists(path / "trajectory_frames.txt", &r.frame_segments);
  r.keyframes = readIfExists(path / "keyframes.txt");
  if (std::filesystem::exists(path / "map.ply")) r.map = readPly(path / "map.ply");
  r.snapshots = readEventSnapshots(path);
  return r;
}

std::optional<Trajectory> findGroundTruth(const RunData& run, const std::filesystem::path& gt_file) {
  if (!gt_file.empty()) {
    Trajectory gt = readSorted(gt_file);
    if (gt.empty()) throw InputError(gt_file.string(), "no pose in the ground truth");
    return gt;
  }
  if (run.is_run && std::filesystem::exists(run.dir / "groundtruth.txt"))
    return readTum(run.dir / "groundtruth.txt");
  return std::nullopt;
}

std::vector<TrajectoryEval> evaluateRun(const RunData& run, const Trajectory& gt) {
  std::vector<TrajectoryEval> out;
  const auto add = [&](const std::string& label, const Trajectory& est,
                       const std::vector<std::size_t>& segments) {
    if (est.size() < 3) return;
    eval::EvalConfig cfg;
    try {
      TrajectoryEval e{label, est, eval::evaluateAte(est, gt, cfg, segments), {}};
      e.rpe = eval::evaluateRpe(est, gt, e.ate, cfg);
      out.push_back(std::move(e));
    } catch (const std::invalid_argument&) {
      // no pose near a ground-truth stamp: nothing to show for this trajectory
    }
  };
  add("event-rate poses", run.events, run.event_segments);
  add(run.is_run ? "frame poses" : "poses", run.frames, run.frame_segments);
  return out;
}

}  // namespace eds::report
