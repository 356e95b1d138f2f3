#pragma once
// The page of a sensitivity study (`eds study`): what was run, a table of medians per level, and box
// plots of the translation and rotation errors of every pose, all seeds of a level together.
#include <string>

#include "study/sensitivity.hpp"

namespace eds::report {

std::string buildStudyReport(const study::StudyResult& result);

}  // namespace eds::report
