// Parameters by name: config_used.yaml round-trips, a --config file overrides, bad files name the line.
#include <gtest/gtest.h>

#include <cstdio>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "system/odometry_config_io.hpp"
#include "test_data.hpp"

namespace eds {
namespace {

template <class T>
constexpr bool kNested = requires(T& t) {
  visitFields([](const char*, auto&) {}, t);
};

// Every configuration struct reached from OdometryConfig lists all of its members in visitFields.
struct CheckListed {
  std::string path;
  std::vector<std::string>* problems;
  template <class T>
  void operator()(const char* name, T& field) {
    if constexpr (kNested<T>) check(path + name, field);
  }
  template <class T>
  void check(const std::string& where, T& cfg) {
    std::size_t listed = 0;
    visitFields([&listed](const char*, auto&) { ++listed; }, cfg);
    if (listed != fieldCount<T>())
      problems->push_back(where + ": " + std::to_string(fieldCount<T>()) + " members, " +
                          std::to_string(listed) + " listed in visitFields");
    CheckListed nested{where + ".", problems};
    visitFields(nested, cfg);
  }
};

// Every leaf's value as text, by dotted name.
struct Dump {
  std::string path;
  std::map<std::string, std::string>* out;
  template <class T>
  void operator()(const char* name, T& field) {
    if constexpr (kNested<T>) {
      Dump nested{path + name + ".", out};
      visitFields(nested, field);
    } else if constexpr (std::is_enum_v<T>) {
      (*out)[path + name] = std::to_string(static_cast<int>(field));
    } else {
      char buf[64];
      std::snprintf(buf, sizeof buf, "%.17g", static_cast<double>(field));
      (*out)[path + name] = buf;
    }
  }
};

// Moves every leaf off its default: numbers by a field-specific amount, flags flipped, enumerations to
// their next value.
struct Perturb {
  int k = 0;
  template <class T>
  void operator()(const char*, T& field) {
    ++k;
    if constexpr (kNested<T>) {
      visitFields(*this, field);
    } else if constexpr (std::is_same_v<T, bool>) {
      field = !field;
    } else if constexpr (std::is_enum_v<T>) {
      const auto names = enumNames(T{});
      for (std::size_t i = 0; i < names.size(); ++i)
        if (names[i].first == field) {
          field = names[(i + 1) % names.size()].first;
          break;
        }
    } else if constexpr (std::is_integral_v<T>) {
      field += 1 + k % 7;
    } else {
      field = field * 1.5 + 0.001 * k + 0.125;
    }
  }
};

std::map<std::string, std::string> dump(OdometryConfig& c) {
  std::map<std::string, std::string> m;
  Dump d{"", &m};
  visitFields(d, c);
  return m;
}

TEST(OdometryConfigIo, EveryMemberOfEveryConfigurationStructIsListed) {
  std::vector<std::string> problems;
  OdometryConfig c;
  CheckListed{"", &problems}.check("OdometryConfig", c);
  for (const std::string& p : problems) ADD_FAILURE() << p;
  EXPECT_GT(dump(c).size(), 120u);
}

TEST(OdometryConfigIo, EveryParameterSurvivesTheFileAtANonDefaultValue) {
  const auto dir = test::tempDir("config_all");
  OdometryConfig defaults, a;
  Perturb perturb;
  visitFields(perturb, a);
  const auto d = dump(defaults), va = dump(a);
  ASSERT_EQ(d.size(), va.size());
  for (const auto& [key, value] : va) EXPECT_NE(value, d.at(key)) << key << " kept its default";
  saveOdometryConfig(dir / "all.yaml", a);
  OdometryConfig b;
  loadOdometryConfig(dir / "all.yaml", b);
  const auto vb = dump(b);
  for (const auto& [key, value] : va) EXPECT_EQ(vb.at(key), value) << key;
  // The names the file uses are the ones --set and odometryParameterNames give.
  const std::vector<std::string> names = odometryParameterNames();
  EXPECT_EQ(names.size(), va.size());
  for (const std::string& n : names) EXPECT_TRUE(va.count(n)) << n;
}

TEST(OdometryConfigIo, SetTakesAnyParameterByNameAndNamedValues) {
  OdometryConfig c;
  setOdometryParameter(c, "bootstrap.tracker.levels=5");
  setOdometryParameter(c, "backend.removal=oldest");
  setOdometryParameter(c, "events.motion_prior.enabled=false");
  setOdometryParameter(c, "event_frame.overlap=0.25");
  EXPECT_EQ(c.bootstrap.tracker.levels, 5);
  EXPECT_EQ(c.backend.removal, WindowRemoval::kOldest);
  EXPECT_FALSE(c.events.motion_prior.enabled);
  EXPECT_DOUBLE_EQ(c.event_frame.overlap, 0.25);
  EXPECT_THROW(setOdometryParameter(c, "backend.removal=newest"), std::invalid_argument);
  EXPECT_THROW(setOdometryParameter(c, "backend.window=many"), std::invalid_argument);
  EXPECT_THROW(setOdometryParameter(c, "backend.windows=3"), std::invalid_argument);
  EXPECT_THROW(setOdometryParameter(c, "backend.window"), std::invalid_argument);
}

TEST(OdometryConfigIo, RoundTripsEveryParameter) {
  const auto dir = test::tempDir("config_io");
  OdometryConfig a;
  a.backend.window = 5;
  a.bootstrap.geometric_init.min_parallax_deg = 2.25;
  a.mapping.epipolar_search = false;
  a.events.tracker.levels = 2;
  a.frame_rate = 12.5;
  saveOdometryConfig(dir / "c.yaml", a);
  OdometryConfig b;
  loadOdometryConfig(dir / "c.yaml", b);
  EXPECT_EQ(b.backend.window, 5);
  EXPECT_DOUBLE_EQ(b.bootstrap.geometric_init.min_parallax_deg, 2.25);
  EXPECT_FALSE(b.mapping.epipolar_search);
  EXPECT_EQ(b.events.tracker.levels, 2);
  EXPECT_DOUBLE_EQ(b.frame_rate, 12.5);
  // Writing what was read gives the same file, so nothing is lost or renamed on the way.
  saveOdometryConfig(dir / "d.yaml", b);
  std::ifstream f1(dir / "c.yaml"), f2(dir / "d.yaml");
  const std::string s1((std::istreambuf_iterator<char>(f1)), {}),
      s2((std::istreambuf_iterator<char>(f2)), {});
  EXPECT_EQ(s1, s2);
  EXPECT_GT(s1.size(), 2000u);  // every parameter, not just the changed ones
  std::filesystem::remove_all(dir);
}

TEST(OdometryConfigIo, PartialFileOverridesOnlyWhatItNames) {
  const auto dir = test::tempDir("config_partial");
  std::ofstream(dir / "c.yaml") << "backend:\n  window: 9\npolicy: {flow_t: 0.03}\n"
                                   "bootstrap: {tracker: {levels: 3}}\n";
  OdometryConfig c;
  loadOdometryConfig(dir / "c.yaml", c);
  EXPECT_EQ(c.backend.window, 9);
  EXPECT_EQ(c.bootstrap.tracker.levels, 3);
  EXPECT_DOUBLE_EQ(c.policy.flow_t, 0.03);
  EXPECT_EQ(c.backend.points_per_keyframe, OdometryConfig{}.backend.points_per_keyframe);
  OdometryConfig d;
  copyOdometryParameter(c, d, "backend.window");
  EXPECT_EQ(d.backend.window, 9);
  EXPECT_THROW(copyOdometryParameter(c, d, "backend.nope"), std::invalid_argument);
  std::filesystem::remove_all(dir);
}

TEST(OdometryConfigIo, BadFilesNameFileLineAndKey) {
  const auto dir = test::tempDir("config_bad");
  const auto expectError = [&](const std::string& text, const std::string& needle) {
    std::ofstream(dir / "c.yaml") << text;
    OdometryConfig c;
    try {
      loadOdometryConfig(dir / "c.yaml", c);
      FAIL() << "no error for: " << text;
    } catch (const InputError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("c.yaml"), std::string::npos) << what;
      EXPECT_NE(what.find(needle), std::string::npos) << what;
    }
  };
  expectError("backend:\n  windw: 3\n", "line 2: unknown parameter 'backend.windw'");
  expectError("backend:\n  window: many\n", "line 2: bad value for 'backend.window'");
  expectError("backend: [1, 2\n", "line");
  expectError("- 1\n- 2\n", "expected a map");
  OdometryConfig c;
  EXPECT_THROW(loadOdometryConfig(dir / "missing.yaml", c), InputError);
  std::filesystem::remove_all(dir);
}

TEST(OdometryConfigIo, DefaultsFollowTheSensorSize) {
  const OdometryConfig base;
  const OdometryConfig small = defaultOdometryConfig(240, 180);
  EXPECT_EQ(small.event_frame.num_events, base.event_frame.num_events);
  EXPECT_EQ(small.events.points.fraction, base.events.points.fraction);
  EXPECT_EQ(small.frame_tracker.levels, base.frame_tracker.levels);
  // The EDS dataset's 640x480: the authors' 80k events, 60 % overlap, 7 % of the pixels.
  const OdometryConfig vga = defaultOdometryConfig(640, 480);
  EXPECT_EQ(vga.event_frame.num_events, 80000);
  EXPECT_NEAR(vga.event_frame.overlap, 0.6, 1e-12);
  EXPECT_NEAR(vga.events.points.fraction, 0.07, 1e-12);
  EXPECT_EQ(vga.frame_tracker.levels, base.frame_tracker.levels + 1);
  EXPECT_EQ(vga.backend.points_per_keyframe, base.backend.points_per_keyframe);
  EXPECT_EQ(small.event_frame.max_rate_hz, 0.0);  // no cap where event rates are a few M/s
  EXPECT_EQ(vga.event_frame.max_rate_hz, 100.0);
  EXPECT_TRUE(small.event_frame.reversal_compensation);
  EXPECT_FALSE(vga.event_frame.reversal_compensation);
  EXPECT_EQ(small.bootstrap.geometric_init.ransac_px, base.bootstrap.geometric_init.ransac_px);
  EXPECT_EQ(vga.bootstrap.geometric_init.ransac_px, 2 * base.bootstrap.geometric_init.ransac_px);
  EXPECT_EQ(vga.bootstrap.geometric_init.max_reproj_px, 2 * base.bootstrap.geometric_init.max_reproj_px);
  EXPECT_EQ(small.bootstrap.final_views, base.bootstrap.final_views);
  EXPECT_EQ(vga.bootstrap.final_views, 5);
  EXPECT_EQ(defaultOdometryConfig(1280, 720).event_frame.num_events, 80000);
  // DAVIS346 (346x260) lies in between.
  const int n346 = defaultOdometryConfig(346, 260).event_frame.num_events;
  EXPECT_GT(n346, 20000);
  EXPECT_LT(n346, 40000);
  EXPECT_THROW(defaultOdometryConfig(0, 480), std::invalid_argument);
  // A file still overrides them.
  const auto dir = test::tempDir("sensor_defaults");
  { std::ofstream(dir / "c.yaml") << "event_frame:\n  num_events: 50000\n"; }
  OdometryConfig c = vga;
  loadOdometryConfig(dir / "c.yaml", c);
  EXPECT_EQ(c.event_frame.num_events, 50000);
  EXPECT_NEAR(c.event_frame.overlap, 0.6, 1e-12);
}

}  // namespace
}  // namespace eds
