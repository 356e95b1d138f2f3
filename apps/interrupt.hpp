#pragma once
// SIGINT and SIGTERM. Before a command listens (and for commands that never do) they end the program
// at once, as by default; once the running command listens, the first one asks it to finish with what
// it has computed and write its outputs, and a second one exits at once.
#include <atomic>

namespace eds::app {

// Installs the handlers; called first thing in main.
void installInterruptHandlers();
// Marks the running command as one that stops cleanly and returns the flag it must poll.
const std::atomic<bool>& listenForInterrupt();
// Whether a clean stop was requested; main turns it into exit code 130.
bool interrupted();

}  // namespace eds::app
