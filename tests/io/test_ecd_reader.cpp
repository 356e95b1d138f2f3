#include <gtest/gtest.h>
#include <zlib.h>

#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "core/error.hpp"
#include "io/ecd_events.hpp"
#include "io/hdf5_events.hpp"
#include "io/merged_stream.hpp"
#include "io/read_events.hpp"
#include "io/sequence.hpp"
#include "io/sequence_stats.hpp"
#include "test_data.hpp"

namespace eds {
namespace {

void writeText(const std::filesystem::path& file, const std::string& content) {
  std::ofstream(file, std::ios::binary) << content;
}

TEST(EcdEvents, ParsesValuesExactlyAcrossChunks) {
  const auto dir = test::tempDir("ecd_values");
  writeText(dir / "events.txt",
            "# comment\n0.000000001 0 0 1\n1.5 239 179 0\n\n2.123456789123 5 6 -1\n3 7 8 +1\r\n"
            "1518195889.204480001 1 2 1");  // last line without newline, DSEC-sized seconds
  EcdEventSource src(dir / "events.txt");
  EventArray ev;
  EXPECT_EQ(src.read(ev, 2), 2u);
  EXPECT_EQ(src.read(ev, 2), 2u);
  EXPECT_EQ(src.read(ev, 2), 1u);
  EXPECT_EQ(src.read(ev, 2), 0u);
  ASSERT_EQ(ev.size(), 5u);
  EXPECT_EQ(ev.t[0], 1);
  EXPECT_EQ(ev.t[1], 1'500'000'000);
  EXPECT_EQ(ev.t[2], 2'123'456'789);  // digits beyond ns are truncated
  EXPECT_EQ(ev.t[3], 3'000'000'000);
  EXPECT_EQ(ev.t[4], 1518195889'204480001LL);
  EXPECT_EQ(ev.x[1], 239);
  EXPECT_EQ(ev.y[1], 179);
  EXPECT_EQ(ev.p[0], 1);
  EXPECT_EQ(ev.p[1], -1);
  EXPECT_EQ(ev.p[2], -1);
  EXPECT_EQ(ev.p[3], 1);
}

TEST(EcdEvents, GzipGivesTheSameEventsAsPlainText) {
  const auto dir = test::tempDir("ecd_gz");
  std::string content;
  for (int i = 0; i < 20000; ++i)
    content += std::to_string(i / 1000) + "." + std::to_string(100000000 + i % 1000 * 1000) + " " +
               std::to_string(i % 240) + " " + std::to_string(i % 180) + " " + std::to_string(i % 2) + "\n";
  writeText(dir / "events.txt", content);
  gzFile gz = gzopen((dir / "events.txt.gz").c_str(), "wb");
  gzwrite(gz, content.data(), static_cast<unsigned>(content.size()));
  gzclose(gz);
  EcdEventSource plain(dir / "events.txt"), zipped(dir / "events.txt.gz");
  const EventArray a = test::readAll(plain, 777), b = test::readAll(zipped, 1000);
  ASSERT_EQ(a.size(), 20000u);
  EXPECT_EQ(a.t, b.t);
  EXPECT_EQ(a.x, b.x);
  EXPECT_EQ(a.y, b.y);
  EXPECT_EQ(a.p, b.p);
}

TEST(EcdEvents, EsimPosterSequenceCountFirstAndLast) {
  EDS_REQUIRE_SHARED(file, "esim_poster6dof_planar/events.txt.gz");
  EcdEventSource src(file, {240, 180});
  EventArray chunk;
  std::size_t n = 0;
  TimeNs first_t = -1;
  int first_x = -1, first_y = -1, first_p = 0;
  while (true) {
    chunk.clear();
    if (src.read(chunk, 1 << 20) == 0) break;
    if (first_t < 0) first_t = chunk.t[0], first_x = chunk.x[0], first_y = chunk.y[0], first_p = chunk.p[0];
    n += chunk.size();
    // Keep the last chunk for the last event.
    if (chunk.size() < (1u << 20)) break;
  }
  while (src.read(chunk, 1 << 20) > 0) n += 0;  // drain (nothing should remain)
  EXPECT_EQ(n, 4'908'566u);
  // First line "0.023836234 214 3 1", last line "5.995000000 154 75 1" (zcat | head/tail).
  EXPECT_EQ(first_t, 23'836'234);
  EXPECT_EQ(first_x, 214);
  EXPECT_EQ(first_y, 3);
  EXPECT_EQ(first_p, 1);
  EXPECT_EQ(chunk.t.back(), 5'995'000'000);
  EXPECT_EQ(chunk.x.back(), 154);
  EXPECT_EQ(chunk.y.back(), 75);
  EXPECT_EQ(chunk.p.back(), 1);
}

TEST(Sequence, EsimPosterInfoFigures) {
  EDS_REQUIRE_SHARED(dir, "esim_poster6dof_planar");
  const Sequence seq(dir);
  EXPECT_TRUE(seq.hasEvents());
  EXPECT_TRUE(seq.hasFrames());
  EXPECT_EQ(seq.width(), 240);
  EXPECT_EQ(seq.height(), 180);
  EXPECT_EQ(seq.camera().distortion, Distortion::kNone);
  const SequenceStats s = computeStats(seq);
  EXPECT_EQ(s.events, 4'908'566u);
  EXPECT_EQ(s.frames, 150u);
  EXPECT_NEAR(s.frame_rate, 25.0, 1e-6);
  EXPECT_NEAR(s.events_per_s_mean, 4'908'566 / (5.995 - 0.023836234), 1.0);
  EXPECT_GT(s.events_per_s_peak, s.events_per_s_mean);
  EXPECT_EQ(s.gt_t0, 0);
  EXPECT_NEAR(toSeconds(s.gt_t1), 6.0, 0.01);
  const auto depth = seq.loadDepth(0);
  ASSERT_TRUE(depth.has_value());
  EXPECT_GT(depth->at<float>(90, 120), 0.8f);  // the plane is 0.83-1.41 m away
  EXPECT_LT(depth->at<float>(90, 120), 1.5f);
}

TEST(Sequence, SliderDepthIsFramesOnlyWithRadTan) {
  EDS_REQUIRE_SHARED(dir, "ecd_slider_depth");
  const Sequence seq(dir);
  EXPECT_FALSE(seq.hasEvents());
  EXPECT_EQ(seq.frames().size(), 87u);
  EXPECT_EQ(seq.camera().width, 240);
  EXPECT_EQ(seq.camera().distortion, Distortion::kRadTan);
  const SequenceStats s = computeStats(seq);
  EXPECT_EQ(s.events, 0u);
  EXPECT_EQ(s.frames, 87u);
  EXPECT_GT(s.gt_poses, 0u);
  EXPECT_THROW(seq.openEvents(), InputError);
  // Frames-only: the merged stream is just the frames in order.
  MergedStream stream(seq);
  EventArray ev;
  std::size_t idx = 0, count = 0;
  while (stream.next(ev, idx) == MergedStream::Kind::kFrame) EXPECT_EQ(idx, count++);
  EXPECT_EQ(count, 87u);
}

TEST(MergedStream, EventsNeverPassTheNextFrame) {
  const auto dir = test::tempDir("merged");
  std::string ev;
  for (int i = 0; i < 1000; ++i) ev += "0." + std::to_string(100000000 + i * 500000) + " 1 1 1\n";
  writeText(dir / "events.txt", ev);  // 0.1 s .. 0.5995 s
  cv::Mat img(4, 6, CV_8U, cv::Scalar(7));
  std::filesystem::create_directories(dir / "images");
  std::string list;
  for (int i = 0; i < 5; ++i) {
    const std::string name = "images/f" + std::to_string(i) + ".png";
    cv::imwrite((dir / name).string(), img);
    list += "0." + std::to_string(100000000 + i * 125000000) + " " + name + "\n";  // 0.1, 0.225, ...
  }
  writeText(dir / "images.txt", list);
  const Sequence seq(dir);
  MergedStream stream(seq, 64);
  EventArray chunk;
  std::size_t idx = 0, events = 0, frames = 0;
  TimeNs last_frame = -1;
  for (auto kind = stream.next(chunk, idx); kind != MergedStream::Kind::kEnd;
       kind = stream.next(chunk, idx)) {
    if (kind == MergedStream::Kind::kFrame) {
      EXPECT_EQ(idx, frames);
      last_frame = seq.frames()[idx].t;
      ++frames;
    } else {
      EXPECT_LE(chunk.size(), 64u);
      // After frame k only events later than it; an event at a frame's exact time precedes the frame.
      EXPECT_GT(chunk.t.front(), last_frame);
      if (frames < seq.frames().size()) {
        EXPECT_LE(chunk.t.back(), seq.frames()[frames].t);
      }
      events += chunk.size();
    }
  }
  EXPECT_EQ(events, 1000u);
  EXPECT_EQ(frames, 5u);
}

}  // namespace
}  // namespace eds

namespace eds {
namespace {

TEST(Sequence, Hdf5EventsWithKalibrCalibration) {
  const auto dir = test::tempDir("seq_h5");
  EventArray ev;
  for (int i = 0; i < 5000; ++i) ev.push_back(1'000'000LL * i, i % 346, i % 260, i % 2 ? 1 : -1);
  writeHdf5Events((dir / "events.h5").string(), ev, 0);
  std::ofstream(dir / "camchain.yaml")
      << "cam0:\n  camera_model: pinhole\n  intrinsics: [180.0, 181.0, 170.0, 128.0]\n"
         "  distortion_model: equidistant\n"
         "  distortion_coeffs: [0.05, -0.02, 0.004, -0.001]\n"
         "  resolution: [346, 260]\n";
  const Sequence seq(dir);
  EXPECT_EQ(seq.width(), 346);
  EXPECT_EQ(seq.camera().distortion, Distortion::kEquidistant);
  EXPECT_DOUBLE_EQ(seq.camera().k[3], -0.001);
  const SequenceStats s = computeStats(seq);
  EXPECT_EQ(s.events, 5000u);
  EXPECT_EQ(s.events_t1, 4999'000'000LL);
  EXPECT_FALSE(seq.hasFrames());
}

}  // namespace
}  // namespace eds
