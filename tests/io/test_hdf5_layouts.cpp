// The HDF5 layouts of MVSEC and M3ED, written by Debian's python3-h5py from the ESIM sequence
// (tests/tools/write_hdf5_layouts.py): the events and frames of the text folder must come out.
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "core/error.hpp"
#include "io/ecd_events.hpp"
#include "io/read_events.hpp"
#include "io/sequence.hpp"
#include "test_data.hpp"

namespace eds {
namespace {

namespace fs = std::filesystem;

constexpr double kUntilS = 0.5;

fs::path writtenLayouts() {
  static const fs::path dir = [] {
    const fs::path out = test::tempDir("hdf5_layouts");
    const std::string cmd = "/usr/bin/python3 " EDS_SOURCE_DIR "/tests/tools/write_hdf5_layouts.py " +
                            (test::sharedDataDir() / "esim_poster6dof_planar").string() + " " + out.string() +
                            " " + std::to_string(kUntilS);
    return std::system(cmd.c_str()) == 0 ? out : fs::path();
  }();
  return dir;
}

#define EDS_REQUIRE_LAYOUTS(dir)                                                                            \
  EDS_REQUIRE_SHARED(esim_, "esim_poster6dof_planar");                                                      \
  EDS_REQUIRE_AVAILABLE(std::system("/usr/bin/python3 -c 'import h5py, numpy, PIL' > /dev/null 2>&1") == 0, \
                        "Debian python3-h5py, python3-pil");                                                \
  const fs::path dir = writtenLayouts();                                                                    \
  ASSERT_FALSE(dir.empty()) << "tests/tools/write_hdf5_layouts.py failed"

// The text events up to kUntilS, with their times floored to `resolution_ns`.
EventArray textEvents(TimeNs resolution_ns) {
  EcdEventSource text(test::sharedDataDir() / "esim_poster6dof_planar/events.txt.gz");
  EventArray all = test::readAll(text, 30000), out;
  for (std::size_t i = 0; i < all.size() && all.t[i] <= fromSeconds(kUntilS); ++i)
    out.push_back(all.t[i] / resolution_ns * resolution_ns, all.x[i], all.y[i], all.p[i]);
  return out;
}

void expectTextEvents(const Sequence& seq, TimeNs resolution_ns) {
  const EventArray expected = textEvents(resolution_ns);
  const EventArray got = test::readAll(*seq.openEvents(), 30000);
  ASSERT_EQ(got.size(), expected.size());
  EXPECT_EQ(got.t, expected.t);
  EXPECT_EQ(got.x, expected.x);
  EXPECT_EQ(got.y, expected.y);
  EXPECT_EQ(got.p, expected.p);
}

TEST(Hdf5Layouts, MvsecAndM3edGiveTheTextFoldersEventsAndFrames) {
  EDS_REQUIRE_LAYOUTS(dir);
  const Sequence folder(test::sharedDataDir() / "esim_poster6dof_planar");
  struct Case {
    const char* file;
    const char* format;
    TimeNs resolution_ns;  // MVSEC stores float64 seconds (exact to the ns here), M3ED integer µs
  };
  for (const Case c : {Case{"mvsec.h5", "MVSEC HDF5 (davis/left)", 1},
                       Case{"m3ed.h5", "M3ED HDF5 (prophesee/left, ovc/left)", 1000}}) {
    SCOPED_TRACE(c.file);
    const Sequence seq(dir / c.file);
    EXPECT_EQ(seq.format(), c.format);
    EXPECT_EQ(seq.width(), 240);
    EXPECT_EQ(seq.height(), 180);
    expectTextEvents(seq, c.resolution_ns);
    ASSERT_EQ(seq.frames().size(), 13u);  // 0 .. 0.48 s at 25 Hz
    for (std::size_t i = 0; i < seq.frames().size(); ++i) {
      EXPECT_EQ(seq.frames()[i].t, folder.frames()[i].t);
      EXPECT_EQ(cv::norm(seq.loadFrame(i), folder.loadFrame(i), cv::NORM_INF), 0.0) << i;
    }
  }
}

// VECtor's event files: the DSEC layout with uint32 times after a (1,)-shaped t_offset, every dataset
// Zstandard-compressed (eds registers its own zstd filter; Debian has no HDF5 plugin for it).
TEST(Hdf5Layouts, VectorZstdEventFileGivesTheTextFoldersEvents) {
  EDS_REQUIRE_LAYOUTS(dir);
  const Sequence seq(dir / "vector.h5");
  EXPECT_EQ(seq.format(), "HDF5 events");
  expectTextEvents(seq, 1000);
  try {
    test::readAll(*Sequence(dir / "vector_corrupt.h5").openEvents(), 30000);
    ADD_FAILURE() << "a corrupt zstd chunk was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("vector_corrupt.h5: cannot read events/t[0.."), std::string::npos)
        << e.what();
  }
}

// M3ED with calibration groups: the events' camera comes from prophesee/left/calib, and the OVC frames,
// another camera 2 cm aside, are not paired with the events (EDS needs frames of the same pixels).
TEST(Hdf5Layouts, M3edCalibrationIsReadAndAnotherCamerasFramesAreNotUsed) {
  EDS_REQUIRE_LAYOUTS(dir);
  const Sequence seq(dir / "m3ed_calibrated.h5");
  EXPECT_EQ(seq.format(),
            "M3ED HDF5 (prophesee/left; the frames of ovc/left are another camera's and not read)");
  EXPECT_FALSE(seq.hasFrames());
  ASSERT_TRUE(seq.hasCalibration());
  EXPECT_EQ(seq.calibrationSource(), "prophesee/left/calib");
  const CameraModel& c = seq.camera();
  EXPECT_EQ(c.distortion, Distortion::kRadTan);
  EXPECT_EQ(c.fx, 199.092);
  EXPECT_EQ(c.cy, 110.712);
  EXPECT_EQ(c.k[0], -0.368436311798);
  EXPECT_EQ(seq.width(), 240);
  expectTextEvents(seq, 1000);
}

TEST(Hdf5Layouts, MalformedMvsecArraysNameTheFileAndDataset) {
  EDS_REQUIRE_LAYOUTS(dir);
  const auto write = [&](const std::string& name, const std::string& python) {
    const fs::path f = dir / name;
    const std::string cmd = "/usr/bin/python3 -c 'import h5py, numpy as np\nwith h5py.File(\"" + f.string() +
                            "\", \"w\") as h:\n  g = h.create_group(\"davis/left\")\n  " + python + "'";
    EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
    return f;
  };
  const auto expectError = [](const fs::path& f, const std::string& phrase) {
    try {
      const Sequence seq(f);
      test::readAll(*seq.openEvents(), 30000);
      ADD_FAILURE() << "no error for " << f;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(f.string()), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(phrase), std::string::npos) << e.what();
    }
  };
  expectError(write("three.h5", "g.create_dataset(\"events\", data=np.zeros((5, 3)))"),
              "davis/left/events has 3 columns, not 4");
  expectError(
      write("nan.h5", "g.create_dataset(\"events\", data=np.array([[1, 2, 0.1, 1], [3, 4, np.nan, -1]]))"),
      "davis/left/events[1] is not finite");
  expectError(
      write("back.h5", "g.create_dataset(\"events\", data=np.array([[1, 2, 0.2, 1], [3, 4, 0.1, -1]]))"),
      "davis/left/events[1]: time 0.1");
  expectError(write("ts.h5",
                    "g.create_dataset(\"events\", data=np.zeros((2, 4)))\n  g.create_dataset(\"image_raw\", "
                    "data=np.zeros((2, 4, 6), dtype=np.uint8))\n  g.create_dataset(\"image_raw_ts\", "
                    "data=np.array([0.5]))"),
              "davis/left/image_raw_ts has 1 times for 2 images");
}

}  // namespace
}  // namespace eds
