// Event-frame snapshots on disk: values come back within the 16-bit quantization, and a damaged index
// names its file and line.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>

#include "core/error.hpp"
#include "io/output_file.hpp"
#include "system/event_snapshots.hpp"
#include "test_data.hpp"

namespace eds {
namespace {

TEST(EventSnapshots, RoundTripWithinTheQuantization) {
  const auto dir = test::tempDir("snapshots");
  std::vector<EventFrameSnapshot> shots(3);
  cv::RNG rng(3);
  for (std::size_t i = 0; i < shots.size(); ++i) {
    shots[i].t = 1'500'000'000'123'456'789 + static_cast<TimeNs>(i) * 50'000'000;  // epoch stamps stay exact
    shots[i].kf_id = static_cast<int>(7 * i);
    shots[i].correlation = 0.5 + 0.1 * static_cast<double>(i);
    shots[i].delta.create(18, 24, CV_32F), shots[i].predicted.create(18, 24, CV_32F);
    rng.fill(shots[i].delta, cv::RNG::NORMAL, 0, 0.05);
    shots[i].predicted.setTo(0);
    shots[i].predicted.at<float>(4, 5) = -0.7f, shots[i].predicted.at<float>(9, 2) = 0.2f;
  }
  writeEventSnapshots(dir, shots);
  const std::vector<EventFrameSnapshot> back = readEventSnapshots(dir);
  ASSERT_EQ(back.size(), shots.size());
  for (std::size_t i = 0; i < shots.size(); ++i) {
    EXPECT_EQ(back[i].t, shots[i].t);
    EXPECT_EQ(back[i].kf_id, shots[i].kf_id);
    EXPECT_NEAR(back[i].correlation, shots[i].correlation, 1e-9);
    double max_abs = 0;
    cv::minMaxLoc(cv::abs(shots[i].delta), nullptr, &max_abs);
    EXPECT_LE(cv::norm(back[i].delta, shots[i].delta, cv::NORM_INF), 0.51 * max_abs / 32767);
    EXPECT_LE(cv::norm(back[i].predicted, shots[i].predicted, cv::NORM_INF), 0.51 * 0.7 / 32767);
    EXPECT_EQ(back[i].predicted.at<float>(0, 0), 0.0f);  // zero stays exactly zero
  }
  EXPECT_TRUE(readEventSnapshots(test::tempDir("no_snapshots")).empty());  // frames-only run: none
}

TEST(EventSnapshots, DamagedIndexNamesFileAndLine) {
  const auto dir = test::tempDir("snapshots_bad");
  std::vector<EventFrameSnapshot> shots(1);
  shots[0].delta = cv::Mat::ones(4, 4, CV_32F), shots[0].predicted = cv::Mat::ones(4, 4, CV_32F);
  writeEventSnapshots(dir, shots);
  writeTextFile(dir / "event_frames" / "index.txt", "# header\n123 4 0.5 nan 1\n");
  try {
    readEventSnapshots(dir);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("index.txt:2"), std::string::npos) << e.what();
  }
  writeTextFile(dir / "event_frames" / "index.txt", "123 4 0.5 1 1\n124 4 0.5 1 1\n");  // 2nd has no image
  EXPECT_THROW(readEventSnapshots(dir), InputError);
}

}  // namespace
}  // namespace eds
