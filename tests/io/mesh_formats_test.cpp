// SPDX-License-Identifier: GPL-3.0-or-later
// OFF, OBJ and STL: write-then-read round trips, hand-written files with every syntax variant,
// vertex merging in STL, and the error messages of malformed files.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>

#include "pointsurf/core/error.h"
#include "pointsurf/io/io.h"
#include "support/files.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

using test::expect_error;

using test::read_bytes;
using test::write_bytes;

// Unit cube with corner i at (i & 1, i >> 1 & 1, i >> 2 & 1), shifted and scaled so that the
// coordinates need every digit of a double; triangles wind counter-clockwise seen from outside.
TriangleMesh cube_mesh() {
  TriangleMesh mesh;
  const Vector3d origin(0.1, 1e6 + 0.3, -7.0 / 3.0);
  for (int i = 0; i < 8; ++i) {
    const Vector3d corner(i & 1, (i >> 1) & 1, (i >> 2) & 1);
    mesh.vertices.positions.push_back(origin + corner * (1.0 / 3.0));
    mesh.vertices.normals.push_back((2.0 * corner - Vector3d::Ones()).normalized());
    mesh.vertices.colors.emplace_back(static_cast<float>(i * 30) / 255.0f, 1.0f, static_cast<float>(255 - i * 7) / 255.0f);
  }
  mesh.triangles = {{0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}, {0, 1, 5}, {0, 5, 4},
                    {2, 6, 7}, {2, 7, 3}, {0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}};
  return mesh;
}

TEST(Off, MeshRoundTripKeepsVerticesNormalsColoursExactly) {
  const auto dir = test::temp_dir("off_roundtrip");
  const TriangleMesh mesh = cube_mesh();
  write_mesh(dir / "cube.off", mesh);
  EXPECT_EQ(read_bytes(dir / "cube.off").substr(0, 6), "CNOFF\n");
  const MeshReadResult result = read_mesh(dir / "cube.off");
  EXPECT_EQ(result.format, "off");
  EXPECT_EQ(result.mesh.vertices.positions, mesh.vertices.positions);
  EXPECT_EQ(result.mesh.vertices.normals, mesh.vertices.normals);
  EXPECT_EQ(result.mesh.vertices.colors, mesh.vertices.colors);
  EXPECT_EQ(result.mesh.triangles, mesh.triangles);
}

TEST(Off, PointCloudWithNormalsRoundTripsAsNoff) {
  const auto dir = test::temp_dir("off_cloud");
  const PointCloud cloud = test::sample_sphere(50, 2.0, Vector3d(6.5e6, 0, 0), 5);
  write_point_cloud(dir / "cloud.off", cloud);
  EXPECT_EQ(read_bytes(dir / "cloud.off").substr(0, 5), "NOFF\n");
  const CloudReadResult result = read_point_cloud(dir / "cloud.off");
  EXPECT_EQ(result.cloud.positions, cloud.positions);
  EXPECT_EQ(result.cloud.normals, cloud.normals);
  EXPECT_EQ(result.face_count, 0u);
}

TEST(Off, ReadsCommentsCoffColoursAndPolygons) {
  const auto dir = test::temp_dir("off_hand");
  const auto path = write_bytes(dir / "square.off",
                               "# made by hand\n"
                               "COFF\n"
                               "# vertices faces edges\n"
                               "4 2 0   # trailing comment\n"
                               "\n"
                               "0 0 0 255 0 0 255\n"
                               "1 0 0 0 255 0 255\n"
                               "1 1 0 0 0 255\n"
                               "0 1 0 51 102 153 255\n"
                               "4 0 1 2 3  255 0 0\n"
                               "3 0 2 3\n");
  const MeshReadResult result = read_mesh(path);
  const TriangleMesh& m = result.mesh;
  ASSERT_EQ(m.vertex_count(), 4u);
  EXPECT_EQ(m.vertices.positions[2], Vector3d(1, 1, 0));
  ASSERT_EQ(m.vertices.colors.size(), 4u);
  EXPECT_EQ(m.vertices.colors[0], Vector3f(1, 0, 0));
  EXPECT_EQ(m.vertices.colors[2], Vector3f(0, 0, 1));
  EXPECT_EQ(m.vertices.colors[3], Vector3f(51 / 255.0f, 102 / 255.0f, 153 / 255.0f));
  EXPECT_EQ(result.polygons_triangulated, 1u);
  EXPECT_EQ(m.triangles, (std::vector<Triangle>{{0, 1, 2}, {0, 2, 3}, {0, 2, 3}}));
}

