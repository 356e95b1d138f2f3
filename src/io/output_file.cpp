#include "io/output_file.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <opencv2/imgcodecs.hpp>

#include "core/error.hpp"

namespace eds {

namespace fs = std::filesystem;

OutputFile::OutputFile(fs::path target) : target_(std::move(target)) {
  std::string name(".");
  name += target_.stem().string();
  name += ".partial-";
  name += std::to_string(::getpid());
  name += target_.extension().string();
  temporary_ = target_.parent_path() / name;
}

OutputFile::~OutputFile() {
  if (committed_) return;
  std::error_code ec;
  fs::remove(temporary_, ec);  // nothing to report from a destructor; the target is untouched
}

void OutputFile::commit() {
  std::error_code ec;
  fs::rename(temporary_, target_, ec);
  if (ec) throw InputError(target_.string(), "cannot write the file: " + ec.message());
  committed_ = true;
}

void writeTextFile(const fs::path& target, const std::string& text) {
  OutputFile out(target);
  std::FILE* f = std::fopen(out.temporary().c_str(), "wb");
  if (f == nullptr)
    throw InputError(target.string(), std::string("cannot open for writing: ") + std::strerror(errno));
  const bool written = std::fwrite(text.data(), 1, text.size(), f) == text.size();
  if (std::fclose(f) != 0 || !written)
    throw InputError(target.string(), std::string("write failed: ") + std::strerror(errno));
  out.commit();
}

void writeImageFile(const fs::path& target, const cv::Mat& image) {
  OutputFile out(target);
  bool written = false;
  try {
    written = cv::imwrite(out.temporary().string(), image);
  } catch (const cv::Exception& e) {
    throw InputError(target.string(), std::string("cannot write the image: ") + e.what());
  }
  if (!written) throw InputError(target.string(), "cannot write the image");
  out.commit();
}

void requireWritableDir(const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw InputError(dir.string(), "cannot create the output folder: " + ec.message());
  if (!fs::is_directory(dir)) throw InputError(dir.string(), "the output path exists and is not a folder");
  const fs::path probe = dir / (".eds-write-test-" + std::to_string(::getpid()));
  std::FILE* f = std::fopen(probe.c_str(), "wb");
  if (f == nullptr)
    throw InputError(dir.string(), std::string("cannot write in the output folder: ") + std::strerror(errno));
  std::fclose(f);
  fs::remove(probe, ec);
}

std::filesystem::path numberedFile(const std::filesystem::path& dir, const std::string& prefix, std::size_t i,
                                   int digits, const std::string& rest) {
  std::string n = std::to_string(i);
  if (static_cast<int>(n.size()) < digits) n.insert(0, static_cast<std::size_t>(digits) - n.size(), '0');
  return dir / (prefix + n + rest);
}

}  // namespace eds
