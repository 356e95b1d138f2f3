#pragma once
// Each subcommand of the `eds` program lives in its own file and registers itself here; the program
// only parses arguments and calls into the library.
#include <CLI/CLI.hpp>

namespace eds::app {

void addInfoCommand(CLI::App& app);
void addConvertCommand(CLI::App& app);
void addEvalCommand(CLI::App& app);
void addSimulateCommand(CLI::App& app);
void addTrackCommand(CLI::App& app);
void addRunCommand(CLI::App& app);
void addCalibrateCommand(CLI::App& app);
void addReportCommand(CLI::App& app);
void addStudyCommand(CLI::App& app);

}  // namespace eds::app
