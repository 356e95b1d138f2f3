#pragma once
// Output files appear whole or not at all: each is written to a hidden temporary file beside its
// target and renamed over it once complete (a rename within one file system is atomic), so no reader
// ever sees half a file and a run stopped mid-write leaves no torn output behind.
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>

namespace eds {

class OutputFile {
 public:
  explicit OutputFile(std::filesystem::path target);
  ~OutputFile();  // removes the temporary file unless commit() ran
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  // Where to write: ".NAME.partial-PID.EXT" beside the target (the extension kept for image encoders).
  const std::filesystem::path& temporary() const { return temporary_; }
  // Renames the temporary file over the target; InputError naming the target when that fails.
  void commit();

 private:
  std::filesystem::path target_, temporary_;
  bool committed_ = false;
};

// `text` as the whole content of `target`, atomically.
void writeTextFile(const std::filesystem::path& target, const std::string& text);
// An image in the format of the target's extension, atomically.
void writeImageFile(const std::filesystem::path& target, const cv::Mat& image);
// Creates `dir` if needed and checks that a file can be written in it, so that a run fails before any
// processing rather than after; InputError naming the folder otherwise.
void requireWritableDir(const std::filesystem::path& dir);
// dir / (prefix + i with `digits` digits + rest), e.g. ("kf_", 3, 6, ".png") -> dir/kf_000003.png.
std::filesystem::path numberedFile(const std::filesystem::path& dir, const std::string& prefix, std::size_t i,
                                   int digits, const std::string& rest);

}  // namespace eds
