// The `eds` program: a thin CLI11 front-end over the eds library.
#include <exception>
#include <iostream>
#include <map>
#include <string>

#include "commands.hpp"
#include "core/error.hpp"
#include "core/log.hpp"
#include "core/version.hpp"
#include "interrupt.hpp"

int main(int argc, char** argv) {
  eds::app::installInterruptHandlers();
  CLI::App app{"eds: Event-aided Direct Sparse Odometry"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "eds " + eds::versionString());
  // Set while parsing, before any subcommand runs; accepted before or after the subcommand.
  std::map<std::string, eds::LogLevel> levels;
  for (const auto& [level, name] : eds::enumNames(eds::LogLevel{})) levels.emplace(name, level);
  std::string level_name = "warn";
  app.add_option(
         "--log-level", level_name,
         "Messages on stderr: error, warn, info or debug (traces the bootstrap, every keyframe's solve "
         "and every event frame)")
      ->check(CLI::IsMember(levels))
      ->capture_default_str()
      ->each([&levels](const std::string& name) { eds::setLogLevel(levels.at(name)); });
  app.fallthrough();
  // Subcommands (one file each under apps/).
  eds::app::addInfoCommand(app);
  eds::app::addConvertCommand(app);
  eds::app::addEvalCommand(app);
  eds::app::addSimulateCommand(app);
  eds::app::addTrackCommand(app);
  eds::app::addRunCommand(app);
  eds::app::addCalibrateCommand(app);
  eds::app::addReportCommand(app);
  eds::app::addStudyCommand(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // Help and version print and succeed; any other usage error is bad input, as below.
    return app.exit(e) == 0 ? 0 : 2;
  } catch (const eds::InputError& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  } catch (const std::invalid_argument& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
  // Exit codes: 0 done, 1 an internal error, 2 bad input or usage (the message names the file and line or
  // the option), 130 stopped by SIGINT/SIGTERM (128 + SIGINT, as a shell reports it).
  return eds::app::interrupted() ? 130 : 0;
}
