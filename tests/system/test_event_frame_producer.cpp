// The event-frame producer's load shedding: with every k-th packet built, the frames it builds are those
// of the full stream at every k-th start, on and off its thread, and the packets passed over are
// counted, in total and before each frame built; passing over packets never reads past the events
// received.
#include <gtest/gtest.h>

#include <random>

#include "core/undistorter.hpp"
#include "sim_frames.hpp"
#include "system/event_frame_producer.hpp"

namespace eds {
namespace {

// 3 M events of random pixels and polarities at 1 M events/s: several of the producer's 1 M-event
// compactions happen while it passes over packets.
EventArray randomEvents() {
  EventArray ev;
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> x(0, 239), y(0, 179), p(0, 1);
  for (TimeNs t = 0; t < fromSeconds(3.0); t += 1000)
    ev.push_back(t, static_cast<std::uint16_t>(x(rng)), static_cast<std::uint16_t>(y(rng)), p(rng) ? 1 : -1);
  return ev;
}

struct Built {
  std::vector<EventFrame> frames;
  std::size_t passed = 0;
};

Built produce(const EventArray& ev, std::size_t every, bool threaded) {
  const Undistorter und(test::simCamera());
  StageClock clock(Stage::kInput);
  EventFrameProducer producer(und, EventFrameConfig{}, FlickerFilterConfig{}, threaded, &clock);
  producer.setEvery(every);
  Built out;
  std::deque<EventFrame> taken;
  for (std::size_t i = 0; i < ev.size(); i += 2000)  // a USB transfer's worth at a time
    producer.add(ev, i, std::min(ev.size(), i + 2000), [&] { producer.take(taken); });
  producer.finish();
  producer.take(taken);
  out.frames.assign(std::make_move_iterator(taken.begin()), std::make_move_iterator(taken.end()));
  out.passed = producer.packetsPassed();
  return out;
}

TEST(EventFrameProducer, EveryKthPacketBuiltIsTheFullStreamsFrameThere) {
  const EventArray ev = randomEvents();
  const Built all = produce(ev, 1, false);
  ASSERT_GT(all.frames.size(), 200u);
  EXPECT_EQ(all.passed, 0u);
  for (const bool threaded : {false, true}) {
    const Built every8 = produce(ev, 8, threaded);
    ASSERT_EQ(every8.frames.size(), (all.frames.size() - 1) / 8 + 1) << threaded;
    // Each built packet passes over the next 7, the last one's partly beyond the stream.
    EXPECT_EQ(every8.passed, 7 * every8.frames.size()) << threaded;
    std::size_t same = 0;
    for (std::size_t k = 0; k < every8.frames.size(); ++k) {
      const EventFrame& a = every8.frames[k];
      const EventFrame& b = all.frames[8 * k];
      ASSERT_EQ(a.t_first, b.t_first) << k;
      ASSERT_EQ(a.t_last, b.t_last) << k;
      // Each frame says how many were passed over right before it (the tracker's step is that long).
      EXPECT_EQ(a.passed_before, k == 0 ? 0u : 7u) << k;
      EXPECT_EQ(b.passed_before, 0u) << k;
      same += cv::norm(a.delta, b.delta, cv::NORM_INF) < 1e-6 ? 1 : 0;
    }
    // The builder's hysteresis memory restarts where a compaction drops events it was never shown.
    EXPECT_GE(same, every8.frames.size() * 9 / 10) << threaded;
  }
}

}  // namespace
}  // namespace eds
