// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/core/point_cloud.h"

#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

TEST(PointCloud, SelectKeepsEveryAttribute) {
  PointCloud c = test::sample_sphere(10);
  c.colors.assign(10, Vector3f(0.1f, 0.2f, 0.3f));
  ScalarField& f = c.fields.add("intensity", 10, ScalarType::UInt16);
  for (int i = 0; i < 10; ++i) f.values[i] = i;
  const std::vector<std::size_t> idx{7, 2, 9};
  const PointCloud s = c.select(idx);
  ASSERT_EQ(s.size(), 3u);
  EXPECT_EQ(s.positions[1], c.positions[2]);
  EXPECT_EQ(s.normals[2], c.normals[9]);
  EXPECT_EQ(s.colors.size(), 3u);
  ASSERT_NE(s.fields.find("intensity"), nullptr);
  EXPECT_EQ(s.fields.find("intensity")->values, (std::vector<double>{7, 2, 9}));
  EXPECT_EQ(s.fields.find("intensity")->type, ScalarType::UInt16);
}

TEST(PointCloud, ValidateNamesTheBadAttribute) {
  PointCloud c = test::sample_sphere(5);
  c.fields.add("label", 4);
  try {
    c.validate();
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("field 'label' has 4 values for 5 points"), std::string::npos) << e.what();
  }
}

TEST(PointCloud, AppendFillsMissingAttributes) {
  PointCloud a = test::sample_sphere(3);
  PointCloud b;
  b.positions = {Vector3d(1, 2, 3)};
  b.fields.add("label", 1).values[0] = 5;
  a.append(b);
  a.validate();
  EXPECT_EQ(a.size(), 4u);
  EXPECT_EQ(a.normals[3], Vector3d::Zero());
  EXPECT_EQ(a.fields.find("label")->values, (std::vector<double>{0, 0, 0, 5}));
}

TEST(PointCloud, AppendToItselfDoubles) {
  PointCloud a = test::sample_sphere(4);
  a.fields.add("label", 4).values = {1, 2, 3, 4};
  a.append(a);
  a.validate();
  ASSERT_EQ(a.size(), 8u);
  EXPECT_EQ(a.positions[5], a.positions[1]);
  EXPECT_EQ(a.fields.find("label")->values, (std::vector<double>{1, 2, 3, 4, 1, 2, 3, 4}));
}

TEST(BoundingBox, OfPointsAndEmpty) {
  EXPECT_TRUE(bounding_box({}).empty());
  std::vector<Vector3d> pts{{1, -2, 3}, {-1, 5, 0}, {6.5e6, 0, 0}};
  const BoundingBox box = bounding_box(pts);
  EXPECT_EQ(box.min, Vector3d(-1, -2, 0));
  EXPECT_EQ(box.max, Vector3d(6.5e6, 5, 3));
}

TEST(Errors, ExitCodes) {
  EXPECT_EQ(UsageError("x").exit_code(), 1);
  EXPECT_EQ(InputError("x").exit_code(), 2);
  EXPECT_EQ(ComputeError("x").exit_code(), 3);
  EXPECT_EQ(CancelledError().exit_code(), 130);  // 128 + SIGINT
}

}  // namespace
}  // namespace pointsurf
