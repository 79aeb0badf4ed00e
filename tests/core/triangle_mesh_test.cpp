// SPDX-License-Identifier: GPL-3.0-or-later
// TriangleMesh: attribute sizes checked by validate(), face fields included; a mesh built from
// a cloud keeps every vertex attribute.
#include "pointsurf/core/triangle_mesh.h"

#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "support/files.h"

namespace pointsurf {
namespace {

TriangleMesh two_triangles() {
  TriangleMesh m;
  m.vertices.positions = {Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0), Vector3d(1, 1, 0)};
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
  m.vertices.fields.add("height", 2);
  test::expect_error<InputError>([&] { m.validate(); }, "mesh: field 'height' has 2 values for 4 vertices");
}

TEST(TriangleMesh, VerticesAreACloudThatKeepsEveryAttribute) {
  TriangleMesh m = two_triangles();
  PointCloud cloud = m.vertices;
  cloud.normals.assign(4, Vector3d(0, 0, 1));
  cloud.fields.add("intensity", 4).values = {1, 2, 3, 4};
  FieldSet faces;
  faces.add("region", 2, ScalarType::UInt8).values = {7, 9};
  const TriangleMesh back = TriangleMesh{cloud, m.triangles, faces};
  EXPECT_EQ(back.vertices.positions, m.vertices.positions);
  EXPECT_EQ(back.vertices.normals, cloud.normals);
  EXPECT_EQ(back.vertices.fields.find("intensity")->values, (std::vector<double>{1, 2, 3, 4}));
  EXPECT_EQ(back.face_fields.find("region")->values, (std::vector<double>{7, 9}));
  EXPECT_EQ(back.face_fields.find("region")->type, ScalarType::UInt8);
  EXPECT_TRUE((TriangleMesh{cloud, m.triangles, {}}.face_fields.empty()));
  EXPECT_NO_THROW(back.validate());
}

}  // namespace
}  // namespace pointsurf
