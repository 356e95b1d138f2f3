#pragma once
// `eds report`: one self-contained HTML page (style, script, images and data inlined; nothing is
// fetched when it is opened) that shows a run: its summary, accuracy against ground truth,
// trajectories, errors over time, stage timings, keyframes with their depth, event frames next to the
// model's prediction, and an orbiting 3D view of the map; or several runs overlaid in one table.
#include <optional>
#include <string>
#include <vector>

#include "report/run_data.hpp"

namespace eds::report {

struct ReportInputs {
  std::vector<RunData> runs;  // one: that run's report; several: a comparison
  std::optional<Trajectory> gt;
  std::string gt_source;  // where the ground truth came from, for the page
};

std::string buildReport(const ReportInputs& in);

// The start of a report page: doctype, the inlined style sheet, the title as heading, eds's version.
std::string htmlPageStart(const std::string& title);

// Loads the runs (`eds run` folders or TUM files), takes the ground truth from `gt_file` or else the
// first run's groundtruth.txt, and writes the page to `out` (atomically). InputError naming the file
// for a run or ground truth that cannot be read.
void writeReport(const std::vector<std::filesystem::path>& runs, const std::filesystem::path& gt_file,
                 const std::filesystem::path& out);

}  // namespace eds::report
