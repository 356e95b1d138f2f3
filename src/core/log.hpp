#pragma once
// A levelled log on stderr. The level is the process's one logging setting (`eds --log-level`, or
// setLogLevel from a program using the library); messages below it cost one atomic load.
#include <array>
#include <string_view>
#include <utility>

namespace eds {

enum class LogLevel { kError, kWarn, kInfo, kDebug };
constexpr std::array<std::pair<LogLevel, std::string_view>, 4> enumNames(LogLevel) {
  return {{{LogLevel::kError, "error"}, {LogLevel::kWarn, "warn"}, {LogLevel::kInfo, "info"}, {LogLevel::kDebug, "debug"}}};
}

void setLogLevel(LogLevel level);  // default: warn
bool logEnabled(LogLevel level);
// printf-style; a newline is added.
void logf(LogLevel level, const char* format, ...) __attribute__((format(printf, 2, 3)));

}  // namespace eds
