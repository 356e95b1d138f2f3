// The recording readers against real sensor files and their published reference numbers
// (../shared/data/real/README.md): every count and time stamp must come out exactly.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "io/aedat4.hpp"
#include "io/prophesee.hpp"
#include "io/read_events.hpp"
#include "io/ros_bag.hpp"
#include "io/ros_events.hpp"
#include "io/sequence.hpp"
#include "io/sequence_stats.hpp"
#include "test_data.hpp"

namespace eds {
namespace {

std::size_t countOn(const EventArray& e) {
  std::size_t n = 0;
  for (auto p : e.p) n += p > 0;
  return n;
}

TEST(PropheseeRaw, Evt2Gen3SampleReproducesItsReferenceNumbers) {
  EDS_REQUIRE_SHARED(file, "real/prophesee/evt2_gen3_640x480.raw");
  PropheseeRawSource src(file);
  EXPECT_EQ(src.header().format, EvtFormat::kEvt2);
  EXPECT_EQ(src.header().width, 640);  // from the Gen3 plugin named in the header
  EXPECT_EQ(src.header().height, 480);
  const EventArray e = test::readAll(src, 7777);
  ASSERT_EQ(e.size(), 539481u);
  EXPECT_EQ(countOn(e), 367855u);
  EXPECT_EQ(e.t.front(), 1'317'888'000);
  EXPECT_EQ(e.t.back(), 1'367'888'000);
  EXPECT_EQ(*std::min_element(e.x.begin(), e.x.end()), 60);
  EXPECT_EQ(*std::max_element(e.x.begin(), e.x.end()), 599);
  EXPECT_EQ(*std::min_element(e.y.begin(), e.y.end()), 18);
  EXPECT_EQ(*std::max_element(e.y.begin(), e.y.end()), 475);
  EXPECT_TRUE(std::is_sorted(e.t.begin(), e.t.end()));
  EXPECT_TRUE(src.triggers().empty());
}

// The reference decoding shipped beside the EVT 3.0 sample: a NumPy structured array
// (t int64 µs, x int16, y int16, p uint8, 3 bytes of padding).
struct NpyEvent {
  std::int64_t t;
  std::int16_t x, y;
  std::uint8_t p;
};

std::vector<NpyEvent> readReferenceNpy(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(std::string(bytes.data() + 1, 5), "NUMPY");
  std::uint16_t header_len;
  std::memcpy(&header_len, bytes.data() + 8, 2);
  const std::string header(bytes.data() + 10, header_len);
  EXPECT_NE(header.find("('t', '<i8'), ('x', '<i2'), ('y', '<i2'), ('p', '|u1'), ('', '|V3')"),
            std::string::npos)
      << header;
  const std::size_t n = std::stoul(header.substr(header.find("'shape': (") + 10));
  std::vector<NpyEvent> out(n);
  const char* rec = bytes.data() + 10 + header_len;
  for (std::size_t i = 0; i < n; ++i, rec += 16) {
    std::memcpy(&out[i].t, rec, 8);
    std::memcpy(&out[i].x, rec + 8, 2);
    std::memcpy(&out[i].y, rec + 10, 2);
    out[i].p = static_cast<std::uint8_t>(rec[12]);
  }
  return out;
}

// Every event's pixel and polarity equal the reference's. Times equal it until the first place where
// the reference adds a 4096 µs wrap of the low time counter that the file's own TIME_HIGH words do not
// make (they advance 2861 -> 2863 only: an 8.8 ms span); after that they differ by whole wraps.
TEST(PropheseeRaw, Evt3Gen41SampleMatchesItsReferenceDecodingEventForEvent) {
  EDS_REQUIRE_SHARED(file, "real/prophesee/evt3_gen41_1280x720.raw");
  EDS_REQUIRE_SHARED(npy, "real/prophesee/evt3_gen41_1280x720.reference.npy");
  const std::vector<NpyEvent> ref = readReferenceNpy(npy);
  PropheseeRawSource src(file);
  EXPECT_EQ(src.header().format, EvtFormat::kEvt3);
  EXPECT_EQ(src.header().width, 1280);
  EXPECT_EQ(src.header().height, 720);
  const EventArray e = test::readAll(src, 7777);
  ASSERT_EQ(e.size(), 219596u);
  ASSERT_EQ(ref.size(), e.size());
  std::size_t same_time = 0;
  while (same_time < e.size() && ref[same_time].t * 1000 == e.t[same_time]) ++same_time;
  EXPECT_EQ(same_time, 20121u);
  for (std::size_t i = 0; i < e.size(); ++i) {
    ASSERT_EQ(e.x[i], ref[i].x) << i;
    ASSERT_EQ(e.y[i], ref[i].y) << i;
    ASSERT_EQ(e.p[i] > 0, ref[i].p == 1) << i;
    ASSERT_EQ((ref[i].t * 1000 - e.t[i]) % (4096 * 1000), 0) << i;
  }
  EXPECT_EQ(e.t.front(), 11'718'656'000);
  EXPECT_EQ(ref.front().t, 11'718'656);
  EXPECT_EQ(ref.back().t, 11'772'513);
  EXPECT_EQ(e.t.back(), 11'727'457'000);  // (2863 << 12 | low) µs: the file's last TIME_HIGH
  EXPECT_EQ(e.t.back() / 1000 >> 12, 2863);
  EXPECT_TRUE(std::is_sorted(e.t.begin(), e.t.end()));
  EXPECT_EQ(src.raisedTimes(), 0u);  // ordered as decoded: no time needed raising
}

struct PacketTotals {
  std::uint64_t messages = 0, off = 0, on = 0, trigger_value0 = 0, trigger_value1 = 0;
  std::int64_t sum_us = 0, first_us = -1;
};

// Decodes every evt3 packet with the sensor's own clock, as the reference numbers were computed.
PacketTotals decodePackets(const std::filesystem::path& path) {
  auto bag = openRosBag(path);
  Evt3Decoder decoder;
  PacketTotals s;
  EventArray cd;
  std::vector<TriggerEvent> triggers;
  std::vector<std::uint16_t> words;
  RosMessage m;
  while (bag->next(m)) {
    RosMessageReader r(m.data, bag->topics()[m.topic].serialization);
    const EventPacketMsg p = readEventPacket(r);
    EXPECT_EQ(p.encoding, "evt3");
    words.resize(p.events.size() / 2);
    std::memcpy(words.data(), p.events.data(), p.events.size());
    cd.clear();
    decoder.decode(words.data(), words.size(), cd, triggers);
    for (std::size_t i = 0; i < cd.size(); ++i) {
      if (s.first_us < 0) s.first_us = cd.t[i] / 1000;
      s.sum_us += cd.t[i] / 1000;
      (cd.p[i] > 0 ? s.on : s.off)++;
    }
    ++s.messages;
  }
  for (const TriggerEvent& t : triggers) {
    s.sum_us += t.t / 1000;
    (t.rising ? s.trigger_value1 : s.trigger_value0)++;
  }
  return s;
}

// The same recording as a ROS 1 bag and a rosbag2 SQLite file: both give the reference's counts
// and its checksum, the sum of all sensor times (events and trigger edges) in µs.
TEST(RosBags, EventPacketBagAndDb3GiveTheReferenceCountsAndChecksum) {
  EDS_REQUIRE_SHARED(dir, "real/ros2_and_ros1_event_camera_msgs");
  for (const auto& path :
       {dir / "test_events_1.bag", dir / "test_events_1" / "test_events_1.db3", dir / "test_events_1"}) {
    SCOPED_TRACE(path.string());
    auto bag = openRosBag(path);
    ASSERT_EQ(bag->topics().size(), 1u);
    EXPECT_EQ(bag->topics()[0].name, "/event_camera/events");
    EXPECT_EQ(bag->topics()[0].type, "event_camera_msgs/EventPacket");
    EXPECT_EQ(bag->topics()[0].messages, 517u);
    const PacketTotals s = decodePackets(path);
    EXPECT_EQ(s.messages, 517u);
    EXPECT_EQ(s.off, 218291u);
    EXPECT_EQ(s.on, 125183u);
    // The reference's own test counts 2,078 edges of value 0 and never checks the other value: 2,079
    // edges of value 1 are in the data, and the checksum below includes all 4,157.
    EXPECT_EQ(s.trigger_value0, 2078u);
    EXPECT_EQ(s.trigger_value1, 2079u);
    EXPECT_EQ(s.sum_us, 2'885'601'049'874);
    EXPECT_EQ(s.first_us, 7'139'845);
  }
}

TEST(RosBags, BagAndDb3GiveTheSameEventsOnTheRecordingClock) {
  EDS_REQUIRE_SHARED(dir, "real/ros2_and_ros1_event_camera_msgs");
  RosEventSource a(dir / "test_events_1.bag"), b(dir / "test_events_1");
  const EventArray ea = test::readAll(a, 7777), eb = test::readAll(b, 7777);
  ASSERT_EQ(ea.size(), 343474u);
  EXPECT_EQ(ea.t, eb.t);
  EXPECT_EQ(ea.x, eb.x);
  EXPECT_EQ(ea.p, eb.p);
  EXPECT_EQ(a.stats().triggers.size(), 4157u);
  EXPECT_EQ(a.stats().width, 640u);
  EXPECT_EQ(a.stats().height, 480u);
  // The first event sits at the first packet's header stamp; the sensor clock runs 2.08 s after it.
  EXPECT_EQ(ea.t.front(), 1'675'956'550'318'678'998);
  EXPECT_NEAR(toSeconds(ea.t.back() - ea.t.front()), 2.078, 0.001);
  EXPECT_TRUE(std::is_sorted(ea.t.begin(), ea.t.end()));
}

TEST(RosBags, McapContainerGivesItsMessagesAndTimeBase) {
  EDS_REQUIRE_SHARED(dir, "real/ros2_and_ros1_event_camera_msgs/test_events_2");
  auto bag = openRosBag(dir);
  EXPECT_STREQ(bag->format(), "mcap");
  ASSERT_EQ(bag->topics().size(), 1u);
  EXPECT_EQ(bag->topics()[0].type, "event_camera_msgs/EventPacket");
  EXPECT_EQ(bag->topics()[0].messages, 100u);
  RosMessage m;
  std::uint64_t n = 0, first_time_base = 0;
  while (bag->next(m)) {
    RosMessageReader r(m.data, bag->topics()[m.topic].serialization);
    const EventPacketMsg p = readEventPacket(r);
    EXPECT_EQ(p.encoding, "libcaer_cmp");
    if (n++ == 0) first_time_base = p.time_base;
  }
  EXPECT_EQ(n, 100u);
  EXPECT_EQ(first_time_base / 1000, 1'744'227'144'732'712u);  // the first sensor time, µs
  // The compressed libcaer payloads (numbers not given by the sample's source: what eds decodes; the
  // events of the first 0.1 s draw a board of twelve tags). The first event is at the first time base.
  RosEventSource src(dir);
  const EventArray e = test::readAll(src, 65536);
  EXPECT_EQ(e.size(), 571'266u);
  EXPECT_EQ(countOn(e), 211'043u);
  EXPECT_EQ(e.t.front(), 1'744'227'144'732'712'000);
  EXPECT_EQ(e.t.back(), 1'744'227'145'732'708'000);
  EXPECT_TRUE(std::is_sorted(e.t.begin(), e.t.end()));
  EXPECT_EQ(src.stats().width, 346u);
  EXPECT_LT(*std::max_element(e.x.begin(), e.x.end()), 346);
  EXPECT_LT(*std::max_element(e.y.begin(), e.y.end()), 260);
}

struct AedatReference {
  const char* file;
  std::uint64_t events, on, imu;
  std::vector<std::int64_t> frames_us;
  std::int64_t exposure_us;  // of every frame: end minus start of its exposure as DV recorded them
  double span_s;
};

TEST(Aedat4, Davis346FilesReproduceTheirReferenceNumbers) {
  EDS_REQUIRE_SHARED(dir, "real/aedat4");
  const AedatReference refs[] = {
      {"davis346_indoor.aedat4",
       117667,
       72363,
       130,
       {1633953690978904, 1633953691018904, 1633953691058904},
       4773,
       0.130},
      {"davis346_street.aedat4",
       6676,
       3563,
       160,
       {1589163147365215, 1589163147405215, 1589163147445215, 1589163147485215},
       500,
       0.170},
  };
  for (const AedatReference& r : refs) {
    SCOPED_TRACE(r.file);
    const Aedat4Counts c = scanAedat4(dir / r.file);
    EXPECT_EQ(c.events, r.events);
    EXPECT_EQ(c.events_on, r.on);
    EXPECT_EQ(c.imu_samples.size(), r.imu);
    ASSERT_EQ(c.frames.size(), r.frames_us.size());
    for (std::size_t i = 0; i < c.frames.size(); ++i) {
      EXPECT_EQ(c.frames[i].t, r.frames_us[i] * 1000);
      // DV stamps a frame at the middle of its exposure (indoor frame 0: 1633953690976518 to ..981291 us).
      EXPECT_EQ(c.frames[i].exposure, r.exposure_us * 1000);
    }
    // The same numbers through a Sequence: events streamed, frames decoded on demand.
    const Sequence seq(dir / r.file);
    EXPECT_EQ(seq.format(), "AEDAT 4.0");
    EXPECT_EQ(seq.width(), 346);
    EXPECT_EQ(seq.height(), 260);
    EXPECT_EQ(seq.imuSamples(), r.imu);
    // In SI units: a hand-held camera feels about one g; it turns at most a few rad/s.
    std::vector<double> g;
    for (std::size_t i = 0; i < seq.imu().size(); ++i) {
      const ImuSample& s = seq.imu()[i];
      if (i > 0) {
        ASSERT_GT(s.t, seq.imu()[i - 1].t);
      }
      g.push_back(std::sqrt(s.acc[0] * s.acc[0] + s.acc[1] * s.acc[1] + s.acc[2] * s.acc[2]));
      for (double w : s.gyro) EXPECT_LT(std::abs(w), 5.0);
    }
    std::nth_element(g.begin(), g.begin() + g.size() / 2, g.end());
    EXPECT_NEAR(g[g.size() / 2], 9.81, 1.5);
    ASSERT_EQ(seq.frames().size(), r.frames_us.size());
    const cv::Mat frame = seq.loadFrame(seq.frames().size() - 1);
    EXPECT_EQ(frame.type(), CV_8UC1);
    EXPECT_EQ(frame.cols, 346);
    EXPECT_EQ(frame.rows, 260);
    EXPECT_GT(cv::countNonZero(frame), 346 * 260 / 2);  // an image, not zeros
    const SequenceStats s = computeStats(seq);
    EXPECT_EQ(s.events, r.events);
    EXPECT_EQ(s.positive, r.on);
    EXPECT_NEAR(toSeconds(s.events_t1 - s.events_t0), r.span_s, 0.0005);
  }
}

TEST(Recordings, SequenceOpensEachRecordingFileByContentAndCountsIt) {
  EDS_REQUIRE_SHARED(real, "real");
  struct Case {
    std::filesystem::path path;
    const char* format_prefix;
    std::size_t events, on;
    int width, height;
  };
  const Case cases[] = {
      {real / "prophesee/evt2_gen3_640x480.raw", "Prophesee EVT 2.0", 539481, 367855, 640, 480},
      {real / "prophesee/evt3_gen41_1280x720.raw", "Prophesee EVT 3.0", 219596, 115532, 1280, 720},
      {real / "ros2_and_ros1_event_camera_msgs/test_events_1.bag", "rosbag1", 343474, 125183, 640, 480},
      {real / "ros2_and_ros1_event_camera_msgs/test_events_1", "rosbag2-sqlite3", 343474, 125183, 640, 480},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.path.string());
    const Sequence seq(c.path);
    EXPECT_EQ(seq.format().rfind(c.format_prefix, 0), 0u) << seq.format();
    EXPECT_TRUE(seq.hasEvents());
    EXPECT_FALSE(seq.hasFrames());
    const SequenceStats s = computeStats(seq);
    EXPECT_EQ(s.events, c.events);
    EXPECT_EQ(s.positive, c.on);
    EXPECT_EQ(s.width, c.width);
    EXPECT_EQ(s.height, c.height);
  }
}

}  // namespace
}  // namespace eds
