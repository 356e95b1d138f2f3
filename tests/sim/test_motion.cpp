// Camera motion (interpolation, smoothing, cutting, the built-in hand-held motion) and the preset
// scenes placed along it.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <numbers>
#include <random>
#include <set>

#include "core/error.hpp"
#include "sim/motion.hpp"
#include "sim/presets.hpp"
#include "sim/textures.hpp"
#include "test_data.hpp"

namespace eds::sim {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

double angleBetween(const SE3& a, const SE3& b) { return (a.so3().inverse() * b.so3()).angle(); }

TEST(Motion, InterpolatesLinearPositionAndSlerpRotation) {
  const Vec3 axis = Vec3(1, 1, 0).normalized();
  const SE3 a(SO3::exp(Vec3(0.1, -0.2, 0.3)), Vec3(1, 2, 3));
  const SE3 b(a.so3() * SO3::exp(axis * 60 * kDeg), Vec3(2, 0, 5));
  const Motion m({{kNsPerSec, a}, {3 * kNsPerSec, b}});
  for (const double s : {0.25, 0.5, 0.75}) {
    const SE3 p = m.pose(kNsPerSec + fromSeconds(2.0 * s));
    EXPECT_NEAR((p.translation() - ((1 - s) * a.translation() + s * b.translation())).norm(), 0, 1e-12);
    const Vec3 rel = (a.so3().inverse() * p.so3()).log();
    EXPECT_NEAR(rel.norm(), s * 60 * kDeg, 1e-12);
    EXPECT_NEAR((rel.normalized() - axis).norm(), 0, 1e-9);
  }
  // Clamped outside the span.
  EXPECT_EQ(m.pose(0).translation(), a.translation());
  EXPECT_EQ(m.pose(10 * kNsPerSec).translation(), b.translation());
  EXPECT_NEAR(angleBetween(m.pose(10 * kNsPerSec), b), 0, 1e-12);
  EXPECT_EQ(m.start(), kNsPerSec);
  EXPECT_EQ(m.end(), 3 * kNsPerSec);
  EXPECT_THROW(Motion({{0, a}}), std::invalid_argument);
  EXPECT_THROW(Motion({{5, a}, {4, b}}), std::invalid_argument);
}

// A gentle curve (its smoothing bias is far below the noise), sampled at 200 Hz for 4 s.
SE3 cleanPose(double t) {
  const double w = 2 * std::numbers::pi;
  const Vec3 p(0.2 * std::sin(w * 0.1 * t), 0.15 * std::sin(w * 0.15 * t + 1), 0.1 * t);
  const Vec3 r(0.1 * std::sin(w * 0.1 * t), 0.2 * std::cos(w * 0.12 * t), 0.05 * t);
  return SE3(SO3::exp(r), p);
}

TEST(Smoothing, RemovesJitter) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> noise(-0.002, 0.002);
  Trajectory clean, noisy;
  for (int k = 0; k <= 800; ++k) {
    const double t = k * 0.005;
    clean.push_back({fromSeconds(t), cleanPose(t)});
    const SE3& c = clean.back().T_w_c;
    const Vec3 dp(noise(rng), noise(rng), noise(rng)), dr(noise(rng), noise(rng), noise(rng));
    noisy.push_back({clean.back().t, SE3(c.so3() * SO3::exp(dr), c.translation() + dp)});
  }
  const Trajectory smooth = smoothTrajectory(noisy, 0.05);
  ASSERT_EQ(smooth.size(), noisy.size());
  double pos_before = 0, pos_after = 0, rot_before = 0, rot_after = 0;
  for (std::size_t i = 0; i < clean.size(); ++i) {
    EXPECT_EQ(smooth[i].t, clean[i].t);
    pos_before += (noisy[i].T_w_c.translation() - clean[i].T_w_c.translation()).squaredNorm();
    pos_after += (smooth[i].T_w_c.translation() - clean[i].T_w_c.translation()).squaredNorm();
    rot_before += std::pow(angleBetween(noisy[i].T_w_c, clean[i].T_w_c), 2);
    rot_after += std::pow(angleBetween(smooth[i].T_w_c, clean[i].T_w_c), 2);
  }
  EXPECT_GT(std::sqrt(pos_before / pos_after), 3.0);
  EXPECT_GT(std::sqrt(rot_before / rot_after), 3.0);
}

