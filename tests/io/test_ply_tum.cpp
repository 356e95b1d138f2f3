#include <gtest/gtest.h>

#include <fstream>

#include "core/error.hpp"
#include "io/ply.hpp"
#include "io/trajectory_io.hpp"
#include "test_data.hpp"

namespace eds {
namespace {

TEST(Ply, RoundTripAndHeaderIsStandard) {
  const auto dir = test::tempDir("ply");
  PointCloud cloud;
  for (int i = 0; i < 100; ++i) {
    cloud.xyz.emplace_back(0.1f * i, -0.2f * i, 1.0f + i);
    cloud.intensity.push_back(static_cast<float>(i) / 100.f);
  }
  writePly(dir / "map.ply", cloud);
  EXPECT_EQ(std::filesystem::file_size(dir / "map.ply"),
            std::string("ply\nformat binary_little_endian 1.0\ncomment written by eds\nelement vertex 100\n"
                        "property float x\nproperty float y\nproperty float z\nproperty float intensity\n"
                        "end_header\n")
                    .size() +
                100 * 16);
  const PointCloud back = readPly(dir / "map.ply");
  ASSERT_EQ(back.xyz.size(), 100u);
  EXPECT_EQ(back.xyz[57], cloud.xyz[57]);
  EXPECT_EQ(back.intensity[99], cloud.intensity[99]);
}

TEST(Ply, TruncatedFileIsAnError) {
  const auto dir = test::tempDir("ply_trunc");
  PointCloud cloud;
  cloud.xyz.assign(10, Eigen::Vector3f(1, 2, 3));
  cloud.intensity.assign(10, 0.5f);
  writePly(dir / "map.ply", cloud);
  std::filesystem::resize_file(dir / "map.ply", std::filesystem::file_size(dir / "map.ply") - 8);
  EXPECT_THROW(readPly(dir / "map.ply"), InputError);
}

TEST(Tum, WriteThenReadKeepsNanosecondsAndPoses) {
  const auto dir = test::tempDir("tum");
  Trajectory traj;
  for (int i = 0; i < 50; ++i) {
    const SE3 T(SO3::exp(Vec3(0.01 * i, -0.02 * i, 0.03)), Vec3(i, 2.0 * i, -0.5 * i));
    traj.push_back({1518195889'000000000LL + i * 4'999'161LL, T});
  }
  writeTum(dir / "traj.txt", traj);
  const Trajectory back = readTum(dir / "traj.txt");
  ASSERT_EQ(back.size(), traj.size());
  for (std::size_t i = 0; i < traj.size(); ++i) {
    EXPECT_EQ(back[i].t, traj[i].t);
    EXPECT_LT((back[i].T_w_c.translation() - traj[i].T_w_c.translation()).norm(), 1e-8);
    EXPECT_LT((back[i].T_w_c.so3().inverse() * traj[i].T_w_c.so3()).angle(), 1e-8);
  }
}

TEST(Tum, ReadsEcdGroundTruthOrderTxyzQxyzw) {
  const auto dir = test::tempDir("tum_order");
  // 90 degrees about z: q = (x y z w) = (0 0 sin45 cos45).
  std::ofstream(dir / "gt.txt") << "0.5 1 2 3 0 0 0.7071067811865476 0.7071067811865476\n";
  const Trajectory t = readTum(dir / "gt.txt");
  ASSERT_EQ(t.size(), 1u);
  EXPECT_EQ(t[0].t, 500'000'000);
  EXPECT_LT((t[0].T_w_c * Vec3(1, 0, 0) - Vec3(1, 3, 3)).norm(), 1e-12);  // R x = y, plus translation
}

}  // namespace
}  // namespace eds
