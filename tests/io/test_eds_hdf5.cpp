// eds's own HDF5 layout and `eds convert`: every stream comes back exactly as written, real recordings
// keep every count through a conversion, and malformed files (written by h5py) are refused by name.
#include <gtest/gtest.h>

#include <cstdlib>
#include <random>
#include <string>

#include "core/error.hpp"
#include "io/convert.hpp"
#include "io/eds_hdf5.hpp"
#include "io/hdf5_events.hpp"
#include "io/read_events.hpp"
#include "io/sequence.hpp"
#include "io/sequence_stats.hpp"
#include "test_data.hpp"

namespace eds {
namespace {

// Events over 2.5 ms after an epoch-scale start, at odd nanoseconds, with bursts of equal times.
EventArray syntheticEvents(std::size_t n) {
  std::mt19937 rng(7);
  EventArray e;
  TimeNs t = 1'633'953'690'978'904'123;
  for (std::size_t i = 0; i < n; ++i) {
    t += static_cast<TimeNs>(rng() % 5 == 0 ? 0 : rng() % 997);
    e.push_back(t, static_cast<std::uint16_t>(rng() % 346), static_cast<std::uint16_t>(rng() % 260),
                rng() % 2 ? 1 : -1);
  }
  return e;
}

EdsHdf5Contents syntheticRest() {
  EdsHdf5Contents c;
  CameraModel cam;
  cam.width = 346, cam.height = 260, cam.fx = 320.5, cam.fy = 319.25, cam.cx = 170.125, cam.cy = 129.75;
  cam.distortion = Distortion::kEquidistant;
  cam.k = {-0.01, 0.002, -0.0003, 0.00004, 0};
  c.camera = cam;
  c.calibration_source = "camchain.yaml";
  for (int i = 0; i < 5; ++i) {
    const TimeNs t = 1'633'953'690'978'904'000 + i * 1'000'000;
    c.ground_truth.push_back(
        {t, SE3(Quat(Eigen::AngleAxisd(0.1 * i, Vec3::UnitY())), Vec3(0.1 * i, -0.2, 1.5))});
    ImuSample s;
    s.t = t + 17;
    s.acc[2] = 9.81 + 0.01 * i;
    s.gyro[0] = -0.5 * i;
    c.imu.push_back(s);
    c.triggers.push_back({t + 5, static_cast<std::uint8_t>(i % 3), i % 2 == 0});
  }
  return c;
}

void expectSameEvents(const EventArray& a, const EventArray& b) {
  ASSERT_EQ(a.size(), b.size());
  EXPECT_TRUE(a.t == b.t && a.x == b.x && a.y == b.y && a.p == b.p);
}

TEST(EdsHdf5, EveryStreamComesBackExactlyAsWritten) {
  const auto dir = test::tempDir("eds_hdf5");
  const EventArray events = syntheticEvents(150'000);
  const EdsHdf5Contents rest = syntheticRest();
  std::mt19937 rng(3);
  std::vector<cv::Mat> frames;
  for (int i = 0; i < 3; ++i) {
    frames.emplace_back(260, 346, CV_8UC1);
    cv::randu(frames.back(), 0, 256);
  }
  for (const bool compress : {false, true}) {
    SCOPED_TRACE(compress ? "gzip" : "plain");
    const auto file = dir / (compress ? "gzip.h5" : "plain.h5");
    {
      EdsHdf5Writer w(file, "synthetic", compress);
      for (std::size_t a = 0; a < events.size(); a += 40'000) {
        EventArray part;
        appendRange(part, events, a, std::min<std::size_t>(40'000, events.size() - a));
        w.appendEvents(part);
      }
      for (int i = 0; i < 3; ++i) w.appendFrame(events.t[0] + i * 40'000'000, frames[i]);
      EXPECT_FALSE(std::filesystem::exists(file));  // only a finished file takes its name
      w.finish(rest);
    }
    const Sequence seq(file);
    EXPECT_EQ(seq.format(), "eds HDF5 (from synthetic)");
    EXPECT_EQ(seq.width(), 346);
    EXPECT_EQ(seq.calibrationSource(), "camchain.yaml");
    const CameraModel& c = seq.camera();
    EXPECT_EQ(c.distortion, Distortion::kEquidistant);
    EXPECT_TRUE(c.fx == 320.5 && c.fy == 319.25 && c.cx == 170.125 && c.cy == 129.75 &&
                c.k == rest.camera->k);
    auto src = seq.openEvents();
    expectSameEvents(test::readAll(*src, 9999), events);
    ASSERT_EQ(src->triggers().size(), 5u);
    EXPECT_EQ(src->triggers()[3].t, rest.triggers[3].t);
    EXPECT_EQ(src->triggers()[2].channel, 2);
    EXPECT_TRUE(src->triggers()[2].rising);
    ASSERT_EQ(seq.frames().size(), 3u);
    EXPECT_EQ(seq.frames()[2].t, events.t[0] + 80'000'000);
    EXPECT_EQ(cv::norm(seq.loadFrame(2), frames[2], cv::NORM_INF), 0.0);
    const Trajectory gt = seq.groundTruth();
    ASSERT_EQ(gt.size(), 5u);
    EXPECT_EQ(gt[4].t, rest.ground_truth[4].t);
    EXPECT_LT((gt[4].T_w_c.matrix() - rest.ground_truth[4].T_w_c.matrix()).norm(), 1e-15);
    ASSERT_EQ(seq.imu().size(), 5u);
    EXPECT_EQ(seq.imu()[1].t, rest.imu[1].t);
    EXPECT_EQ(seq.imu()[4].gyro[0], -2.0);
    // The millisecond index finds the first event at or after a time, as a search would.
    Hdf5EventOptions o;
    o.tick_ns = 1;
    Hdf5EventSource h5(file.string(), o);
    const TimeNs mid = events.t[77'777];
    h5.seek(mid);
    EXPECT_EQ(h5.position(), static_cast<std::size_t>(
                                 std::lower_bound(events.t.begin(), events.t.end(), mid) - events.t.begin()));
  }
}

// Every count of the real AEDAT 4.0 and EVT 3.0 samples survives a conversion; frames stay pixel-exact.
TEST(EdsHdf5, ConvertedRealRecordingsKeepEveryCount) {
  EDS_REQUIRE_SHARED(real, "real");
  const auto dir = test::tempDir("eds_convert_real");
  for (const char* name : {"aedat4/davis346_indoor.aedat4", "aedat4/davis346_street.aedat4",
                           "prophesee/evt3_gen41_1280x720.raw"}) {
    SCOPED_TRACE(name);
    const Sequence source(real / name);
    const auto out = dir / (std::filesystem::path(name).stem().string() + ".h5");
    const ConvertCounts n = convertToEdsHdf5(source, out, true);
    const Sequence converted(out);
    EXPECT_EQ(converted.format(), "eds HDF5 (from " + source.format() + ")");
    const SequenceStats a = computeStats(source), b = computeStats(converted);
    EXPECT_EQ(b.events, a.events);
    EXPECT_EQ(b.events, n.events);
    EXPECT_EQ(b.positive, a.positive);
    EXPECT_EQ(b.events_t0, a.events_t0);
    EXPECT_EQ(b.events_t1, a.events_t1);
    EXPECT_EQ(b.triggers, a.triggers);
    EXPECT_EQ(b.width, a.width);
    EXPECT_EQ(converted.imu().size(), source.imu().size());
    ASSERT_EQ(converted.frames().size(), source.frames().size());
    for (std::size_t i = 0; i < source.frames().size(); ++i) {
      EXPECT_EQ(converted.frames()[i].t, source.frames()[i].t);
      EXPECT_EQ(cv::norm(converted.loadFrame(i), source.loadFrame(i), cv::NORM_INF), 0.0);
    }
  }
}

// Files that claim the layout but break it, written by Debian's python3-h5py.
TEST(EdsHdf5, MalformedFilesAreRefusedNamingTheFileAndDataset) {
  EDS_REQUIRE_AVAILABLE(std::system("/usr/bin/python3 -c 'import h5py, numpy' > /dev/null 2>&1") == 0,
                        "Debian python3-h5py");
  const auto dir = test::tempDir("eds_hdf5_bad");
  const std::string script = R"PY(
import h5py, numpy as np, sys
d = sys.argv[1]
def base(name, version=1):
    f = h5py.File(d + '/' + name, 'w')
    f.attrs['eds_layout'] = np.int32(version)
    f['frames/images'] = np.zeros((2, 4, 5), np.uint8)
    f['frames/t'] = np.array([10, 20], np.int64)
    return f
base('version.h5', 2).close()
f = base('model.h5'); g = f.create_group('calibration')
g.attrs['model'] = np.bytes_('fisheye'); f.close()
f = base('fx.h5'); g = f.create_group('calibration')
g.attrs['model'] = np.bytes_('none'); g.attrs['width'] = np.int32(5); f.close()
f = base('gt.h5'); f['ground_truth/t'] = np.array([1, 2], np.int64); f['ground_truth/T_w_c'] = np.zeros((2, 6)); f.close()
f = base('quat.h5'); f['ground_truth/t'] = np.array([1], np.int64); f['ground_truth/T_w_c'] = np.zeros((1, 7)); f.close()
f = base('imu.h5'); f['imu/t'] = np.array([5, 3], np.int64); f['imu/acc'] = np.zeros((2, 3)); f['imu/gyro'] = np.zeros((2, 3)); f.close()
f = base('frames.h5'); del f['frames/t']; f['frames/t'] = np.array([20, 10], np.int64); f.close()
f = base('triggers.h5'); f['triggers/t'] = np.array([1, 2], np.int64); f['triggers/channel'] = np.zeros(2, np.uint8); f.close()
)PY";
  const std::string cmd = "/usr/bin/python3 -c \"$EDS_PY\" " + dir.string();
  ASSERT_EQ(setenv("EDS_PY", script.c_str(), 1), 0);
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  const std::pair<const char*, const char*> cases[] = {
      {"version.h5", "eds_layout version"},
      {"model.h5", "model 'fisheye'"},
      {"fx.h5", "attribute height"},
      {"gt.h5", "ground_truth/T_w_c is not an array of 2 x 7"},
      {"quat.h5", "ground_truth/T_w_c[0] is not a pose"},
      {"imu.h5", "imu/t[1]: times must not decrease"},
      {"frames.h5", "frames/t[1]: times must increase"},
      {"triggers.h5", "missing dataset triggers/rising"},
  };
  for (const auto& [file, what] : cases) {
    SCOPED_TRACE(file);
    try {
      const Sequence seq(dir / file);
      ADD_FAILURE() << "accepted";
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find((dir / file).string()), std::string::npos) << msg;
      EXPECT_NE(msg.find(what), std::string::npos) << msg;
    }
  }
}

}  // namespace
}  // namespace eds
