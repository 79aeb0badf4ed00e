// SPDX-License-Identifier: GPL-3.0-or-later
// TriangleMesh: attribute sizes checked by validate(), face fields included; from_cloud and
// vertex_cloud carry every attribute.
#include "pointsurf/core/triangle_mesh.h"

#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "support/files.h"

namespace pointsurf {
namespace {

TriangleMesh two_triangles() {
  TriangleMesh m;
  m.vertices = {Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0), Vector3d(1, 1, 0)};
  m.triangles = {Triangle(0, 1, 2), Triangle(1, 3, 2)};
  return m;
}

TEST(TriangleMesh, FaceFieldsHoldOneValuePerTriangle) {
  TriangleMesh m = two_triangles();
  m.face_fields.add("region", 2, ScalarType::Int32).values = {0, 1};
  EXPECT_NO_THROW(m.validate());
  m.face_fields.add("quality", 3);
  test::expect_error<InputError>([&] { m.validate(); }, "mesh: face field 'quality' has 3 values for 2 triangles");
  m.face_fields.remove("quality");
  m.vertex_fields.add("height", 2);
  test::expect_error<InputError>([&] { m.validate(); }, "mesh: field 'height' has 2 values for 4 vertices");
}

TEST(TriangleMesh, FromCloudAndVertexCloudKeepEveryAttribute) {
  TriangleMesh m = two_triangles();
  PointCloud cloud = m.vertex_cloud();
  cloud.normals.assign(4, Vector3d(0, 0, 1));
  cloud.fields.add("intensity", 4).values = {1, 2, 3, 4};
  FieldSet faces;
  faces.add("region", 2, ScalarType::UInt8).values = {7, 9};
  const TriangleMesh back = TriangleMesh::from_cloud(cloud, m.triangles, faces);
  EXPECT_EQ(back.vertices, m.vertices);
  EXPECT_EQ(back.vertex_normals, cloud.normals);
  EXPECT_EQ(back.vertex_fields.find("intensity")->values, (std::vector<double>{1, 2, 3, 4}));
  EXPECT_EQ(back.face_fields.find("region")->values, (std::vector<double>{7, 9}));
  EXPECT_EQ(back.face_fields.find("region")->type, ScalarType::UInt8);
  EXPECT_TRUE(TriangleMesh::from_cloud(cloud, m.triangles).face_fields.empty());
  EXPECT_NO_THROW(back.validate());
}

}  // namespace
}  // namespace pointsurf