TEST(Smoothing, KeepsConstantVelocityOnUnevenSampling) {
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> step(0.002, 0.008);
  const SO3 R0 = SO3::exp(Vec3(0.3, -1.0, 2.0));
  const Vec3 p0(4.4, -0.45, 1.44), v(0.3, -0.2, 0.5), w(0.5, -0.8, 1.1);  // m/s, rad/s (body)
  Trajectory traj;
  double t = 0;
  for (int k = 0; k < 600; ++k, t += step(rng)) {
    Quat q = (R0 * SO3::exp(w * t)).quaternion();
    if (k % 2) q.coeffs() = -q.coeffs();  // same rotation, flipped sign
    traj.push_back({fromSeconds(10 + t), SE3(q, p0 + v * t)});
  }
  const Trajectory smooth = smoothTrajectory(traj, 0.05);
  ASSERT_EQ(smooth.size(), traj.size());
  for (std::size_t i = 0; i < traj.size(); ++i) {
    EXPECT_NEAR((smooth[i].T_w_c.translation() - traj[i].T_w_c.translation()).norm(), 0, 1e-9) << i;
    EXPECT_NEAR(angleBetween(smooth[i].T_w_c, traj[i].T_w_c), 0, 1e-9) << i;
    if (i > 0) EXPECT_GT(smooth[i].T_w_c.quaternion().dot(smooth[i - 1].T_w_c.quaternion()), 0) << i;
  }
  // Zero sigma is the identity.
  EXPECT_EQ(smoothTrajectory(traj, 0).size(), traj.size());
}

TEST(Cut, WindowStartsAtZero) {
  const Trajectory traj = handheldMotion(3.0, 5, 200.0);
  Trajectory shifted = traj;
  for (StampedPose& p : shifted) p.t += fromSeconds(1500.25);  // large offset, as DSEC's
  const Trajectory cut = cutTrajectory(shifted, 0.5, 2.0, "traj.txt");
  const Motion full(traj);
  ASSERT_GE(cut.size(), 2u);
  EXPECT_EQ(cut.front().t, 0);
  EXPECT_EQ(cut.back().t, 2 * kNsPerSec);
  EXPECT_NEAR((cut.front().T_w_c.translation() - full.pose(fromSeconds(0.5)).translation()).norm(), 0, 1e-12);
  EXPECT_NEAR((cut.back().T_w_c.translation() - full.pose(fromSeconds(2.5)).translation()).norm(), 0, 1e-12);
  for (std::size_t i = 1; i < cut.size(); ++i) EXPECT_GT(cut[i].t, cut[i - 1].t);
  EXPECT_EQ(cut.size(), 401u);  // 200 Hz: both ends fall on samples
  // The whole span is allowed; beyond it is an error naming the file.
  EXPECT_NO_THROW(cutTrajectory(traj, 0.0, 3.0, "traj.txt"));
  for (const auto& [start, dur] : {std::pair{1.5, 2.0}, {0.0, 3.01}, {-0.1, 1.0}, {0.0, 0.0}}) {
    try {
      cutTrajectory(traj, start, dur, "traj.txt");
      FAIL() << "no error for window " << start << " + " << dur;
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), "traj.txt");
    }
  }
}

double peakRateDegS(const Trajectory& traj) {
  double peak = 0;
  for (std::size_t i = 1; i < traj.size(); ++i)
    peak =
        std::max(peak, angleBetween(traj[i - 1].T_w_c, traj[i].T_w_c) / toSeconds(traj[i].t - traj[i - 1].t));
  return peak / kDeg;
}

