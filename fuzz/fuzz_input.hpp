#pragma once
// Shared by the fuzz targets: the readers take paths, as users give them, so each input is written to a
// file first. Only InputError is an expected outcome; any other exception escapes to libFuzzer and
// counts as a crash, as would a sanitizer report.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>

#include "core/error.hpp"

namespace eds::fuzz {

// The input as `name` in a folder of this process (one file per name, rewritten for every input).
inline std::filesystem::path writeInput(const std::uint8_t* data, std::size_t size, const char* name) {
  struct Folder {
    std::filesystem::path path =
        std::filesystem::temp_directory_path() / ("eds_fuzz_" + std::to_string(::getpid()));
    Folder() { std::filesystem::create_directories(path); }
    ~Folder() {
      std::error_code ec;
      std::filesystem::remove_all(path, ec);
    }
  };
  static const Folder folder;
  const std::filesystem::path file = folder.path / name;
  std::FILE* f = std::fopen(file.c_str(), "wb");
  if (f == nullptr) std::abort();
  if (size > 0 && std::fwrite(data, 1, size, f) != size) std::abort();
  std::fclose(f);
  return file;
}

// Runs a reader on the input; an InputError is the reader refusing bad input, which is correct.
template <typename F>
void expectOnlyInputErrors(F&& read) {
  try {
    read();
  } catch (const InputError&) {
  }
}

}  // namespace eds::fuzz
