#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <stdexcept>
#include <vector>

#include "system/exposure_events.hpp"

namespace eds {
namespace {

// Events every millisecond from `from` to `to` (ms), in chunks as a driver would deliver them.
void feed(ExposureEvents& ex, int from, int to) {
  EventArray ev;
  for (int ms = from; ms < to; ++ms) {
    ev.t.push_back(fromSeconds(ms / 1000.0));
    ev.x.push_back(static_cast<std::uint16_t>(ms % 7)), ev.y.push_back(0), ev.p.push_back(1);
  }
  ex.addEvents(ev, 0, ev.size());
}

struct Handed {
  TimeNs t;
  std::vector<TimeNs> times;  // the events handed on with it
};

TEST(ExposureEvents, EachFrameGetsTheEventsOfItsExposureOnceItHasEnded) {
  ExposureEvents ex(fromSeconds(0.02));
  std::vector<Handed> got;
  const auto handle = [&](TimeNs t, TimeNs, bool, const cv::Mat&, const EventArray& ev, std::size_t b,
                          std::size_t e) {
    got.push_back({t, std::vector<TimeNs>(ev.t.begin() + static_cast<std::ptrdiff_t>(b),
                                          ev.t.begin() + static_cast<std::ptrdiff_t>(e))});
  };
  const cv::Mat img(2, 2, CV_8UC1, cv::Scalar(9));
  feed(ex, 0, 100);
  ex.addFrame(fromSeconds(0.1), img);  // exposed over [90, 110) ms
  feed(ex, 100, 105);
  ex.endExposures(fromSeconds(0.105), fromSeconds(0.1), handle);
  EXPECT_TRUE(got.empty());  // not ended yet
  feed(ex, 105, 400);
  ex.endExposures(fromSeconds(0.2), fromSeconds(0.05), handle);
  EXPECT_TRUE(got.empty());  // the frame itself not processed yet
  ex.endExposures(fromSeconds(0.2), fromSeconds(0.1), handle);
  ASSERT_EQ(got.size(), 1u);
  ASSERT_EQ(got[0].times.size(), 20u);
  EXPECT_EQ(got[0].times.front(), fromSeconds(0.09));
  EXPECT_EQ(got[0].times.back(), fromSeconds(0.109));
  // A frame that comes more than an exposure after its events were dropped is not handed on; one
  // within reach is.
  ex.addFrame(fromSeconds(0.3), img);
  ex.addFrame(fromSeconds(0.38), img);
  ex.endExposures(fromSeconds(0.399), fromSeconds(0.38), handle);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[1].t, fromSeconds(0.38));
  EXPECT_EQ(got[1].times.size(), 20u);
  EXPECT_THROW(ExposureEvents(0), std::invalid_argument);
}

TEST(ExposureEvents, ARecordedExposureReplacesTheDefaultForItsFrame) {
  ExposureEvents ex(fromSeconds(0.02));
  std::vector<Handed> got;
  std::vector<TimeNs> exposures;
  std::vector<bool> recorded;
  const auto handle = [&](TimeNs t, TimeNs exposure, bool rec, const cv::Mat&, const EventArray& ev,
                          std::size_t b, std::size_t e) {
    exposures.push_back(exposure), recorded.push_back(rec);
    got.push_back({t, std::vector<TimeNs>(ev.t.begin() + static_cast<std::ptrdiff_t>(b),
                                          ev.t.begin() + static_cast<std::ptrdiff_t>(e))});
  };
  const cv::Mat img(2, 2, CV_8UC1, cv::Scalar(9));
  feed(ex, 0, 40);
  ex.addFrame(fromSeconds(0.05), img, fromSeconds(0.006));  // exposed over [47, 53) ms
  ex.addFrame(fromSeconds(0.08), img);                      // the default: [70, 90) ms
  EXPECT_THROW(ex.addFrame(fromSeconds(0.09), img, fromSeconds(0.021)), std::invalid_argument);
  EXPECT_THROW(ex.addFrame(fromSeconds(0.09), img, -1), std::invalid_argument);
  feed(ex, 40, 200);
  ex.endExposures(fromSeconds(0.2), fromSeconds(0.2), handle);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(exposures[0], fromSeconds(0.006));
  EXPECT_TRUE(recorded[0]);
  ASSERT_EQ(got[0].times.size(), 6u);
  EXPECT_EQ(got[0].times.front(), fromSeconds(0.047));
  EXPECT_EQ(exposures[1], fromSeconds(0.02));
  EXPECT_FALSE(recorded[1]);
  EXPECT_EQ(got[1].times.size(), 20u);
}

}  // namespace
}  // namespace eds
