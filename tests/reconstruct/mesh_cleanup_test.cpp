// SPDX-License-Identifier: GPL-3.0-or-later
// Small-component removal on a sphere with specks of known sizes next to it.
#include "pointsurf/reconstruct/mesh_cleanup.h"

#include <vector>

#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "pointsurf/core/mesh_topology.h"
#include "support/files.h"
#include "support/mesh_shapes.h"

namespace pointsurf {
namespace {

// A 1280-face sphere, three lone triangles far away and one pair sharing an edge; a face
// field "id" holds each face's index, to follow the faces.
TriangleMesh sphere_with_specks() {
  TriangleMesh mesh = test::icosphere_mesh(3, 1.0);
  auto add_triangle = [&](const Vector3d& at) {
    const int base = static_cast<int>(mesh.vertices.positions.size());
    mesh.vertices.positions.insert(mesh.vertices.positions.end(), {at, at + Vector3d(0.01, 0, 0), at + Vector3d(0, 0.01, 0)});
    mesh.triangles.emplace_back(base, base + 1, base + 2);
  };
  add_triangle(Vector3d(10, 0, 0));
  add_triangle(Vector3d(0, 10, 0));
  add_triangle(Vector3d(0, 0, 10));
  add_triangle(Vector3d(-10, 0, 0));
  const int last = static_cast<int>(mesh.vertices.positions.size()) - 1;  // the pair: shares edge (last - 1, last)
  mesh.vertices.positions.push_back(Vector3d(-10, 0, 0) + Vector3d(0.01, 0.01, 0));
  mesh.triangles.emplace_back(last - 1, last + 1, last);
  ScalarField& id = mesh.face_fields.add("id", mesh.triangle_count(), ScalarType::Int32);
  for (std::size_t f = 0; f < id.values.size(); ++f) id.values[f] = static_cast<double>(f);
  return mesh;
}

TEST(SmallComponents, DefaultShareRemovesTheLoneTrianglesAndKeepsTheirOrderAndFields) {
  TriangleMesh mesh = sphere_with_specks();
  const std::size_t vertices = mesh.vertex_count();
  ASSERT_EQ(mesh.triangle_count(), 1285u);
  ASSERT_EQ(analyze_topology(mesh).components, 5u);
  // 0.1 % of 1285 faces is 1.285: the single triangles go, the pair stays.
  const SmallComponentsResult r = remove_small_components(mesh);
  EXPECT_EQ(r.components, 5u);
  EXPECT_EQ(r.components_removed, 3u);
  EXPECT_EQ(r.faces_removed, 3u);
  EXPECT_EQ(r.min_faces, 2u);
  EXPECT_EQ(mesh.triangle_count(), 1282u);
  EXPECT_EQ(mesh.vertex_count(), vertices);  // vertices stay, now unused
  EXPECT_EQ(analyze_topology(mesh).components, 2u);
  EXPECT_EQ(analyze_topology(mesh).isolated_vertices, 9u);
  const std::vector<double>& id = mesh.face_fields.find("id")->values;
  ASSERT_EQ(id.size(), 1282u);
  for (std::size_t f = 0; f < 1280; ++f) ASSERT_EQ(id[f], static_cast<double>(f));
  EXPECT_EQ(id[1280], 1283.0);
  EXPECT_EQ(id[1281], 1284.0);
  EXPECT_NO_THROW(mesh.validate());
}

TEST(SmallComponents, LargerShareLeavesTheSphereAloneAndZeroRemovesNothing) {
  TriangleMesh mesh = sphere_with_specks();
  SmallComponentParams p;
  p.min_share = 0.002;  // 2.57 faces: the pair goes too
  const SmallComponentsResult r = remove_small_components(mesh, p);
  EXPECT_EQ(r.components_removed, 4u);
  EXPECT_EQ(r.faces_removed, 5u);
  EXPECT_EQ(mesh.triangle_count(), 1280u);
  const MeshTopology t = analyze_topology(mesh);
  EXPECT_EQ(t.components, 1u);
  EXPECT_TRUE(t.watertight());

  TriangleMesh untouched = sphere_with_specks();
  p.min_share = 0.0;
  const SmallComponentsResult none = remove_small_components(untouched, p);
  EXPECT_EQ(none.components, 5u);
  EXPECT_EQ(none.components_removed, 0u);
  EXPECT_EQ(none.faces_removed, 0u);
  EXPECT_EQ(untouched.triangles, sphere_with_specks().triangles);
  // The whole mesh as the share keeps only a component holding every face: none here.
  p.min_share = 1.0;
  EXPECT_EQ(remove_small_components(untouched, p).faces_removed, 1285u);
  EXPECT_TRUE(untouched.triangles.empty());
  EXPECT_TRUE(untouched.face_fields.find("id")->values.empty());
}

TEST(SmallComponents, BadShareAndMeshThrow) {
  TriangleMesh mesh = sphere_with_specks();
  SmallComponentParams p;
  p.min_share = -0.1;
  test::expect_error<UsageError>([&] { remove_small_components(mesh, p); }, "remove_small_components: min_share must be in [0, 1], got -0.1");
  mesh.face_fields.find("id")->values.pop_back();
  test::expect_error<InputError>([&] { remove_small_components(mesh); }, "face field 'id' has 1284 values for 1285 triangles");
}

}  // namespace
}  // namespace pointsurf
