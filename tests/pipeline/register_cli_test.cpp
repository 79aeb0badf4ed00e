// SPDX-License-Identifier: GPL-3.0-or-later
// The registration commands and stages end to end: `transform --file T.json`.
#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_run.h"
#include "pointsurf/io/io.h"
#include "pointsurf/io/transform_file.h"
#include "support/files.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

class RegisterCli : public ::testing::Test {
public:
  void SetUp() override {
    dir_ = test::temp_dir(std::string("register_cli_") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::filesystem::path dir_;
};


RigidTransform test_motion() {
  return RigidTransform(Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.2, 1.0, 0.3).normalized()).toRotationMatrix(), Eigen::Vector3d(0.3, -0.1, 0.2));
}

TEST_F(RegisterCli, TransformReadsTJsonAndInverts) {
  const PointCloud sphere = test::sample_sphere(500, 1.0, Vector3d(2, 0, 1));
  write_point_cloud(path("in.ply"), sphere);
  TransformFile t;
  t.transform = test_motion();
  t.members = {{"fitness", 1.0}};
  write_transform_file(path("T.json"), t);
  test::CliResult r = test::run_cli("transform " + path("in.ply") + " " + path("moved.ply") + " --file " + path("T.json"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const PointCloud moved = read_point_cloud(path("moved.ply")).cloud;
  ASSERT_EQ(moved.size(), sphere.size());
  for (std::size_t i = 0; i < sphere.size(); ++i) EXPECT_LT((moved.positions[i] - t.transform.apply(sphere.positions[i])).norm(), 1e-12);
  r = test::run_cli("transform " + path("moved.ply") + " " + path("back.ply") + " --file " + path("T.json") + " --invert", dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const PointCloud back = read_point_cloud(path("back.ply")).cloud;
  for (std::size_t i = 0; i < sphere.size(); ++i) EXPECT_LT((back.positions[i] - sphere.positions[i]).norm(), 1e-12);

  r = test::run_cli("transform " + path("in.ply") + " " + path("x.ply") + " --file " + path("T.json") + " --matrix 1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1",
                    dir_);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_TRUE(test::contains(r.err, "give one of them, not both")) << r.err;
  test::write_bytes(dir_ / "bad.json", "{\"matrix\": [1, 2, 3]}");
  r = test::run_cli("transform " + path("in.ply") + " " + path("x.ply") + " --file " + path("bad.json"), dir_);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_TRUE(test::contains(r.err, "bad.json: \"matrix\": a list of 3 items")) << r.err;
  EXPECT_FALSE(std::filesystem::exists(path("x.ply")));
}


}  // namespace
}  // namespace pointsurf
