#include "interrupt.hpp"

#include <unistd.h>

#include <csignal>

namespace eds::app {

namespace {

// A signal handler can reach only static storage: these two flags are the program's only globals,
// set here and by the command that listens, read by its driver between chunks of input.
std::atomic<bool> g_listening{false}, g_stop{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the flags must be async-signal-safe");

extern "C" void onStopSignal(int) {
  if (!g_listening.load() || g_stop.exchange(true)) _exit(130);  // 128 + SIGINT, as a shell reports it
  constexpr char kMessage[] =
      "\ninterrupted: finishing and writing the outputs so far (signal again to exit at once)\n";
  const ssize_t ignored = write(STDERR_FILENO, kMessage, sizeof kMessage - 1);
  (void)ignored;
}

}  // namespace

void installInterruptHandlers() {
  struct sigaction sa {};
  sa.sa_handler = onStopSignal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

const std::atomic<bool>& listenForInterrupt() {
  g_listening.store(true);
  return g_stop;
}

bool interrupted() { return g_stop.load(); }

}  // namespace eds::app
