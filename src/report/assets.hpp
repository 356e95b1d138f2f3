#pragma once
// The files of src/report/assets/, compiled into the library (cmake/embed_assets.cmake), so that a
// report is one self-contained file and `eds report` needs nothing installed beside the program.

namespace eds::report {

extern const char* const kReportCss;  // report.css: the page's style
extern const char* const kView3dJs;   // view3d.js: the orbiting 3D view of the map and camera paths

}  // namespace eds::report