TEST(Off, ReadsCountsOnTheHeaderLineAndFloatColoursWithNormals) {
  const auto dir = test::temp_dir("off_cnoff");
  const MeshReadResult one = read_mesh(write_bytes(dir / "a.off", "CNOFF 1 0 0\n0.5 0 -1 0 0 1 1.0 0.5 0.25 1.0\n"));
  ASSERT_EQ(one.mesh.vertex_count(), 1u);
  EXPECT_EQ(one.mesh.vertices.positions[0], Vector3d(0.5, 0, -1));
  EXPECT_EQ(one.mesh.vertices.normals[0], Vector3d(0, 0, 1));
  EXPECT_EQ(one.mesh.vertices.colors[0], Vector3f(1.0f, 0.5f, 0.25f));
  const MeshReadResult two = read_mesh(write_bytes(dir / "b.off", "OFF 3 1 3\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"));
  EXPECT_EQ(two.mesh.triangles, (std::vector<Triangle>{{0, 1, 2}}));
  EXPECT_FALSE(two.mesh.vertices.colors.size());
}

TEST(Off, MalformedFilesNameTheLine) {
  const auto dir = test::temp_dir("off_errors");
  std::string text = "OFF\n10 0 0\n";
  for (int i = 0; i < 9; ++i) text += "0 0 0\n";
  expect_error<InputError>([&] { read_mesh(write_bytes(dir / "model.off", text + "1 2\n")); },
                           "model.off: line 12 (vertex 9): expected 3 coordinates, got 2");
  expect_error<InputError>([&] { read_mesh(write_bytes(dir / "short.off", text)); }, "short.off: vertex 9 of 10: file ends at line 11");
  const std::string quad = "OFF\n4 4 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n3 1 2 3\n";
  expect_error<InputError>([&] { read_mesh(write_bytes(dir / "faces.off", quad + "5 0 1 2 3\n")); },
                           "faces.off: line 10 (face 3): 5 indices announced, 4 given");
  expect_error<InputError>([&] { read_mesh(write_bytes(dir / "few.off", quad)); }, "few.off: face 3 of 4: file ends at line 9");
  expect_error<InputError>([&] { read_mesh(write_bytes(dir / "range.off", quad + "3 0 1 4\n")); },
                           "range.off: line 10 (face 3): vertex index 4 out of range [0, 4)");
  expect_error<InputError>([&] { read_mesh(write_bytes(dir / "word.off", "OFF\n1 0 0\n0 0 zero\n")); },
                           "word.off: line 3 (vertex 0): expected a number, got 'zero'");
  expect_error<InputError>([&] { read_mesh(write_bytes(dir / "4d.off", "4OFF\n1 0 0\n0 0 0 0\n")); },
                           "4d.off: line 1: expected the keyword OFF, COFF, NOFF or CNOFF, got '4OFF'");
  expect_error<InputError>([&] { read_mesh(write_bytes(dir / "color.off", "COFF\n1 0 0\n0 0 0 1 1\n")); },
                           "color.off: line 3 (vertex 0): expected 3 or 4 colour values after the coordinates, got 2");
}

TEST(Obj, MeshRoundTripKeepsVerticesNormalsColoursExactly) {
  const auto dir = test::temp_dir("obj_roundtrip");
  const TriangleMesh mesh = cube_mesh();
  write_mesh(dir / "cube.obj", mesh);
  const MeshReadResult result = read_mesh(dir / "cube.obj");
  EXPECT_EQ(result.format, "obj");
  EXPECT_EQ(result.mesh.vertices.positions, mesh.vertices.positions);
  EXPECT_EQ(result.mesh.vertices.normals, mesh.vertices.normals);
  EXPECT_EQ(result.mesh.vertices.colors, mesh.vertices.colors);
  EXPECT_EQ(result.mesh.triangles, mesh.triangles);
}

