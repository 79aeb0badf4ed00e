// SPDX-License-Identifier: GPL-3.0-or-later
// The library example of README.md, run on a shipped scan: it must compile and work as shown.
#include <gtest/gtest.h>

#include "pointsurf/io/io.h"
#include "pointsurf/normals/normals.h"
#include "pointsurf/spatial/kd_tree.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

TEST(LibraryExample, ReadmeSnippetRuns) {
  const std::filesystem::path dir = test::temp_dir("readme_example");
  CloudReadResult scan = read_point_cloud(test::data_path("b9_training.ply"));
  PointCloud& cloud = scan.cloud;
  KdTree tree(cloud.positions);
  const double h = mean_spacing(tree);
  estimate_normals(cloud, {.k = 30}, &tree);
  orient_normals(cloud, {.method = Orientation::Mst}, &tree);
  write_point_cloud(dir / "oriented.ply", cloud);

  EXPECT_GT(h, 0.0);
  const PointCloud back = read_point_cloud(dir / "oriented.ply").cloud;
  ASSERT_EQ(back.size(), cloud.size());
  EXPECT_TRUE(back.has_normals());
  EXPECT_TRUE(back.fields.contains("label"));
  EXPECT_TRUE(back.fields.contains("variation"));
  // Georeferenced (x ~ 596,648 m): the binary PLY round trip is exact in double.
  EXPECT_EQ(back.positions[123], cloud.positions[123]);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace pointsurf
