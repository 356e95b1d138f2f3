#include <gtest/gtest.h>
#include <hdf5.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "io/hdf5_events.hpp"
#include "io/read_events.hpp"
#include "test_data.hpp"

namespace eds {
namespace {

namespace fs = std::filesystem;

// A directory of its own per test, removed afterwards.
class TempDir {
 public:
  TempDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("eds_h5_" + std::to_string(::getpid()) + "_" + info->test_suite_name() + "_" + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  std::string file(const std::string& name) const { return (dir_ / name).string(); }

 private:
  fs::path dir_;
};

// Whole-microsecond times (the file's resolution), with repeated stamps and gaps of a few ms so
// that some ms_to_idx entries point at the same event.
EventArray makeEvents(std::size_t n, std::uint32_t seed, TimeNs t0 = 0) {
  std::mt19937 rng(seed);
  EventArray ev;
  ev.reserve(n);
  TimeNs t = t0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t r = rng();
    t += 1000 * ((r % 97 == 0) ? 2500 + r % 4000 : r % 4);
    ev.push_back(t, static_cast<std::uint16_t>(rng() % 640), static_cast<std::uint16_t>(rng() % 480),
                 (rng() & 1) ? 1 : -1);
  }
  return ev;
}

void expectEqual(const EventArray& a, const EventArray& b) {
  ASSERT_EQ(a.size(), b.size());
  EXPECT_TRUE(a.t == b.t);
  EXPECT_TRUE(a.x == b.x);
  EXPECT_TRUE(a.y == b.y);
  EXPECT_TRUE(a.p == b.p);
}

// Writes datasets of arbitrary types and shapes, for inputs the eds writer would never produce.
class RawFile {
 public:
  explicit RawFile(const std::string& path)
      : file_(H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT)) {
    H5Gclose(H5Gcreate2(file_, "events", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  }
  ~RawFile() { H5Fclose(file_); }
  void add(const char* name, hid_t ftype, const std::vector<double>& values, int rank = 1) {
    const hsize_t dims[2] = {rank == 2 ? values.size() / 2 : values.size(), 2};
    const hid_t space = H5Screate_simple(rank, dims, nullptr);
    const hid_t ds = H5Dcreate2(file_, name, ftype, space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    if (!values.empty()) H5Dwrite(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data());
    H5Dclose(ds);
    H5Sclose(space);
  }
  // A small valid file: 4 events at 10, 20, 30, 40 µs, with fields replaced as asked.
  void addEvents(const std::vector<double>& t = {10, 20, 30, 40},
                 const std::vector<double>& p = {0, 1, 1, 0}) {
    add("events/t", H5T_STD_I64LE, t);
    add("events/x", H5T_STD_U16LE, {1, 2, 3, 4});
    add("events/y", H5T_STD_U16LE, {5, 6, 7, 8});
    add("events/p", H5T_STD_U8LE, p);
  }

 private:
  hid_t file_;
};

// Asserts that fn throws InputError whose message names the file and contains `part`.
void expectInputError(const std::function<void()>& fn, const std::string& file, const std::string& part) {
  try {
    fn();
    ADD_FAILURE() << "no InputError for " << file << " (expected '" << part << "')";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(file), std::string::npos) << msg;
    EXPECT_NE(msg.find(part), std::string::npos) << msg;
  }
}

void readFile(const std::string& path, Hdf5EventOptions opt = {}) {
  Hdf5EventSource src(path, opt);
  test::readAll(src, 3);
}

unsigned firstFilter(const std::string& path, const char* dataset) {
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  const hid_t ds = H5Dopen2(file, dataset, H5P_DEFAULT);
  const hid_t dcpl = H5Dget_create_plist(ds);
  unsigned flags = 0;
  std::size_t n = 0;
  const H5Z_filter_t last =
      H5Pget_nfilters(dcpl) > 0
          ? H5Pget_filter2(dcpl, H5Pget_nfilters(dcpl) - 1, &flags, &n, nullptr, 0, nullptr, nullptr)
          : H5Z_FILTER_NONE;
  H5Pclose(dcpl);
  H5Dclose(ds);
  H5Fclose(file);
  return static_cast<unsigned>(last);
}

TEST(Hdf5Events, RoundTripExactValues) {
  TempDir dir;
  const std::string path = dir.file("events.h5");
  const EventArray ev = makeEvents(100'000, 1);
  EXPECT_EQ(writeHdf5Events(path, ev, 0), Hdf5Compression::kNone);
  Hdf5EventSource src(path, {640, 480});
  ASSERT_EQ(src.size(), ev.size());
  EXPECT_EQ(src.firstTimeNs(), ev.t.front());
  EXPECT_EQ(src.lastTimeNs(), ev.t.back());
  EventArray out;
  EXPECT_EQ(src.read(out, 1'000'000), ev.size());
  EXPECT_EQ(src.read(out, 1'000'000), 0u);
  expectEqual(out, ev);
  EXPECT_EQ(out.t[0], ev.t[0]);
  EXPECT_EQ(out.p[12345], ev.p[12345]);
  EXPECT_EQ(out.x.back(), ev.x.back());
}

TEST(Hdf5Events, ChunkedReadsAppendAcrossBoundaries) {
  TempDir dir;
  const std::string path = dir.file("events.h5");
  const EventArray ev = makeEvents(50'000, 2);
  writeHdf5Events(path, ev, 0, Hdf5Compression::kGzip);  // file chunks of 32768 elements
  for (std::size_t chunk : {1u, 777u, 4096u, 49'999u}) {
    Hdf5EventSource src(path);
    EventArray out;
    out.push_back(-5, 0, 0, 1);  // read appends and must keep what is there
    std::size_t calls = 0;
    while (src.read(out, chunk) > 0) ++calls;
    EXPECT_EQ(calls, (ev.size() + chunk - 1) / chunk);
    EXPECT_EQ(out.t.front(), -5);
    out.t.erase(out.t.begin());
    out.x.erase(out.x.begin());
    out.y.erase(out.y.begin());
    out.p.erase(out.p.begin());
    expectEqual(out, ev);
  }
}

TEST(Hdf5Events, TimeOffsetIsAdded) {
  TempDir dir;
  const std::string path = dir.file("dsec.h5");
  constexpr std::int64_t kOffsetUs = 1'627'000'000'000'000;  // a DSEC-like epoch offset
  const EventArray ev = makeEvents(10'000, 3, kOffsetUs * 1000 + 17'000);
  writeHdf5Events(path, ev, kOffsetUs);
  Hdf5EventSource src(path);
  EXPECT_EQ(src.tOffsetNs(), kOffsetUs * 1000);
  expectEqual(test::readAll(src, 1000), ev);

  // The stored values are relative to t_offset.
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  const hid_t ds = H5Dopen2(file, "events/t", H5P_DEFAULT);
  std::vector<std::int64_t> t(ev.size());
  H5Dread(ds, H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, t.data());
  H5Dclose(ds);
  H5Fclose(file);
  EXPECT_EQ(t[0] + kOffsetUs, ev.t[0] / 1000);
  EXPECT_LT(t[0], 17 + 4);
  EXPECT_EQ(t.back() * 1000 + kOffsetUs * 1000, ev.t.back());
}

TEST(Hdf5Events, MsToIdxFollowsDsecSemantics) {
  TempDir dir;
  const std::string path = dir.file("events.h5");
  const EventArray ev = makeEvents(20'000, 4, 3'000'000);
  writeHdf5Events(path, ev, 1000);  // t_offset 1 ms: stored times start at 2 ms
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  const hid_t ds = H5Dopen2(file, "ms_to_idx", H5P_DEFAULT);
  const hid_t space = H5Dget_space(ds);
  std::vector<std::uint64_t> idx(static_cast<std::size_t>(H5Sget_simple_extent_npoints(space)));
  H5Dread(ds, H5T_NATIVE_UINT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, idx.data());
  H5Sclose(space);
  H5Dclose(ds);
  H5Fclose(file);
  const std::int64_t last_rel_us = ev.t.back() / 1000 - 1000;
  ASSERT_EQ(idx.size(), static_cast<std::size_t>(last_rel_us / 1000 + 1));
  for (std::size_t ms = 0; ms < idx.size(); ++ms) {
    const TimeNs start_ns = (static_cast<TimeNs>(ms) * 1000 + 1000) * 1000;  // + t_offset
    const auto first = std::lower_bound(ev.t.begin(), ev.t.end(), start_ns) - ev.t.begin();
    ASSERT_EQ(idx[ms], static_cast<std::uint64_t>(first)) << "ms " << ms;
  }
  EXPECT_EQ(idx[0], 0u);
  EXPECT_EQ(idx[2], 0u);
  EXPECT_GT(idx[3], 0u);
}

void checkSeeks(const std::string& path, const EventArray& ev, bool expect_ms_to_idx) {
  Hdf5EventSource src(path);
  EXPECT_EQ(src.hasMsToIdx(), expect_ms_to_idx);
  std::mt19937 rng(5);
  std::vector<TimeNs> targets = {ev.t.front() - 5'000'000, ev.t.front(),
                                 ev.t.front() + 1,         ev.t.back(),
                                 ev.t.back() + 1,          ev.t.back() + 10'000'000};
  targets.push_back(std::numeric_limits<TimeNs>::min());  // saturates instead of overflowing
  targets.push_back(std::numeric_limits<TimeNs>::max());
  for (int i = 0; i < 200; ++i) {
    targets.push_back(ev.t.front() + static_cast<TimeNs>(rng() % (ev.t.back() - ev.t.front())));
    targets.push_back(ev.t[rng() % ev.size()]);  // exact stamps, often repeated ones
  }
  for (const TimeNs target : targets) {
    src.seek(target);
    const auto want =
        static_cast<std::size_t>(std::lower_bound(ev.t.begin(), ev.t.end(), target) - ev.t.begin());
    ASSERT_EQ(src.position(), want) << "seek " << target;
    EventArray out;
    if (want < ev.size()) {
      ASSERT_EQ(src.read(out, 2), std::min<std::size_t>(2, ev.size() - want));
      EXPECT_EQ(out.t[0], ev.t[want]);
      EXPECT_EQ(out.x[0], ev.x[want]);
    } else {
      EXPECT_EQ(src.read(out, 2), 0u);
    }
  }
}

TEST(Hdf5Events, SeekUsesMsToIdx) {
  TempDir dir;
  const std::string path = dir.file("events.h5");
  const EventArray ev = makeEvents(30'000, 6, 123'456'000);
  writeHdf5Events(path, ev, 100'000);
  checkSeeks(path, ev, true);
}

TEST(Hdf5Events, SeekWithoutMsToIdxBinarySearches) {
  TempDir dir;
  const std::string path = dir.file("no_index.h5");
  const EventArray ev = makeEvents(5'000, 7, 1'000'000);
  {
    RawFile raw(path);
    std::vector<double> t, x, y, p;
    for (std::size_t i = 0; i < ev.size(); ++i) {
      t.push_back(static_cast<double>(ev.t[i] / 1000));
      x.push_back(ev.x[i]);
      y.push_back(ev.y[i]);
      p.push_back(ev.p[i]);  // stored as -1/+1 in an int8
    }
    raw.add("events/t", H5T_STD_U32LE, t);
    raw.add("events/x", H5T_STD_I32BE, x);
    raw.add("events/y", H5T_STD_U16BE, y);
    raw.add("events/p", H5T_STD_I8LE, p);
  }
  checkSeeks(path, ev, false);
}

TEST(Hdf5Events, AcceptsOtherIntegerTypes) {
  TempDir dir;
  const std::string path = dir.file("types.h5");
  {
    RawFile raw(path);
    raw.add("events/t", H5T_STD_U64BE, {5, 6, 6, 9});
    raw.add("events/x", H5T_STD_I64LE, {0, 639, 65535, 2});
    raw.add("events/y", H5T_STD_U8LE, {1, 255, 3, 4});
    raw.add("events/p", H5T_STD_I16LE, {-1, 1, 0, 1});
  }
  Hdf5EventSource src(path);
  const EventArray out = test::readAll(src, 3);
  EXPECT_EQ(out.t, (std::vector<TimeNs>{5000, 6000, 6000, 9000}));
  EXPECT_EQ(out.x, (std::vector<std::uint16_t>{0, 639, 65535, 2}));
  EXPECT_EQ(out.y, (std::vector<std::uint16_t>{1, 255, 3, 4}));
  EXPECT_EQ(out.p, (std::vector<std::int8_t>{-1, 1, -1, 1}));
  EXPECT_FALSE(src.hasMsToIdx());
  EXPECT_EQ(src.tOffsetNs(), 0);
}

TEST(Hdf5Events, GzipRoundTrip) {
  TempDir dir;
  const std::string path = dir.file("gzip.h5");
  const EventArray ev = makeEvents(300'000, 8);
  EXPECT_EQ(writeHdf5Events(path, ev, 42, Hdf5Compression::kGzip), Hdf5Compression::kGzip);
  EXPECT_EQ(firstFilter(path, "events/t"), unsigned{H5Z_FILTER_DEFLATE});
  Hdf5EventSource src(path);
  expectEqual(test::readAll(src, 100'000), ev);
  checkSeeks(path, ev, true);
}

TEST(Hdf5Events, BloscRoundTripThroughDebianPlugin) {
  EDS_REQUIRE_AVAILABLE(hdf5BloscAvailable(),
                        "HDF5's blosc filter (install hdf5-filter-plugin-blosc-serial)");
  TempDir dir;
  const std::string path = dir.file("blosc.h5");
  const EventArray ev = makeEvents(300'000, 9);
  ASSERT_EQ(writeHdf5Events(path, ev, 0, Hdf5Compression::kBloscIfAvailable),
            Hdf5Compression::kBloscIfAvailable);
  EXPECT_EQ(firstFilter(path, "events/x"), 32001u);
  Hdf5EventSource src(path);
  expectEqual(test::readAll(src, 65'536), ev);
}

// ---- bad inputs: every error is an InputError naming the file ----

TEST(Hdf5EventsBad, MissingFile) {
  TempDir dir;
  const std::string path = dir.file("nope.h5");
  expectInputError([&] { readFile(path); }, path, "does not exist");
}

TEST(Hdf5EventsBad, NotHdf5AndHdf5StaysQuiet) {
  TempDir dir;
  const std::string path = dir.file("text.h5");
  std::ofstream(path) << "0.1 2 3 1\n";
  ::testing::internal::CaptureStderr();
  expectInputError([&] { readFile(path); }, path, "not an HDF5 file");
  expectInputError([&] { readFile(dir.file("")); }, dir.file(""), "not a regular file");
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
}

TEST(Hdf5EventsBad, MissingGroupOrDataset) {
  TempDir dir;
  const std::string path = dir.file("missing.h5");
  {
    RawFile raw(path);
    raw.add("events/t", H5T_STD_I64LE, {1, 2});
    raw.add("events/x", H5T_STD_U16LE, {1, 2});
    raw.add("events/y", H5T_STD_U16LE, {1, 2});
  }
  expectInputError([&] { readFile(path); }, path, "missing dataset events/p");
  const std::string flat = dir.file("flat.h5");
  H5Fclose(H5Fcreate(flat.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT));
  expectInputError([&] { readFile(flat); }, flat, "missing group 'events'");
}

TEST(Hdf5EventsBad, DifferentLengths) {
  TempDir dir;
  const std::string path = dir.file("lengths.h5");
  {
    RawFile raw(path);
    raw.add("events/t", H5T_STD_I64LE, {1, 2, 3});
    raw.add("events/x", H5T_STD_U16LE, {1, 2, 3});
    raw.add("events/y", H5T_STD_U16LE, {1, 2});
    raw.add("events/p", H5T_STD_U8LE, {1, 0, 1});
  }
  expectInputError([&] { readFile(path); }, path, "events/y has 2 elements but events/t has 3");
}

TEST(Hdf5EventsBad, DecreasingTimestampsNameTheIndex) {
  TempDir dir;
  const std::string path = dir.file("order.h5");
  RawFile(path).addEvents({10, 20, 30, 25});
  expectInputError([&] { readFile(path); }, path, "events/t[3] = 25");
  // Across a read boundary: the last event of one read against the first of the next.
  Hdf5EventSource src(path);
  EventArray out;
  EXPECT_EQ(src.read(out, 3), 3u);
  expectInputError([&] { src.read(out, 3); }, path, "events/t[3]");
  EXPECT_EQ(out.size(), 3u);  // a failed read leaves out as it was
}

TEST(Hdf5EventsBad, PolarityNotBinary) {
  TempDir dir;
  const std::string path = dir.file("polarity.h5");
  RawFile(path).addEvents({10, 20, 30, 40}, {0, 1, 2, 1});
  expectInputError([&] { readFile(path); }, path, "events/p[2] = 2");
  const std::string neg = dir.file("polarity255.h5");
  RawFile(neg).addEvents({10, 20, 30, 40}, {0, 255, 1, 1});  // uint8: -1 is not possible
  expectInputError([&] { readFile(neg); }, neg, "events/p[1] = 255");
}

TEST(Hdf5EventsBad, PixelOutsideSensor) {
  TempDir dir;
  const std::string path = dir.file("pixels.h5");
  RawFile(path).addEvents();  // x up to 4, y up to 8
  EXPECT_NO_THROW(readFile(path, {5, 9}));
  EXPECT_NO_THROW(readFile(path, {70'000, 70'000}));
  expectInputError([&] { readFile(path, {4, 9}); }, path, "events/x[3] = 4 is outside");
  expectInputError([&] { readFile(path, {5, 7}); }, path, "events/y[2] = 7 is outside");
}

TEST(Hdf5EventsBad, EmptyDataset) {
  TempDir dir;
  const std::string path = dir.file("empty.h5");
  writeHdf5Events(path, EventArray{}, 0);
  expectInputError([&] { readFile(path); }, path, "events/t is empty");
}

TEST(Hdf5EventsBad, ValueOutOfRangeForField) {
  TempDir dir;
  const std::string path = dir.file("range.h5");
  {
    RawFile raw(path);
    raw.add("events/t", H5T_STD_I64LE, {1, 2, 3});
    raw.add("events/x", H5T_STD_I32LE, {1, -2, 3});  // would be clipped to 0 silently
    raw.add("events/y", H5T_STD_U16LE, {1, 2, 3});
    raw.add("events/p", H5T_STD_U8LE, {1, 0, 1});
  }
  expectInputError([&] { readFile(path); }, path, "events/x[0..3) holds a value out of range");
}

TEST(Hdf5EventsBad, WrongTypeOrShape) {
  TempDir dir;
  const std::string floats = dir.file("float.h5");
  {
    RawFile raw(floats);
    raw.add("events/t", H5T_IEEE_F64LE, {1, 2});
    raw.add("events/x", H5T_STD_U16LE, {1, 2});
    raw.add("events/y", H5T_STD_U16LE, {1, 2});
    raw.add("events/p", H5T_STD_U8LE, {1, 0});
  }
  expectInputError([&] { readFile(floats); }, floats, "events/t does not hold integers");
  const std::string shape = dir.file("shape.h5");
  {
    RawFile raw(shape);
    raw.add("events/t", H5T_STD_I64LE, {1, 2});
    raw.add("events/x", H5T_STD_U16LE, {1, 2, 3, 4}, 2);
    raw.add("events/y", H5T_STD_U16LE, {1, 2});
    raw.add("events/p", H5T_STD_U8LE, {1, 0});
  }
  expectInputError([&] { readFile(shape); }, shape, "events/x is not a 1-D array");
}

TEST(Hdf5EventsBad, TimeOffsetOverflow) {
  TempDir dir;
  const std::string path = dir.file("overflow.h5");
  {
    RawFile raw(path);
    raw.addEvents();
    raw.add("t_offset", H5T_STD_I64LE, {9.3e15});  // a 1-element array is accepted too
  }
  expectInputError([&] { readFile(path); }, path, "overflows int64 ns");
}

}  // namespace
}  // namespace eds
