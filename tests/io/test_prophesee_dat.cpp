// Prophesee .dat CD files, written by tests/tools/write_dat.py with NumPy as Prophesee documents the
// layout: every event comes out to the microsecond, and damaged files are refused by name and offset.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "core/error.hpp"
#include "io/read_events.hpp"
#include "io/sequence.hpp"
#include "test_data.hpp"

namespace eds {
namespace {

namespace fs = std::filesystem;

fs::path writeDat(const fs::path& esim, const fs::path& out, const std::string& options = "") {
  const std::string cmd = "/usr/bin/python3 " EDS_SOURCE_DIR "/tests/tools/write_dat.py " + esim.string() +
                          " " + out.string() + " 0.2 " + options;
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
  return out;
}

#define EDS_REQUIRE_DAT_WRITER(esim)                                                             \
  EDS_REQUIRE_SHARED(esim, "esim_poster6dof_planar");                                            \
  EDS_REQUIRE_AVAILABLE(std::system("/usr/bin/python3 -c 'import numpy' > /dev/null 2>&1") == 0, \
                        "python3-numpy")

TEST(PropheseeDat, EsimAsDatGivesEveryEventToTheMicrosecond) {
  EDS_REQUIRE_DAT_WRITER(esim);
  const fs::path dir = test::tempDir("dat");
  const Sequence dat(writeDat(esim, dir / "esim.dat")), folder(esim);
  EXPECT_EQ(dat.format(), "Prophesee DAT (CD events)");
  EXPECT_EQ(dat.width(), 240);
  EXPECT_EQ(dat.height(), 180);
  auto a = folder.openEvents();
  EventArray expected;
  while (a->read(expected, 1 << 16) > 0 && expected.t.back() <= 200'000'000) {
  }
  while (!expected.empty() && expected.t.back() > 200'000'000) expected.resize(expected.size() - 1);
  auto b = dat.openEvents();
  const EventArray got = test::readAll(*b, 5000);
  ASSERT_EQ(got.size(), expected.size());
  ASSERT_GT(got.size(), 4'000u);
  for (std::size_t i = 0; i < got.size(); ++i) {
    ASSERT_EQ(got.t[i], expected.t[i] / 1000 * 1000) << i;
    ASSERT_EQ(got.x[i], expected.x[i]) << i;
    ASSERT_EQ(got.y[i], expected.y[i]) << i;
    ASSERT_EQ(got.p[i], expected.p[i]) << i;
  }
}

TEST(PropheseeDat, DamagedFilesAreRefusedNamingFileAndOffset) {
  EDS_REQUIRE_DAT_WRITER(esim);
  const fs::path dir = test::tempDir("dat_bad");
  const std::pair<std::string, std::string> cases[] = {
      {"--type 3", "event type 3 of 8 bytes is not read"},
      {"--size 16", "event type 12 of 16 bytes is not read"},
      {"--width 200", "outside the 200x180 sensor"},
  };
  int k = 0;
  for (const auto& [options, what] : cases) {
    SCOPED_TRACE(options);
    const fs::path file = writeDat(esim, dir / ("bad" + std::to_string(k++) + ".dat"), options);
    try {
      const Sequence seq(file);
      auto src = seq.openEvents();
      test::readAll(*src, 1 << 16);
      ADD_FAILURE() << "accepted";
    } catch (const InputError& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(file.string()), std::string::npos) << msg;
      EXPECT_NE(msg.find(what), std::string::npos) << msg;
      EXPECT_NE(msg.find("byte "), std::string::npos) << msg;
    }
  }
  // Cut inside the last record: the events before it, then an error at the cut.
  const fs::path cut = writeDat(esim, dir / "cut.dat");
  fs::resize_file(cut, fs::file_size(cut) - 3);
  const Sequence seq(cut);
  auto src = seq.openEvents();
  EXPECT_THROW(test::readAll(*src, 1 << 16), InputError);
}

}  // namespace
}  // namespace eds