TEST(Obj, PointCloudNormalsWithoutFacesAreTakenInOrder) {
  const auto dir = test::temp_dir("obj_cloud");
  const PointCloud cloud = test::sample_plane(20, 1.0, 9);
  write_point_cloud(dir / "cloud.obj", cloud);
  const CloudReadResult result = read_point_cloud(dir / "cloud.obj");
  EXPECT_EQ(result.cloud.positions, cloud.positions);
  EXPECT_EQ(result.cloud.normals, cloud.normals);
}

TEST(Obj, ReadsEveryFaceFormNegativeIndicesAndQuads) {
  const auto dir = test::temp_dir("obj_hand");
  const auto path = write_bytes(dir / "pyramid.obj",
                               "# a square pyramid\n"
                               "mtllib pyramid.mtl\n"
                               "o pyramid\n"
                               "v 0 0 0\n"
                               "v 1 0 0\n"
                               "v 1 1 0\n"
                               "v 0 1 0\n"
                               "v 0.5 0.5 1 # apex\n"
                               "vt 0 0\n"
                               "vt 1 0\n"
                               "vn 0 0 1\n"
                               "vn 0 0 -1\n"
                               "vn 1 0 0\n"
                               "g sides\n"
                               "usemtl stone\n"
                               "s off\n"
                               "f 1//2 4//2 3//2 2//2\n"
                               "f 1 2 5\n"
                               "f 2/1 3/2 5/1\n"
                               "f 3/1/3 4/2/3 5/1/3\n"
                               "f -2 -5 -1\n"
                               "l 1 2\n"
                               "p 5\n");
  const MeshReadResult result = read_mesh(path);
  const TriangleMesh& m = result.mesh;
  ASSERT_EQ(m.vertex_count(), 5u);
  EXPECT_EQ(m.vertices.positions[4], Vector3d(0.5, 0.5, 1));
  EXPECT_EQ(result.polygons_triangulated, 1u);
  EXPECT_EQ(m.triangles, (std::vector<Triangle>{{0, 3, 2}, {0, 2, 1}, {0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}}));
  // Normals come from the face references; a vertex given two different ones gets their mean.
  ASSERT_EQ(m.vertices.normals.size(), 5u);
  EXPECT_EQ(m.vertices.normals[0], Vector3d(0, 0, -1));
  EXPECT_EQ(m.vertices.normals[1], Vector3d(0, 0, -1));
  EXPECT_TRUE(m.vertices.normals[2].isApprox(Vector3d(1, 0, -1).normalized(), 1e-15));
  EXPECT_TRUE(m.vertices.normals[3].isApprox(Vector3d(1, 0, -1).normalized(), 1e-15));
  EXPECT_EQ(m.vertices.normals[4], Vector3d(1, 0, 0));
  EXPECT_TRUE(m.vertices.colors.empty());
}

TEST(Obj, ReadsVertexColoursInEitherRange) {
  const auto dir = test::temp_dir("obj_colors");
  const CloudReadResult unit = read_point_cloud(write_bytes(dir / "unit.obj", "v 0 0 0 1 0.5 0\nv 1 2 3 1 0 0.25 0\n"));
  ASSERT_EQ(unit.cloud.colors.size(), 2u);
  EXPECT_EQ(unit.cloud.colors[0], Vector3f(1, 0.5f, 0));
  EXPECT_EQ(unit.cloud.positions[1], Vector3d(1, 2, 3));  // "x y z w r g b"
  EXPECT_EQ(unit.cloud.colors[1], Vector3f(0, 0.25f, 0));
  const CloudReadResult bytes = read_point_cloud(write_bytes(dir / "bytes.obj", "v 0 0 0 255 51 0\n"));
  EXPECT_EQ(bytes.cloud.colors[0], Vector3f(1, 51 / 255.0f, 0));
}