TEST(Handheld, DeterministicLivelyAndFacingForward) {
  const Trajectory a = handheldMotion(10.0, 7);
  const Trajectory b = handheldMotion(10.0, 7);
  const Trajectory c = handheldMotion(10.0, 8);
  ASSERT_EQ(a.size(), 10001u);  // 1 kHz, both ends
  EXPECT_EQ(a.back().t, 10 * kNsPerSec);
  EXPECT_NEAR(a.front().T_w_c.translation().norm(), 0, 1e-15);
  EXPECT_NEAR(a.front().T_w_c.so3().angle(), 0, 1e-15);
  double diff = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].t, b[i].t);
    EXPECT_EQ(a[i].T_w_c.translation(), b[i].T_w_c.translation());
    EXPECT_EQ(a[i].T_w_c.quaternion().coeffs(), b[i].T_w_c.quaternion().coeffs());
    diff = std::max(diff, (a[i].T_w_c.translation() - c[i].T_w_c.translation()).norm());
  }
  EXPECT_GT(diff, 0.01) << "different seeds give the same motion";
  for (std::uint64_t seed = 0; seed < 10; ++seed) {
    const Trajectory m = handheldMotion(10.0, seed);
    const double peak = peakRateDegS(m);
    EXPECT_GT(peak, 15.0) << "seed " << seed;
    EXPECT_LT(peak, 120.0) << "seed " << seed;
    for (const StampedPose& p : m) {
      const Vec3 axis = p.T_w_c.so3() * Vec3::UnitZ();
      ASSERT_LT(std::acos(std::clamp(axis.z(), -1.0, 1.0)), 30 * kDeg) << "seed " << seed;
      ASSERT_LT(p.T_w_c.translation().cwiseAbs().maxCoeff(), 0.25) << "seed " << seed;
    }
  }
}

// ---------------------------------------------------------------- presets

double rectDistance(const Plane& p, const Vec3& x) {
  const Vec3 d = x - p.center;
  const double a = std::clamp(d.dot(p.u), -0.5 * p.size_u, 0.5 * p.size_u);
  const double b = std::clamp(d.dot(p.v), -0.5 * p.size_v, 0.5 * p.size_v);
  return (d - a * p.u - b * p.v).norm();
}

// Distance along the ray to the nearest rectangle it hits (infinity if none).
double castRay(const Scene& s, const Vec3& o, const Vec3& d) {
  double best = std::numeric_limits<double>::infinity();
  for (const Plane& p : s.planes) {
    const Vec3 n = p.normal();
    const double den = n.dot(d);
    if (std::abs(den) < 1e-12) continue;
    const double t = n.dot(p.center - o) / den;
    if (t <= 0 || t >= best) continue;
    const Vec3 x = o + t * d - p.center;
    if (std::abs(x.dot(p.u)) <= 0.5 * p.size_u && std::abs(x.dot(p.v)) <= 0.5 * p.size_v) best = t;
  }
  return best;
}

struct NamedMotion {
  std::string name;
  Trajectory traj;
};

std::vector<NamedMotion> testMotions() {
  std::vector<NamedMotion> out;
  out.push_back({"handheld", handheldMotion(5.0, 11)});
  // Like the shared poster trajectory: far from the origin, looking along +x (camera y down = -z).
  Mat3 R;
  R.col(0) = Vec3(0, -1, 0), R.col(1) = Vec3(0, 0, -1), R.col(2) = Vec3(1, 0, 0);
  const SE3 T0(SO3(R), Vec3(4.4, -0.45, 1.44));
  Trajectory moved = handheldMotion(5.0, 12);
  for (StampedPose& p : moved) p.T_w_c = T0 * p.T_w_c;
  out.push_back({"handheld_at_poster", moved});
  const auto poster = test::sharedDataDir() / "trajectories" / "ecd_poster_6dof_groundtruth.txt";
  if (std::filesystem::exists(poster)) {
    out.push_back(
        {"poster", cutTrajectory(smoothTrajectory(readTum(poster), 0.05), 1.0, 5.0, poster.string())});
  } else if (test::dataRequired()) {
    ADD_FAILURE() << "shared data missing: " << poster;
  } else {
    std::fprintf(stderr, "note: %s not found, the 'poster' motion is left out\n", poster.c_str());
  }
  return out;
}

struct PresetCase {
  const char* name;
  double min_depth, max_depth;  // of the central ray of the middle pose
};

