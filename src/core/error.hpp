#pragma once
// Errors about input data. Every message names the file, and the line where there is one, so a user
// can find and fix the offending input (DEVELOPERS.md: bad input never crashes or goes silent).
#include <cstddef>
#include <stdexcept>
#include <string>

namespace eds {

class InputError : public std::runtime_error {
 public:
  InputError(const std::string& file, std::size_t line, const std::string& what)
      : std::runtime_error(format(file, line, what)), file_(file), line_(line) {}
  InputError(const std::string& file, const std::string& what) : InputError(file, 0, what) {}

  const std::string& file() const { return file_; }
  std::size_t line() const { return line_; }  // 1-based; 0 when the error has no line

 private:
  static std::string format(const std::string& file, std::size_t line, const std::string& what) {
    return line > 0 ? file + ":" + std::to_string(line) + ": " + what : file + ": " + what;
  }
  std::string file_;
  std::size_t line_;
};

}  // namespace eds