TEST(Obj, MalformedFilesNameTheLine) {
  const auto dir = test::temp_dir("obj_errors");
  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  expect_error<InputError>([&] { read_mesh(write_bytes(dir / "zero.obj", tri + "f 0 1 2\n")); },
                           "zero.obj: line 4: vertex index 0: OBJ indices start at 1");
  expect_error<InputError>([&] { read_mesh(write_bytes(dir / "range.obj", tri + "f 1 2 4\n")); },
                           "range.obj: line 4: vertex index 4 out of range: 3 vertices defined so far");
  expect_error<InputError>([&] { read_mesh(write_bytes(dir / "relative.obj", tri + "f -1 -2 -4\n")); },
                           "relative.obj: line 4: vertex index -4 out of range");
  expect_error<InputError>([&] { read_mesh(write_bytes(dir / "normal.obj", tri + "vn 0 0 1\nf 1//1 2//2 3//1\n")); },
                           "normal.obj: line 5: normal index 2 out of range: 1 normals defined so far");
  expect_error<InputError>([&] { read_mesh(write_bytes(dir / "short.obj", "v 0 0 0\nv 1 0\n")); },
                           "short.obj: line 2: vertex: expected 3 coordinates, got 2");
  expect_error<InputError>([&] { read_mesh(write_bytes(dir / "text.obj", "v 0 0 0\nv 1 0 x\n")); },
                           "text.obj: line 2: vertex: expected a number, got 'x'");
  expect_error<InputError>([&] { read_mesh(write_bytes(dir / "edge.obj", tri + "f 1 2\n")); },
                           "edge.obj: line 4: face: expected at least 3 vertices, got 2");
  expect_error<InputError>([&] { read_mesh(write_bytes(dir / "junk.obj", tri + "f 1 2 three\n")); },
                           "junk.obj: line 4: expected a vertex index, got 'three'");
}

// Corners of each triangle, so that meshes with differently numbered vertices compare.
std::vector<Vector3d> triangle_corners(const TriangleMesh& mesh) {
  std::vector<Vector3d> corners;
  for (const Triangle& t : mesh.triangles)
    for (int c = 0; c < 3; ++c) corners.push_back(mesh.vertices.positions[t[c]]);
  return corners;
}

TEST(Stl, BinaryRoundTripMergesCornersAndRoundsToFloat) {
  const auto dir = test::temp_dir("stl_binary");
  const TriangleMesh mesh = cube_mesh();
  write_mesh(dir / "cube.stl", mesh);
  const std::string bytes = read_bytes(dir / "cube.stl");
  EXPECT_EQ(bytes.size(), 84u + 50u * 12u);
  EXPECT_NE(bytes.substr(0, 5), "solid");
  const MeshReadResult result = read_mesh(dir / "cube.stl");
  EXPECT_EQ(result.format, "stl");
  EXPECT_EQ(result.encoding, "binary_little_endian");
  EXPECT_EQ(result.mesh.vertex_count(), 8u);
  ASSERT_EQ(result.mesh.triangle_count(), 12u);
  std::vector<Vector3d> expected = triangle_corners(mesh);
  for (Vector3d& p : expected) p = p.cast<float>().cast<double>();  // binary STL is float32
  EXPECT_EQ(triangle_corners(result.mesh), expected);
  // The facet normal written for the first triangle (bottom face) is -z.
  float normal[3];
  std::memcpy(normal, bytes.data() + 84, sizeof(normal));
  EXPECT_EQ(Vector3f(normal[0], normal[1], normal[2]), Vector3f(0, 0, -1));
}

TEST(Stl, AsciiRoundTripKeepsDoublePrecision) {
  const auto dir = test::temp_dir("stl_ascii");
  const TriangleMesh mesh = cube_mesh();
  WriteOptions options;
  options.ascii = true;
  write_mesh(dir / "cube.stl", mesh, options);
  EXPECT_EQ(read_bytes(dir / "cube.stl").substr(0, 16), "solid pointsurf\n");
  const MeshReadResult result = read_mesh(dir / "cube.stl");
  EXPECT_EQ(result.encoding, "ascii");
  EXPECT_EQ(result.mesh.vertex_count(), 8u);
  EXPECT_EQ(triangle_corners(result.mesh), triangle_corners(mesh));
}

