// Output files written whole or not at all, and output folders checked before a run.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "io/output_file.hpp"
#include "test_data.hpp"

namespace eds {
namespace {

namespace fs = std::filesystem;

std::size_t entries(const fs::path& dir) {
  return static_cast<std::size_t>(std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}

template <typename F>
std::string inputError(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(OutputFile, ReplacesTheTargetWholeAndLeavesNoTemporary) {
  const fs::path dir = test::tempDir("output_file");
  writeTextFile(dir / "a.txt", "first\n");
  writeTextFile(dir / "a.txt", "second, longer\n");
  EXPECT_EQ(test::fileText(dir / "a.txt"), "second, longer\n");
  EXPECT_EQ(entries(dir), 1u);
}

TEST(OutputFile, WithoutCommitTheTargetKeepsItsContent) {
  const fs::path dir = test::tempDir("output_abandoned");
  writeTextFile(dir / "a.txt", "kept\n");
  {
    OutputFile out(dir / "a.txt");
    std::ofstream(out.temporary()) << "half of a new";
    EXPECT_EQ(out.temporary().parent_path(), dir);
    EXPECT_EQ(out.temporary().extension(), ".txt");
    EXPECT_EQ(entries(dir), 2u);
  }  // as when an error or a signal cuts the write short
  EXPECT_EQ(test::fileText(dir / "a.txt"), "kept\n");
  EXPECT_EQ(entries(dir), 1u);
}

TEST(OutputFile, ErrorsNameTheTarget) {
  const fs::path dir = test::tempDir("output_errors");
  fs::create_directories(dir / "busy" / "inside");  // a non-empty folder cannot be replaced by a file
  const std::string busy = inputError([&] { writeTextFile(dir / "busy", "x"); });
  EXPECT_NE(busy.find((dir / "busy").string() + ": cannot write the file"), std::string::npos) << busy;
  const std::string missing = inputError([&] { writeTextFile(dir / "no" / "such" / "a.txt", "x"); });
  EXPECT_NE(missing.find((dir / "no" / "such" / "a.txt").string() + ": cannot open for writing"),
            std::string::npos)
      << missing;
  const cv::Mat img(4, 4, CV_8UC1, cv::Scalar(7));
  const std::string ext = inputError([&] { writeImageFile(dir / "image.unknown", img); });
  EXPECT_NE(ext.find((dir / "image.unknown").string() + ": cannot write the image"), std::string::npos) << ext;
  EXPECT_EQ(entries(dir), 1u);  // only "busy": no temporary left by any failure
}

TEST(OutputFile, ImagesKeepTheirFormat) {
  const fs::path dir = test::tempDir("output_image");
  cv::Mat img(6, 5, CV_8UC1);
  for (int i = 0; i < img.rows * img.cols; ++i) img.data[i] = static_cast<std::uint8_t>(i * 7);
  writeImageFile(dir / "k.png", img);
  const std::string head = test::fileText(dir / "k.png").substr(1, 3);
  EXPECT_EQ(head, "PNG");
}

TEST(OutputFolder, CreatedWhenMissingRefusedWhenNotAFolder) {
  const fs::path dir = test::tempDir("output_folder");
  requireWritableDir(dir / "new" / "nested");
  EXPECT_TRUE(fs::is_directory(dir / "new" / "nested"));
  EXPECT_EQ(entries(dir / "new" / "nested"), 0u);  // the probe file is gone
  std::ofstream(dir / "file") << "x";
  const std::string file = inputError([&] { requireWritableDir(dir / "file"); });
  EXPECT_NE(file.find((dir / "file").string() + ": "), std::string::npos) << file;
  EXPECT_NE(file.find("output"), std::string::npos) << file;
}

}  // namespace
}  // namespace eds
