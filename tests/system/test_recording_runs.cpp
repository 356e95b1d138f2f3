// Runs over recordings in each format the readers take (ROS 1 bags, MCAP, the HDF5 layouts, eds's own
// HDF5, AEDAT 4), written by tools eds did not write: the same outputs as the run over the folder.
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "accuracy.hpp"
#include "core/error.hpp"
#include "eval/ate.hpp"
#include "io/convert.hpp"
#include "run_outputs.hpp"
#include "system/odometry.hpp"
#include "test_data.hpp"

namespace eds {
namespace {

using test::allEvents;
using test::expectSameOutputs;
using test::syncConfig;

// The first 1.4 s of `folder` and of the same recording in another format, run deterministically:
// every output file the same byte for byte.
void expectSameRuns(const Sequence& folder, const Sequence& other, const std::filesystem::path& out,
                    const std::string& name) {
  OdometryConfig cfg = syncConfig();
  cfg.duration_s = 1.4;
  const OdometryResult a = runOdometry(folder, cfg), b = runOdometry(other, cfg);
  ASSERT_TRUE(a.initialized);
  ASSERT_GT(a.events.size(), 30u);
  writeOdometryOutputs(out / "folder", a, cfg);
  writeOdometryOutputs(out / name, b, cfg);
  expectSameOutputs(out / "folder", out / name);
}

// The ESIM sequence as a ROS 1 bag written by Debian's python3-rosbag (events, mono8 frames, CameraInfo,
// PoseStamped ground truth; tests/tools/write_bags.py): the run over the bag is the run over the folder.
TEST(RecordingRuns, EsimAsARosBagGivesByteIdenticalOutputs) {
  EDS_REQUIRE_SHARED(dir, "esim_poster6dof_planar");
  EDS_REQUIRE_AVAILABLE(
      std::system("/usr/bin/python3 -c 'import rosbag, genpy, roslz4, PIL' > /dev/null 2>&1") == 0,
      "Debian python3-rosbag, python3-roslz4, python3-genpy, python3-pil");
  const auto out = test::tempDir("recording_runs");
  const std::string cmd = "/usr/bin/python3 " EDS_SOURCE_DIR "/tests/tools/write_bags.py " + dir.string() +
                          " " + out.string() + " 1000 2500 1.4";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const Sequence folder(dir), bag(out / "recording.bag");
  EXPECT_EQ(bag.camera().fx, folder.camera().fx);
  EXPECT_EQ(bag.camera().cy, folder.camera().cy);
  ASSERT_EQ(bag.frames().size(), 36u);  // 0 .. 1.4 s at 25 Hz
  for (std::size_t i = 0; i < bag.frames().size(); ++i) {
    ASSERT_EQ(bag.frames()[i].t, folder.frames()[i].t);
    ASSERT_EQ(cv::norm(bag.loadFrame(i), folder.loadFrame(i), cv::NORM_INF), 0.0) << i;
  }
  const Trajectory gt_bag = bag.groundTruth(), gt_folder = folder.groundTruth();
  ASSERT_GT(gt_bag.size(), 250u);
  for (std::size_t i = 0; i < gt_bag.size(); ++i) {
    ASSERT_EQ(gt_bag[i].t, gt_folder[i].t);
    ASSERT_EQ(gt_bag[i].T_w_c.matrix(), gt_folder[i].T_w_c.matrix()) << i;
  }
  expectSameRuns(folder, bag, out, "bag");
}

// The ESIM sequence in MVSEC's HDF5 layout, written by Debian's python3-h5py
// (tests/tools/write_hdf5_layouts.py), with the folder's calibration: the same outputs again.
TEST(RecordingRuns, EsimInTheMvsecHdf5LayoutGivesByteIdenticalOutputs) {
  EDS_REQUIRE_SHARED(dir, "esim_poster6dof_planar");
  EDS_REQUIRE_AVAILABLE(std::system("/usr/bin/python3 -c 'import h5py, numpy, PIL' > /dev/null 2>&1") == 0,
                        "Debian python3-h5py, python3-pil");
  const auto out = test::tempDir("mvsec_runs");
  const std::string cmd = "/usr/bin/python3 " EDS_SOURCE_DIR "/tests/tools/write_hdf5_layouts.py " +
                          dir.string() + " " + out.string() + " 1.4";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const Sequence folder(dir);
  Sequence mvsec(out / "mvsec.h5");
  EXPECT_EQ(mvsec.format(), "MVSEC HDF5 (davis/left)");
  mvsec.setCamera(readCameraFile(dir / "calib.txt"), "calib.txt");
  ASSERT_EQ(mvsec.frames().size(), 36u);
  for (std::size_t i = 0; i < mvsec.frames().size(); ++i) {
    ASSERT_EQ(mvsec.frames()[i].t, folder.frames()[i].t);
    ASSERT_EQ(cv::norm(mvsec.loadFrame(i), folder.loadFrame(i), cv::NORM_INF), 0.0) << i;
  }
  expectSameRuns(folder, mvsec, out, "mvsec");
}

// The ESIM folder converted to eds's own HDF5 layout (nanosecond times, calibration and ground truth
// inside): the same outputs byte for byte, and the same ground truth.
TEST(RecordingRuns, EsimConvertedToEdsHdf5GivesByteIdenticalOutputs) {
  EDS_REQUIRE_SHARED(dir, "esim_poster6dof_planar");
  const auto out = test::tempDir("eds_hdf5_runs");
  const Sequence folder(dir);
  const ConvertCounts n = convertToEdsHdf5(folder, out / "esim.h5", false);
  EXPECT_TRUE(n.calibration);
  const Sequence h5(out / "esim.h5");
  EXPECT_EQ(h5.format(), "eds HDF5 (from ECD folder)");
  EXPECT_EQ(h5.camera().fx, folder.camera().fx);
  EXPECT_EQ(h5.camera().k, folder.camera().k);
  ASSERT_EQ(h5.frames().size(), folder.frames().size());
  const Trajectory gt_h5 = h5.groundTruth(), gt_folder = folder.groundTruth();
  ASSERT_EQ(gt_h5.size(), gt_folder.size());
  for (std::size_t i = 0; i < gt_h5.size(); ++i) {
    ASSERT_EQ(gt_h5[i].t, gt_folder[i].t);
    ASSERT_LT((gt_h5[i].T_w_c.matrix() - gt_folder[i].T_w_c.matrix()).norm(), 1e-14) << i;
  }
  expectSameRuns(folder, h5, out, "h5");
}

// The ESIM sequence as a rosbag2 MCAP file of ROS 2 (CDR) messages in zstd chunks
// (tests/tools/write_mcap.py): events, frames and ground truth exactly as the folder's, the same outputs.
TEST(RecordingRuns, EsimAsMcapGivesByteIdenticalOutputs) {
  EDS_REQUIRE_SHARED(dir, "esim_poster6dof_planar");
  EDS_REQUIRE_AVAILABLE(std::system("/usr/bin/python3 -c 'import PIL' > /dev/null 2>&1") == 0 &&
                            std::system("zstd --version > /dev/null 2>&1") == 0,
                        "Debian python3-pil, zstd");
  const auto out = test::tempDir("mcap_runs");
  const std::string cmd = "/usr/bin/python3 " EDS_SOURCE_DIR "/tests/tools/write_mcap.py " + dir.string() +
                          " " + (out / "esim.mcap").string() + " 1.4 zstd";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const Sequence folder(dir), mcap(out / "esim.mcap");
  EXPECT_EQ(mcap.calibrationSource(), "CameraInfo on /dvs/camera_info");
  const EventArray a = allEvents(folder), b = allEvents(mcap);
  const std::size_t n =
      static_cast<std::size_t>(std::upper_bound(a.t.begin(), a.t.end(), 1'400'000'000) - a.t.begin());
  ASSERT_EQ(b.size(), n);
  EXPECT_TRUE(
      std::equal(b.t.begin(), b.t.end(), a.t.begin()) && std::equal(b.x.begin(), b.x.end(), a.x.begin()) &&
      std::equal(b.y.begin(), b.y.end(), a.y.begin()) && std::equal(b.p.begin(), b.p.end(), a.p.begin()));
  ASSERT_EQ(mcap.frames().size(), 36u);
  for (std::size_t i = 0; i < mcap.frames().size(); ++i) {
    ASSERT_EQ(mcap.frames()[i].t, folder.frames()[i].t);
    ASSERT_EQ(cv::norm(mcap.loadFrame(i), folder.loadFrame(i), cv::NORM_INF), 0.0) << i;
  }
  const Trajectory gt = mcap.groundTruth(), gt_folder = folder.groundTruth();
  ASSERT_EQ(gt.size(), 280u);
  for (std::size_t i = 0; i < gt.size(); ++i) {
    ASSERT_EQ(gt[i].t, gt_folder[i].t);
    ASSERT_EQ(gt[i].T_w_c.matrix(), gt_folder[i].T_w_c.matrix()) << i;
  }
  expectSameRuns(folder, mcap, out, "mcap");
}

// The layouts that keep microseconds (DSEC / TUM-VIE, VECtor with zstd, M3ED), written by python3-h5py
// from the ESIM events cut to the microsecond, beside a text folder of the same events: every run gives
// the text folder's outputs byte for byte.
TEST(RecordingRuns, EsimInEveryMicrosecondHdf5LayoutGivesByteIdenticalOutputs) {
  EDS_REQUIRE_SHARED(dir, "esim_poster6dof_planar");
  EDS_REQUIRE_AVAILABLE(std::system("/usr/bin/python3 -c 'import h5py, numpy, PIL' > /dev/null 2>&1") == 0 &&
                            std::system("zstd --version > /dev/null 2>&1") == 0,
                        "Debian python3-h5py, python3-pil, zstd");
  const auto out = test::tempDir("us_layout_runs");
  for (const std::string mode : {"--us-folders " + dir.string() + " " + out.string() + " 1.4",
                                 dir.string() + " " + out.string() + " 1.4"}) {
    const std::string cmd = "/usr/bin/python3 " EDS_SOURCE_DIR "/tests/tools/write_hdf5_layouts.py " + mode;
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  }
  OdometryConfig cfg = syncConfig();
  cfg.duration_s = 1.4;
  const OdometryResult ref = runOdometry(Sequence(out / "us_text"), cfg);
  ASSERT_TRUE(ref.initialized);
  writeOdometryOutputs(out / "out_text", ref, cfg);
  for (const char* name : {"us_dsec", "us_vector", "m3ed.h5"}) {
    SCOPED_TRACE(name);
    Sequence seq(out / name);
    if (!seq.hasCalibration()) seq.setCamera(readCameraFile(dir / "calib.txt"), "calib.txt");
    writeOdometryOutputs(out / (std::string("out_") + name), runOdometry(seq, cfg), cfg);
    expectSameOutputs(out / "out_text", out / (std::string("out_") + name));
  }
}

// The ESIM sequence as AEDAT 4.0 (lz4), written by tests/tools/write_aedat4.py with Debian's
// python3-flatbuffers, with the folder's calibration: AEDAT holds microseconds, so the events differ from
// the folder's by under 1 us and the run is compared by its accuracy, not byte by byte.
TEST(RecordingRuns, EsimAsAedat4TracksAsTheFolder) {
  EDS_REQUIRE_SHARED(dir, "esim_poster6dof_planar");
  EDS_REQUIRE_AVAILABLE(std::system("/usr/bin/python3 -c 'import flatbuffers, PIL' > /dev/null 2>&1") == 0 &&
                            std::system("lz4 --version > /dev/null 2>&1") == 0,
                        "Debian python3-flatbuffers, python3-pil, lz4");
  const auto out = test::tempDir("aedat_runs");
  const std::string cmd = "/usr/bin/python3 " EDS_SOURCE_DIR "/tests/tools/write_aedat4.py " + dir.string() +
                          " " + (out / "esim.aedat4").string() + " lz4 2.0";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  OdometryConfig cfg = syncConfig();
  cfg.duration_s = 2.0;
  const Sequence folder(dir);
  Sequence aedat(out / "esim.aedat4");
  aedat.setCamera(readCameraFile(dir / "calib.txt"), "calib.txt");
  const OdometryResult a = runOdometry(folder, cfg), b = runOdometry(aedat, cfg);
  ASSERT_TRUE(a.initialized);
  ASSERT_TRUE(b.initialized);
  EXPECT_EQ(b.init_t, a.init_t);
  EXPECT_EQ(b.event_frames, a.event_frames);
  const eval::AteResult ea = eval::evaluateAte(a.events_refined, folder.groundTruth(), eval::EvalConfig{});
  const eval::AteResult eb = eval::evaluateAte(b.events_refined, folder.groundTruth(), eval::EvalConfig{});
  std::printf("[ ESIM 2 s, folder / AEDAT 4.0 ] ATE %.4f / %.4f cm, rot %.4f / %.4f deg\n",
              ea.trans.rmse * 100, eb.trans.rmse * 100, ea.rot.rmse, eb.rot.rmse);
  EXPECT_LE(eb.trans.rmse * 100, test::translationBoundCm(ea.trans.rmse * 100));
  EXPECT_LE(eb.rot.rmse, 1.5 * ea.rot.rmse);
}

}  // namespace
}  // namespace eds