TEST(Stl, ReadsHandWrittenAscii) {
  const auto dir = test::temp_dir("stl_hand");
  const auto path = write_bytes(dir / "square.stl",
                               "solid square\n"
                               "  facet normal 0 0 1\n"
                               "    outer loop\n"
                               "      vertex 0 0 0\n"
                               "      vertex 1 0 0\n"
                               "      vertex 1 1 0\n"
                               "    endloop\n"
                               "  endfacet\n"
                               "  facet normal 0 0 1\n"
                               "    outer loop\n"
                               "      vertex 0 0 0\n"
                               "      vertex 1 1 0\n"
                               "      vertex 0 1 -0\n"
                               "    endloop\n"
                               "  endfacet\n"
                               "endsolid square\n");
  const MeshReadResult result = read_mesh(path);
  EXPECT_EQ(result.mesh.vertices.positions, (std::vector<Vector3d>{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}));
  EXPECT_EQ(result.mesh.triangles, (std::vector<Triangle>{{0, 1, 2}, {0, 2, 3}}));
}

// 12 facets of a cube as binary STL, each corner stored in every facet that uses it; the
// header starts with "solid" as many exporters' do.
std::string binary_cube_stl(std::uint32_t announced, std::size_t facets) {
  const TriangleMesh mesh = cube_mesh();
  std::string bytes = "solid exported by some CAD tool";
  bytes.resize(80, '\0');
  bytes.append(reinterpret_cast<const char*>(&announced), 4);
  for (std::size_t f = 0; f < facets; ++f) {
    const Triangle& t = mesh.triangles[f % 12];
    float values[12] = {};
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) values[3 + 3 * c + k] = static_cast<float>(mesh.vertices.positions[t[c]][k]);
    bytes.append(reinterpret_cast<const char*>(values), sizeof(values));
    bytes.append(2, '\0');
  }
  return bytes;
}

TEST(Stl, BinaryFacetsMergeIntoEightCubeVertices) {
  const auto dir = test::temp_dir("stl_merge");
  const MeshReadResult result = read_mesh(write_bytes(dir / "cube.stl", binary_cube_stl(12, 12)));
  EXPECT_EQ(result.mesh.vertex_count(), 8u);
  EXPECT_EQ(result.mesh.triangle_count(), 12u);
  EXPECT_EQ(result.dropped_faces, 0u);
}

TEST(Stl, MalformedFilesAndImpossibleWrites) {
  const auto dir = test::temp_dir("stl_errors");
  ReadOptions forced;
  forced.format = "stl";
  std::string cut = binary_cube_stl(100, 12) + std::string(20, '\0');
  expect_error<InputError>([&] { read_mesh(write_bytes(dir / "cut.stl", cut), forced); }, "cut.stl: binary STL: facet 12 of 100: file ends at byte 704");
  EXPECT_THROW(read_mesh(dir / "cut.stl"), InputError);  // detection already refuses it
  expect_error<InputError>([&] { read_mesh(write_bytes(dir / "tiny.stl", std::string(40, '\1')), forced); },
                           "tiny.stl: binary STL: file ends at byte 40, inside the 84-byte header");

  const std::string head = "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n";
  expect_error<InputError>([&] { read_mesh(write_bytes(dir / "loop.stl", head + "endloop\nendfacet\nendsolid\n")); },
                           "loop.stl: line 5: expected 'vertex x y z' (corner 2 of 3), got 'endloop'");
  expect_error<InputError>([&] { read_mesh(write_bytes(dir / "coords.stl", head + "vertex 1 0\n")); },
                           "coords.stl: line 5: vertex: expected 3 coordinates, got 2");
  expect_error<InputError>([&] { read_mesh(write_bytes(dir / "ends.stl", head + "vertex 1 0 0\n")); },
                           "ends.stl: line 5: file ends inside facet 0");
  expect_error<InputError>([&] { read_mesh(write_bytes(dir / "nofacet.stl", "solid s\nfacet normal 0 0 1\nvertex 0 0 0\n")); },
                           "nofacet.stl: line 3: expected 'outer loop', got 'vertex'");

  expect_error<UsageError>([&] { write_point_cloud(dir / "cloud.stl", test::sample_plane(10)); },
                           "cloud.stl: STL holds triangles only; this has no triangles");
  EXPECT_FALSE(std::filesystem::exists(dir / "cloud.stl"));
}

}  // namespace
}  // namespace pointsurf
