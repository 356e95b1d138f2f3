// The `eds` program: a thin CLI11 front-end over the eds library.
#include <exception>
#include <iostream>

#include "commands.hpp"
#include "core/error.hpp"
#include "core/version.hpp"

int main(int argc, char** argv) {
  CLI::App app{"eds: Event-aided Direct Sparse Odometry"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "eds " + eds::versionString());
  // Subcommands (one file each under apps/).
  eds::app::addInfoCommand(app);
  eds::app::addEvalCommand(app);
  eds::app::addSimulateCommand(app);
  eds::app::addTrackCommand(app);
  eds::app::addRunCommand(app);
  eds::app::addCalibrateCommand(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
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
  return 0;
}
