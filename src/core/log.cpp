#include "core/log.hpp"

#include <atomic>
#include <cstdarg>
#include <cstdio>

namespace eds {

namespace {
std::atomic<int>& level() {
  static std::atomic<int> value{static_cast<int>(LogLevel::kWarn)};
  return value;
}
}  // namespace

void setLogLevel(LogLevel l) { level().store(static_cast<int>(l), std::memory_order_relaxed); }

bool logEnabled(LogLevel l) { return static_cast<int>(l) <= level().load(std::memory_order_relaxed); }

void logf(LogLevel l, const char* format, ...) {
  if (!logEnabled(l)) return;
  char buf[1024];
  va_list args;
  va_start(args, format);
  std::vsnprintf(buf, sizeof buf, format, args);
  va_end(args);
  std::fprintf(stderr, "%s\n", buf);  // one call: lines from two threads do not interleave
}

}  // namespace eds
