// SPDX-License-Identifier: GPL-3.0-or-later
// The library example of README.md, run on a shipped scan: it must compile, and its result must
// match what is known of the scan.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "pointsurf/io/io.h"
#include "pointsurf/normals/normals.h"
#include "pointsurf/spatial/kd_tree.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

TEST(LibraryExample, ReadmeSnippetGivesTheKnownAnswers) {
  const std::filesystem::path dir = test::temp_dir("readme_example");
  CloudReadResult scan = read_point_cloud(test::data_path("b9_training.ply"));
  PointCloud& cloud = scan.cloud;
  KdTree tree(cloud.positions);
  const double h = mean_spacing(tree);
  estimate_normals(cloud, {.k = 30}, &tree);
  orient_normals(cloud, {.method = Orientation::Mst}, &tree);
  write_point_cloud(dir / "oriented.ply", cloud);

  // Known answers, measured 2026-12-02 with margins a regression would cross:
  // b9 holds 22,300 points at a mean spacing of 0.660 m (an aerial LiDAR tile of a town).
  ASSERT_EQ(cloud.size(), 22300u);
  EXPECT_NEAR(h, 0.660, 0.01);
  const PointCloud back = read_point_cloud(dir / "oriented.ply").cloud;
  ASSERT_EQ(back.size(), cloud.size());
  ASSERT_TRUE(back.has_normals());
  ASSERT_TRUE(back.fields.contains("variation"));
  // Georeferenced (x ~ 596,648 m): the binary PLY round trip is exact in double, fields too.
  EXPECT_EQ(back.positions, cloud.positions);
  for (std::size_t i = 0; i < back.size(); ++i) ASSERT_LE((back.normals[i] - cloud.normals[i]).norm(), 1e-6) << "point " << i;
  ASSERT_TRUE(back.fields.contains("label"));
  EXPECT_EQ(back.fields.find("label")->values, scan.cloud.fields.find("label")->values);

  // The tile is mostly roofs and ground: 76 % of the normals are within 26 degrees of vertical,
  // 97 % of those point up (the MST's terrain rule), and the median surface variation is 0.005.
  // The points the data set labels 0 (ground) face up: 99.2 % have n_z > 0.9.
  std::size_t horizontal = 0, up = 0, ground = 0, ground_up = 0;
  const std::vector<double>& label = back.fields.find("label")->values;
  for (std::size_t i = 0; i < back.size(); ++i) {
    const Vector3d& n = back.normals[i];
    ASSERT_NEAR(n.norm(), 1.0, 1e-9) << "point " << i;
    if (std::abs(n.z()) > 0.9) {
      ++horizontal;
      up += n.z() > 0.0 ? 1 : 0;
    }
    if (label[i] == 0.0) {
      ++ground;
      ground_up += n.z() > 0.9 ? 1 : 0;
    }
  }
  EXPECT_GE(double(horizontal) / double(back.size()), 0.70);
  EXPECT_GE(double(up) / double(horizontal), 0.95);
  ASSERT_EQ(ground, 1567u);
  EXPECT_GE(double(ground_up) / double(ground), 0.97);
  std::vector<double> variation = back.fields.find("variation")->values;
  std::nth_element(variation.begin(), variation.begin() + std::ptrdiff_t(variation.size() / 2), variation.end());
  EXPECT_LT(variation[variation.size() / 2], 0.01);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace pointsurf