TEST(Presets, PlacedInFrontAndClearOfTheCamera) {
  const PresetCase cases[] = {
      {"planar", 0.7, 1.3}, {"room", 0.8, 8.0}, {"desk", 0.3, 5.5}, {"building", 3.0, 16.0}};
  for (const NamedMotion& nm : testMotions()) {
    const Motion motion(nm.traj);
    for (const PresetCase& pc : cases) {
      SCOPED_TRACE(std::string(pc.name) + " along " + nm.name);
      const Scene s = makePreset(pc.name, motion, 3);
      ASSERT_FALSE(s.planes.empty());
      EXPECT_FALSE(s.mirror_outside);
      for (const Plane& p : s.planes) {
        EXPECT_NEAR(p.u.norm(), 1, 1e-9) << p.name;
        EXPECT_NEAR(p.v.norm(), 1, 1e-9) << p.name;
        EXPECT_NEAR(p.u.dot(p.v), 0, 1e-9) << p.name;
        EXPECT_GT(p.size_u, 0);
        EXPECT_GT(p.texel, 0);
        ASSERT_GE(p.texture, 0);
        ASSERT_LT(static_cast<std::size_t>(p.texture), s.texture_specs.size());
        double clearance = 1e9;
        for (const StampedPose& sp : motion.samples())
          clearance = std::min(clearance, rectDistance(p, sp.T_w_c.translation()));
        EXPECT_GE(clearance, 0.3) << p.name;
      }
      const SE3 mid = motion.pose(motion.start() + (motion.end() - motion.start()) / 2);
      const double depth = castRay(s, mid.translation(), mid.so3() * Vec3::UnitZ());
      EXPECT_GE(depth, pc.min_depth);
      EXPECT_LE(depth, pc.max_depth);
      // Also the corners of a 240x180 view at f = 200 px see something (no holes to the background).
      for (const Vec3 ray :
           {Vec3(-0.6, -0.45, 1), Vec3(0.6, -0.45, 1), Vec3(-0.6, 0.45, 1), Vec3(0.6, 0.45, 1)})
        EXPECT_LT(castRay(s, mid.translation(), mid.so3() * ray.normalized()), 50.0) << ray.transpose();
    }
  }
}

TEST(Presets, RoomHasBoxesAndVarietyDeterministically) {
  const Motion motion(handheldMotion(5.0, 1));
  const Scene a = makePreset("room", motion, 4);
  std::set<std::string> kinds, boxes;
  for (const TextureSpec& t : a.texture_specs) kinds.insert(parseProceduralSource(t.source)->name);
  for (const Plane& p : a.planes)
    if (p.name.rfind("box", 0) == 0) boxes.insert(p.name.substr(0, p.name.find('_')));
  EXPECT_GE(kinds.size(), 4u);
  EXPECT_GE(boxes.size(), 4u);
  EXPECT_LE(boxes.size(), 6u);

  const Scene b = makePreset("room", motion, 4);
  const Scene c = makePreset("room", motion, 5);
  ASSERT_EQ(a.planes.size(), b.planes.size());
  for (std::size_t i = 0; i < a.planes.size(); ++i) EXPECT_EQ(a.planes[i].center, b.planes[i].center);
  for (std::size_t i = 0; i < a.texture_specs.size(); ++i)
    EXPECT_EQ(a.texture_specs[i].source, b.texture_specs[i].source);
  bool differs = a.planes.size() != c.planes.size();
  for (std::size_t i = 0; !differs && i < a.planes.size(); ++i)
    differs = a.planes[i].center != c.planes[i].center;
  EXPECT_TRUE(differs);
}

TEST(Presets, TexturesLoadQuicklyAndRoundTripThroughYaml) {
  const Motion motion(handheldMotion(2.0, 1));
  for (const char* name : {"planar", "room", "desk", "building"}) {
    Scene s = makePreset(name, motion, 9);
    const auto t0 = std::chrono::steady_clock::now();
    s.loadTextures();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_LT(seconds, 5.0) << name;  // ~0.1-0.3 s in release; sanitizers are slower
    ASSERT_EQ(s.textures.size(), s.texture_specs.size());
    const auto dir = test::tempDir(std::string("preset_yaml_") + name);
    writeSceneYaml(dir / "scene.yaml", s);
    const Scene r = readSceneYaml(dir / "scene.yaml");
    ASSERT_EQ(r.planes.size(), s.planes.size());
    ASSERT_EQ(r.texture_specs.size(), s.texture_specs.size());
    EXPECT_EQ(r.texture_specs[0].source, s.texture_specs[0].source);
    EXPECT_EQ(r.planes.back().center, s.planes.back().center);
  }
}

TEST(Presets, UnknownNameListsTheKnownOnes) {
  const Motion motion(handheldMotion(1.0, 1));
  try {
    makePreset("kitchen", motion, 1);
    FAIL() << "no error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("planar, room, desk, building"), std::string::npos) << e.what();
  }
  EXPECT_STREQ(presetNames(), "planar, room, desk, building");
}

}  // namespace
}  // namespace eds::sim
