// SPDX-License-Identifier: GPL-3.0-or-later
// PLY: write-then-read in every encoding, hand-written files with unusual layouts, and every
// malformed-input error with its message.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "pointsurf/core/error.h"
#include "pointsurf/io/io.h"
#include "support/files.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

using test::write_bytes;
using test::error_of;
using test::contains;

namespace fs = std::filesystem;

// Appends `value` to `bytes` in the requested byte order.
template <typename T>
void put(std::string& bytes, T value, bool big) {
  char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  if (big == (std::endian::native == std::endian::little))
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(raw[i], raw[sizeof(T) - 1 - i]);
  bytes.append(raw, sizeof(T));
}

// Runs `f`, expects an exception of type E, and returns its message.
// A small mesh with every attribute PLY can hold: normals, 8-bit colours and fields of
// several types, with values each type stores exactly.
TriangleMesh attributed_mesh() {
  const PointCloud sphere = test::sample_sphere(50, 2.0, Vector3d(10, -20, 30), 3);
  TriangleMesh mesh;
  mesh.vertices.positions = sphere.positions;
  mesh.vertices.normals = sphere.normals;
  for (std::size_t i = 0; i < mesh.vertices.positions.size(); ++i)
    mesh.vertices.colors.emplace_back(static_cast<float>(i % 256) / 255.0f, static_cast<float>((3 * i) % 256) / 255.0f, 1.0f);
  ScalarField& label = mesh.vertices.fields.add("label", 50, ScalarType::UInt8);
  ScalarField& intensity = mesh.vertices.fields.add("intensity", 50, ScalarType::Float32);
  ScalarField& distance = mesh.vertices.fields.add("distance", 50, ScalarType::Float64);
  ScalarField& offset = mesh.vertices.fields.add("offset", 50, ScalarType::Int16);
  ScalarField& id = mesh.vertices.fields.add("id", 50, ScalarType::UInt32);
  for (std::size_t i = 0; i < 50; ++i) {
    label.values[i] = static_cast<double>(i % 7);
    intensity.values[i] = 0.25 * static_cast<double>(i);
    distance.values[i] = 1.0 / (1.0 + static_cast<double>(i));
    offset.values[i] = -300.0 + static_cast<double>(i);
    id.values[i] = 4000000000.0 + static_cast<double>(i);
  }
  for (int i = 0; i + 2 < 50; i += 3) mesh.triangles.emplace_back(i, i + 1, i + 2);
  const std::size_t faces = mesh.triangles.size();
  ScalarField& region = mesh.face_fields.add("region", faces, ScalarType::Int32);
  ScalarField& quality = mesh.face_fields.add("quality", faces, ScalarType::Float32);
  ScalarField& flag = mesh.face_fields.add("flag", faces, ScalarType::UInt8);
  for (std::size_t f = 0; f < faces; ++f) {
    region.values[f] = 100000.0 * static_cast<double>(f % 3) - 7.0;
    quality.values[f] = 0.125 * static_cast<double>(f);
    flag.values[f] = static_cast<double>((37 * f) % 256);
  }
  return mesh;
}

class PlyRoundTrip : public ::testing::TestWithParam<PlyEncoding> {};

TEST_P(PlyRoundTrip, KeepsEveryAttributeExactly) {
  const fs::path dir = test::temp_dir("ply_round_trip");
  const fs::path path = dir / "mesh.ply";
  const TriangleMesh mesh = attributed_mesh();
  WriteOptions options;
  options.ply_encoding = GetParam();
  write_mesh(path, mesh, options);

  const MeshReadResult result = read_mesh(path);
  const std::string expected_encoding = GetParam() == PlyEncoding::Ascii             ? "ascii"
                                        : GetParam() == PlyEncoding::BinaryBigEndian ? "binary_big_endian"
                                                                                     : "binary_little_endian";
  EXPECT_EQ(result.format, "ply");
  EXPECT_EQ(result.encoding, expected_encoding);
  const TriangleMesh& back = result.mesh;
  EXPECT_EQ(back.vertices.positions, mesh.vertices.positions);
  EXPECT_EQ(back.vertices.normals, mesh.vertices.normals);
  EXPECT_EQ(back.vertices.colors, mesh.vertices.colors);
  EXPECT_EQ(back.triangles, mesh.triangles);
  ASSERT_EQ(back.vertices.fields.size(), mesh.vertices.fields.size());
  for (const ScalarField& field : mesh.vertices.fields) {
    const ScalarField* got = back.vertices.fields.find(field.name);
    ASSERT_NE(got, nullptr) << field.name;
    EXPECT_EQ(got->type, field.type) << field.name;
    EXPECT_EQ(got->values, field.values) << field.name;
  }
  ASSERT_EQ(back.face_fields.size(), mesh.face_fields.size());
  for (std::size_t i = 0; i < mesh.face_fields.size(); ++i) {
    const ScalarField& field = mesh.face_fields[i];
    EXPECT_EQ(back.face_fields[i].name, field.name);  // in the order written
    EXPECT_EQ(back.face_fields[i].type, field.type) << field.name;
    EXPECT_EQ(back.face_fields[i].values, field.values) << field.name;
  }
  EXPECT_EQ(result.dropped_faces, 0u);
  EXPECT_EQ(result.polygons_triangulated, 0u);
}

INSTANTIATE_TEST_SUITE_P(Encodings, PlyRoundTrip,
                         ::testing::Values(PlyEncoding::BinaryLittleEndian, PlyEncoding::BinaryBigEndian, PlyEncoding::Ascii));

TEST(Ply, EmptyCloudRoundTrips) {
  const fs::path path = test::temp_dir("ply_empty") / "empty.ply";
  PointCloud cloud;
  cloud.fields.add("label", 0, ScalarType::UInt8);
  write_point_cloud(path, cloud);
  const PointCloud back = read_point_cloud(path).cloud;
  EXPECT_TRUE(back.empty());
  ASSERT_NE(back.fields.find("label"), nullptr);
  EXPECT_EQ(back.fields.find("label")->type, ScalarType::UInt8);
}

TEST(Ply, AsciiOptionOverridesEncodingAndCloudReadCountsFaces) {
  const fs::path path = test::temp_dir("ply_ascii_option") / "mesh.ply";
  WriteOptions options;
  options.ply_encoding = PlyEncoding::BinaryBigEndian;
  options.ascii = true;
  write_mesh(path, attributed_mesh(), options);
  const CloudReadResult result = read_point_cloud(path);
  EXPECT_EQ(result.encoding, "ascii");
  EXPECT_EQ(result.cloud.size(), 50u);
  EXPECT_EQ(result.face_count, 16u);
}

TEST(Ply, Int64FieldsAreWrittenAsDouble) {
  const fs::path path = test::temp_dir("ply_int64") / "cloud.ply";
  PointCloud cloud = test::sample_plane(4);
  ScalarField& f = cloud.fields.add("gps_id", 4, ScalarType::Int64);
  f.values = {1e15, -2, 3, 9007199254740992.0};
  write_point_cloud(path, cloud);
  const PointCloud back = read_point_cloud(path).cloud;
  ASSERT_NE(back.fields.find("gps_id"), nullptr);
  EXPECT_EQ(back.fields.find("gps_id")->type, ScalarType::Float64);
  EXPECT_EQ(back.fields.find("gps_id")->values, f.values);
}

TEST(Ply, AsciiWithOddOrderSpellingsAndExtraElements) {
  const fs::path path = test::temp_dir("ply_odd") / "odd.ply";
  write_bytes(path,
              "ply\r\n"
              "format ascii 1.0\r\n"
              "comment made by hand\r\n"
              "obj_info anything at all\r\n"
              "element vertex 4\r\n"
              "property float64 z\r\n"
              "property uint8 red\r\n"
              "property int8 x\r\n"
              "property uchar green\r\n"
              "property float32 y\r\n"
              "property uint8 blue\r\n"
              "property list uchar float texcoord\r\n"
              "property float32 nz\r\n"
              "property float32 nx\r\n"
              "property float32 ny\r\n"
              "property int16 quality\r\n"
              "element edge 2\r\n"
              "property int vertex1\r\n"
              "property int vertex2\r\n"
              "property list uchar int extra\r\n"
              "element face 2\r\n"
              "property uchar flags\r\n"
              "property list uint8 int32 vertex_index\r\n"
              "property list uchar float texcoord\r\n"
              "property float area\r\n"
              "end_header\r\n"
              "0.5 255 1 0 2.25 51 2 0.1 0.2 0 0 1 -7\r\n"
              "1.5 0 -2 102 3.5 0 0 1 0 0 12\r\n"
              "\r\n"
              "2.5 10 3 20 4.5 30 1 9 0 1 0 300\r\n"
              "3.5 40 -128 50 5.5 60 0 1 0 0 -1\r\n"
              "0 1 0\r\n"
              "1 2 3 7 8 9\r\n"
              "7 3 0 1 2 6 0 0 1 0 1 1 0.5\r\n"
              "0 3 1 2 3 0 0.25\r\n"
              "trailing data after the last element is allowed\r\n");
  const MeshReadResult result = read_mesh(path);
  const TriangleMesh& mesh = result.mesh;
  ASSERT_EQ(mesh.vertex_count(), 4u);
  EXPECT_EQ(mesh.vertices.positions[0], Vector3d(1, 2.25, 0.5));
  EXPECT_EQ(mesh.vertices.positions[1], Vector3d(-2, 3.5, 1.5));
  EXPECT_EQ(mesh.vertices.positions[3], Vector3d(-128, 5.5, 3.5));
  ASSERT_EQ(mesh.vertices.normals.size(), 4u);
  EXPECT_EQ(mesh.vertices.normals[0], Vector3d(0, 1, 0));  // nz nx ny = 0 0 1
  EXPECT_EQ(mesh.vertices.normals[1], Vector3d(0, 0, 1));
  ASSERT_EQ(mesh.vertices.colors.size(), 4u);
  EXPECT_EQ(mesh.vertices.colors[0], Vector3f(1.0f, 0.0f, 51 / 255.0f));
  EXPECT_EQ(mesh.vertices.colors[2], Vector3f(10 / 255.0f, 20 / 255.0f, 30 / 255.0f));
  ASSERT_EQ(mesh.vertices.fields.size(), 1u);
  const ScalarField* quality = mesh.vertices.fields.find("quality");
  ASSERT_NE(quality, nullptr);
  EXPECT_EQ(quality->type, ScalarType::Int16);
  EXPECT_EQ(quality->values, (std::vector<double>{-7, 12, 300, -1}));
  EXPECT_EQ(mesh.triangles, (std::vector<Triangle>{Triangle(0, 1, 2), Triangle(1, 2, 3)}));
  // The scalar face properties on either side of the lists become face fields of their type.
  ASSERT_EQ(mesh.face_fields.size(), 2u);
  EXPECT_EQ(mesh.face_fields[0].name, "flags");
  EXPECT_EQ(mesh.face_fields[0].type, ScalarType::UInt8);
  EXPECT_EQ(mesh.face_fields[0].values, (std::vector<double>{7, 0}));
  EXPECT_EQ(mesh.face_fields[1].name, "area");
  EXPECT_EQ(mesh.face_fields[1].type, ScalarType::Float32);
  EXPECT_EQ(mesh.face_fields[1].values, (std::vector<double>{0.5, 0.25}));
}

// What pcl_pcd2ply / pcl::PLYWriter writes for a point cloud: an empty "element face 0" with
// no properties, then a "camera" element of floats and ints. Nothing is lost, so no warning.
TEST(Ply, PclStyleEmptyFaceElementAndCameraGiveNoWarning) {
  const fs::path path = test::temp_dir("ply_pcl_style") / "pcl.ply";
  std::string bytes =
      "ply\nformat binary_little_endian 1.0\ncomment PCL generated\n"
      "element vertex 2\nproperty double x\nproperty double y\nproperty double z\n"
      "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty int label\n"
      "element face 0\n"
      "element camera 1\n";
  for (const char* p : {"view_px", "view_py", "view_pz", "x_axisx", "x_axisy", "x_axisz", "y_axisx", "y_axisy", "y_axisz",
                        "z_axisx", "z_axisy", "z_axisz", "focal", "scalex", "scaley", "centerx", "centery"})
    bytes += std::string("property float ") + p + "\n";
  bytes += "property int viewportx\nproperty int viewporty\nproperty float k1\nproperty float k2\nend_header\n";
  const double xyz[2][3] = {{596648.0625, 243620.015625, 73.5}, {596738.9375, 243731.984375, 97.25}};
  for (int i = 0; i < 2; ++i) {
    for (double v : xyz[i]) put<double>(bytes, v, false);
    for (int c = 0; c < 3; ++c) put<std::uint8_t>(bytes, static_cast<std::uint8_t>(10 * i + c), false);
    put<std::int32_t>(bytes, i - 1, false);
  }
  for (int k = 0; k < 17; ++k) put<float>(bytes, 0.0f, false);
  put<std::int32_t>(bytes, 2, false);
  put<std::int32_t>(bytes, 1, false);
  put<float>(bytes, 0.0f, false);
  put<float>(bytes, 0.0f, false);
  write_bytes(path, bytes);

  const CloudReadResult result = read_point_cloud(path);
  EXPECT_TRUE(result.warnings.empty()) << result.warnings.front();
  EXPECT_EQ(result.face_count, 0u);
  ASSERT_EQ(result.cloud.size(), 2u);
  EXPECT_EQ(result.cloud.positions[1], Vector3d(xyz[1][0], xyz[1][1], xyz[1][2]));
  EXPECT_EQ(result.cloud.colors[1], Vector3f(10 / 255.0f, 11 / 255.0f, 12 / 255.0f));
  ASSERT_NE(result.cloud.fields.find("label"), nullptr);
  EXPECT_EQ(result.cloud.fields.find("label")->values, (std::vector<double>{-1, 0}));
}

TEST(Ply, DiffuseColoursUshortColoursAndAlpha) {
  const fs::path path = test::temp_dir("ply_diffuse") / "c.ply";
  write_bytes(path,
              "ply\nformat ascii 1.0\nelement vertex 2\n"
              "property float x\nproperty float y\nproperty float z\n"
              "property ushort diffuse_red\nproperty ushort diffuse_green\nproperty ushort diffuse_blue\nproperty uchar alpha\n"
              "end_header\n"
              "0 0 0 65535 0 13107 255\n"
              "1 1 1 0 65535 0 128\n");
  const PointCloud cloud = read_point_cloud(path).cloud;
  ASSERT_EQ(cloud.colors.size(), 2u);
  EXPECT_EQ(cloud.colors[0], Vector3f(1.0f, 0.0f, 13107 / 65535.0f));
  EXPECT_EQ(cloud.colors[1], Vector3f(0.0f, 1.0f, 0.0f));
  const ScalarField* alpha = cloud.fields.find("alpha");
  ASSERT_NE(alpha, nullptr);
  EXPECT_EQ(alpha->type, ScalarType::UInt8);
  EXPECT_EQ(alpha->values, (std::vector<double>{255, 128}));
}

TEST(Ply, FloatColoursAreTakenAsIs) {
  const fs::path path = test::temp_dir("ply_float_colours") / "c.ply";
  write_bytes(path,
              "ply\nformat ascii 1.0\nelement vertex 1\n"
              "property double x\nproperty double y\nproperty double z\n"
              "property float red\nproperty float green\nproperty float blue\nend_header\n"
              "0 0 0 0.25 0.5 0.75\n");
  EXPECT_EQ(read_point_cloud(path).cloud.colors[0], Vector3f(0.25f, 0.5f, 0.75f));
}

TEST(Ply, BigEndianBinaryBuiltByteByByte) {
  const fs::path path = test::temp_dir("ply_big_endian") / "be.ply";
  std::string bytes =
      "ply\nformat binary_big_endian 1.0\n"
      "element vertex 3\n"
      "property float x\nproperty list uchar float uv\nproperty double y\nproperty int z\n"
      "property ushort intensity\nproperty char tag\n"
      "element edge 2\nproperty int vertex1\nproperty int vertex2\n"
      "element material 1\nproperty list ushort uchar name\n"
      "element face 1\n"
      "property list int uint vertex_indices\n"
      "property uchar flags\n"
      "end_header\n";
  const float xs[3] = {1.5f, -2.0f, 1e6f};
  const double ys[3] = {0.1, 6500000.123456, -3.0};
  const std::int32_t zs[3] = {7, -8, 2000000000};
  for (int i = 0; i < 3; ++i) {
    put<float>(bytes, xs[i], true);
    put<std::uint8_t>(bytes, static_cast<std::uint8_t>(2 * i), true);  // records of varying size
    for (int k = 0; k < 2 * i; ++k) put<float>(bytes, 0.5f, true);
    put<double>(bytes, ys[i], true);
    put<std::int32_t>(bytes, zs[i], true);
    put<std::uint16_t>(bytes, static_cast<std::uint16_t>(60000 + i), true);
    put<std::int8_t>(bytes, static_cast<std::int8_t>(-1 - i), true);
  }
  for (int k = 0; k < 4; ++k) put<std::int32_t>(bytes, k, true);  // two edges
  put<std::uint16_t>(bytes, 3, true);  // material: a 3-byte name
  bytes += "abc";
  put<std::int32_t>(bytes, 3, true);
  put<std::uint32_t>(bytes, 2, true);
  put<std::uint32_t>(bytes, 0, true);
  put<std::uint32_t>(bytes, 1, true);
  put<std::uint8_t>(bytes, 9, true);
  write_bytes(path, bytes);

  const MeshReadResult result = read_mesh(path);
  EXPECT_EQ(result.encoding, "binary_big_endian");
  const TriangleMesh& mesh = result.mesh;
  ASSERT_EQ(mesh.vertex_count(), 3u);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(mesh.vertices.positions[i], Vector3d(xs[i], ys[i], zs[i])) << i;
  ASSERT_NE(mesh.vertices.fields.find("intensity"), nullptr);
  EXPECT_EQ(mesh.vertices.fields.find("intensity")->type, ScalarType::UInt16);
  EXPECT_EQ(mesh.vertices.fields.find("intensity")->values, (std::vector<double>{60000, 60001, 60002}));
  EXPECT_EQ(mesh.vertices.fields.find("tag")->type, ScalarType::Int8);
  EXPECT_EQ(mesh.vertices.fields.find("tag")->values, (std::vector<double>{-1, -2, -3}));
  EXPECT_EQ(mesh.triangles, (std::vector<Triangle>{Triangle(2, 0, 1)}));
}

TEST(Ply, QuadsAreTriangulatedByReadMesh) {
  const fs::path path = test::temp_dir("ply_quads") / "quads.ply";
  write_bytes(path,
              "ply\nformat ascii 1.0\nelement vertex 6\n"
              "property float x\nproperty float y\nproperty float z\n"
              "element face 3\nproperty list uchar int vertex_indices\nend_header\n"
              "0 0 0\n1 0 0\n2 0 0\n0 1 0\n1 1 0\n2 1 0\n"
              "4 0 1 4 3\n4 1 2 5 4\n3 0 4 3\n");
  const MeshReadResult result = read_mesh(path);
  EXPECT_EQ(result.polygons_triangulated, 2u);
  EXPECT_EQ(result.mesh.triangles,
            (std::vector<Triangle>{Triangle(0, 1, 4), Triangle(0, 4, 3), Triangle(1, 2, 5), Triangle(1, 5, 4), Triangle(0, 4, 3)}));
}

TEST(Ply, FaceFieldsFollowPolygonFansAndDroppedFaces) {
  const fs::path path = test::temp_dir("ply_face_fields") / "quads.ply";
  // Binary, big endian: a quad (split in two), a degenerate triangle (dropped), a triangle.
  std::string bytes =
      "ply\nformat binary_big_endian 1.0\nelement vertex 5\nproperty double x\nproperty double y\nproperty double z\n"
      "element face 3\nproperty short part\nproperty list uchar int vertex_indices\nproperty double weight\nend_header\n";
  const double xy[5][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {2, 0}};
  for (const auto& p : xy) {
    put(bytes, p[0], true);
    put(bytes, p[1], true);
    put(bytes, 0.0, true);
  }
  auto face = [&](std::int16_t part, std::vector<std::int32_t> corners, double weight) {
    put(bytes, part, true);
    put(bytes, static_cast<std::uint8_t>(corners.size()), true);
    for (const std::int32_t c : corners) put(bytes, c, true);
    put(bytes, weight, true);
  };
  face(-3, {0, 1, 2, 3}, 0.5);
  face(8, {1, 1, 4}, 2.0);
  face(11, {1, 4, 2}, -1.25);
  write_bytes(path, bytes);
  const MeshReadResult result = read_mesh(path);
  EXPECT_EQ(result.polygons_triangulated, 1u);
  EXPECT_EQ(result.dropped_faces, 1u);
  const TriangleMesh& mesh = result.mesh;
  ASSERT_EQ(mesh.triangles, (std::vector<Triangle>{Triangle(0, 1, 2), Triangle(0, 2, 3), Triangle(1, 4, 2)}));
  ASSERT_NE(mesh.face_fields.find("part"), nullptr);
  EXPECT_EQ(mesh.face_fields.find("part")->type, ScalarType::Int16);
  EXPECT_EQ(mesh.face_fields.find("part")->values, (std::vector<double>{-3, -3, 11}));
  ASSERT_NE(mesh.face_fields.find("weight"), nullptr);
  EXPECT_EQ(mesh.face_fields.find("weight")->values, (std::vector<double>{0.5, 0.5, -1.25}));
  EXPECT_NO_THROW(mesh.validate());
  // A cloud read of the same file has no faces and so no face fields to keep.
  EXPECT_EQ(read_point_cloud(path).face_count, 3u);
}

TEST(Ply, FaceFieldsNeedFacesAndGoodNames) {
  const fs::path dir = test::temp_dir("ply_face_field_errors");
  TriangleMesh mesh = attributed_mesh();
  // Without faces there is no face element, so nothing to write them into: no error.
  TriangleMesh no_faces = mesh;
  no_faces.triangles.clear();
  for (ScalarField& f : no_faces.face_fields) f.values.clear();
  write_mesh(dir / "points.ply", no_faces);
  EXPECT_TRUE(read_mesh(dir / "points.ply").mesh.face_fields.empty());
  mesh.face_fields.add("bad name", mesh.triangle_count(), ScalarType::Int32);
  test::expect_error<UsageError>([&] { write_mesh(dir / "bad.ply", mesh); }, "face field name 'bad name' cannot be written to PLY");
  TriangleMesh short_field = attributed_mesh();
  short_field.face_fields.add("short", 2);
  test::expect_error<InputError>([&] { write_mesh(dir / "short.ply", short_field); },
                                 "mesh: face field 'short' has 2 values for 16 triangles");
  TriangleMesh clash = attributed_mesh();
  clash.face_fields.add("vertex_indices", clash.triangle_count());
  test::expect_error<UsageError>([&] { write_mesh(dir / "clash.ply", clash); }, "clashes with the PLY corner list");
}

TEST(Ply, GeoreferencedCloudSurvivesDoubleRoundTrip) {
  const fs::path dir = test::temp_dir("ply_georef");
  PointCloud cloud = test::sample_plane(1000, 50.0, 5);
  for (Vector3d& p : cloud.positions) p += Vector3d(6500000.0, 5200000.0, 300.0);
  for (PlyEncoding encoding : {PlyEncoding::BinaryLittleEndian, PlyEncoding::Ascii}) {
    WriteOptions options;
    options.ply_encoding = encoding;
    write_point_cloud(dir / "geo.ply", cloud, options);
    const PointCloud back = read_point_cloud(dir / "geo.ply").cloud;
    ASSERT_EQ(back.size(), cloud.size());
    double worst = 0;
    for (std::size_t i = 0; i < cloud.size(); ++i) worst = std::max(worst, (back.positions[i] - cloud.positions[i]).norm());
    EXPECT_LT(worst, 1e-4);
  }
}

TEST(Ply, SinglePrecisionIsRefusedForGeoreferencedCloud) {
  const fs::path dir = test::temp_dir("ply_single_refused");
  PointCloud cloud = test::sample_plane(100, 50.0, 5);
  for (Vector3d& p : cloud.positions) p += Vector3d(6500000.0, 0.0, 0.0);
  WriteOptions options;
  options.single_precision = true;
  const std::string message = error_of<UsageError>([&] { write_point_cloud(dir / "geo.ply", cloud, options); });
  EXPECT_NE(message.find("float32 steps are 0.5 at 6.5"), std::string::npos) << message;
  EXPECT_NE(message.find("write double"), std::string::npos) << message;
  EXPECT_FALSE(fs::exists(dir / "geo.ply"));
}

TEST(Ply, SinglePrecisionWritesFloatsForSmallCoordinates) {
  const fs::path path = test::temp_dir("ply_single") / "s.ply";
  const PointCloud cloud = test::sample_sphere(100, 1.0, Vector3d::Zero(), 9);
  WriteOptions options;
  options.single_precision = true;
  write_point_cloud(path, cloud, options);
  const PointCloud back = read_point_cloud(path).cloud;
  ASSERT_EQ(back.size(), 100u);
  for (std::size_t i = 0; i < 100; ++i) {
    EXPECT_EQ(back.positions[i], cloud.positions[i].cast<float>().cast<double>());
    EXPECT_EQ(back.normals[i], cloud.normals[i].cast<float>().cast<double>());
  }
  // Six floats per point after the header.
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(bytes.find("property float x\n"), std::string::npos);
  EXPECT_NE(bytes.find("property float nx\n"), std::string::npos);
  EXPECT_EQ(bytes.size() - (bytes.find("end_header\n") + 11), 100u * 6u * 4u);
}

TEST(Ply, ReadsTheShippedAerialScan) {
  const CloudReadResult result = read_point_cloud(test::data_path("b9_training.ply"));
  EXPECT_EQ(result.encoding, "binary_little_endian");
  ASSERT_EQ(result.cloud.size(), 22300u);
  EXPECT_TRUE(result.cloud.has_colors());
  const ScalarField* label = result.cloud.fields.find("label");
  ASSERT_NE(label, nullptr);
  EXPECT_EQ(label->type, ScalarType::Int32);
  const BoundingBox box = bounding_box(result.cloud.positions);
  EXPECT_GT(box.min.x(), 590000.0);
  EXPECT_LT(box.max.x(), 600000.0);
}

// ---- malformed input -------------------------------------------------------------------------

std::string read_error(const fs::path& path) {
  return error_of<InputError>([&] { read_point_cloud(path); });
}

const char* const kXyzDoubleHeader =
    "ply\nformat binary_little_endian 1.0\nelement vertex 2000\n"
    "property double x\nproperty double y\nproperty double z\nend_header\n";

TEST(PlyErrors, TruncatedBinaryBodyNamesTheVertex) {
  const fs::path path = test::temp_dir("ply_truncated") / "scan.ply";
  std::string bytes = kXyzDoubleHeader;
  const std::size_t header = bytes.size();
  bytes.append(1532 * 24 + 10, '\0');
  write_bytes(path, bytes);
  const std::string message = read_error(path);
  EXPECT_TRUE(contains(message, "scan.ply: vertex 1532 of 2000: file ends at byte " + std::to_string(header + 1532 * 24 + 10) +
                                    ", expected 24 bytes"))
      << message;
}

TEST(PlyErrors, TruncatedFaceList) {
  const fs::path path = test::temp_dir("ply_truncated_face") / "mesh.ply";
  std::string bytes =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\n"
      "property float x\nproperty float y\nproperty float z\n"
      "element face 2\nproperty list uchar int vertex_indices\nend_header\n";
  bytes.append(36, '\0');
  put<std::uint8_t>(bytes, 3, false);
  for (int i = 0; i < 3; ++i) put<std::int32_t>(bytes, i, false);
  put<std::uint8_t>(bytes, 3, false);
  put<std::int32_t>(bytes, 0, false);
  write_bytes(path, bytes);
  const std::string message = read_error(path);
  EXPECT_TRUE(contains(message, "mesh.ply: face 1 of 2: list 'vertex_indices' of 3 items needs 12 bytes, file ends at byte")) << message;
}

TEST(PlyErrors, AsciiLineWithTooFewValues) {
  const fs::path path = test::temp_dir("ply_few_values") / "scan.ply";
  std::string text =
      "ply\nformat ascii 1.0\ncomment one\ncomment two\nelement vertex 8\n"
      "property float x\nproperty float y\nproperty float z\n"
      "property float nx\nproperty float ny\nproperty float nz\nend_header\n";  // 12 lines
  for (int i = 0; i < 5; ++i) text += "1 2 3 0 0 1\n";                        // lines 13-17: vertices 0-4
  text += "1 2 3 0\n";                                                          // line 18: vertex 5
  text += "1 2 3 0 0 1\n1 2 3 0 0 1\n";
  write_bytes(path, text);
  const std::string message = read_error(path);
  EXPECT_TRUE(contains(message, "scan.ply: line 18 (vertex 5): expected 6 values, got 4")) << message;
}

TEST(PlyErrors, AsciiLineWithTooManyValues) {
  const fs::path path = test::temp_dir("ply_many_values") / "scan.ply";
  write_bytes(path,
              "ply\nformat ascii 1.0\nelement vertex 1\n"
              "property float x\nproperty float y\nproperty float z\nend_header\n1 2 3 4\n");
  EXPECT_TRUE(contains(read_error(path), "scan.ply: line 8 (vertex 0): expected 3 values, got 4"));
}

TEST(PlyErrors, AsciiBodyEndsEarly) {
  const fs::path path = test::temp_dir("ply_ascii_short") / "scan.ply";
  write_bytes(path,
              "ply\nformat ascii 1.0\nelement vertex 3\n"
              "property float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n4 5 6\n");
  EXPECT_TRUE(contains(read_error(path), "scan.ply: vertex 2 of 3: file ends after line 9, expected 3 values"));
}

TEST(PlyErrors, NonNumericToken) {
  const fs::path path = test::temp_dir("ply_nan_token") / "scan.ply";
  write_bytes(path,
              "ply\nformat ascii 1.0\nelement vertex 2\n"
              "property float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n4 five 6\n");
  EXPECT_TRUE(contains(read_error(path), "scan.ply: line 9 (vertex 1): 'five' is not a number (property 'y')"));
}

TEST(PlyErrors, UnknownPropertyType) {
  const fs::path path = test::temp_dir("ply_bad_type") / "scan.ply";
  write_bytes(path,
              "ply\nformat ascii 1.0\nelement vertex 1\n"
              "property float x\nproperty float y\nproperty quad z\nend_header\n1 2 3\n");
  EXPECT_TRUE(contains(read_error(path), "scan.ply: line 6: unknown property type 'quad'"));
}

TEST(PlyErrors, MissingEndHeader) {
  const fs::path path = test::temp_dir("ply_no_end") / "scan.ply";
  write_bytes(path, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n1 2 3\n");
  EXPECT_TRUE(contains(read_error(path), "scan.ply: line 7: unknown header keyword '1'"));
  write_bytes(path, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n");
  EXPECT_TRUE(contains(read_error(path), "scan.ply: the header has no end_header line (file ends after line 6)"));
}

TEST(PlyErrors, MissingCoordinate) {
  const fs::path path = test::temp_dir("ply_no_z") / "scan.ply";
  write_bytes(path, "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float w\nend_header\n1 2 3\n");
  EXPECT_TRUE(contains(read_error(path), "scan.ply: line 3: element vertex has no property 'z': expected x, y and z"));
}

TEST(PlyErrors, FormatLineIsValidated) {
  const fs::path path = test::temp_dir("ply_format") / "scan.ply";
  const std::string rest = "element vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n";
  write_bytes(path, "ply\nformat binary_middle_endian 1.0\n" + rest);
  EXPECT_TRUE(contains(read_error(path), "scan.ply: line 2: unknown PLY encoding 'binary_middle_endian'"));
  write_bytes(path, "ply\nformat ascii 2.0\n" + rest);
  EXPECT_TRUE(contains(read_error(path), "scan.ply: line 2: unsupported PLY version '2.0': expected 1.0"));
  write_bytes(path, "ply\n" + rest);
  EXPECT_TRUE(contains(read_error(path), "scan.ply: the header has no 'format' line"));
}

TEST(PlyErrors, HugeVertexCountInTinyFile) {
  const fs::path dir = test::temp_dir("ply_huge");
  std::string binary = kXyzDoubleHeader;
  binary.replace(binary.find("2000"), 4, "1000000000000");
  binary.append(48, '\0');
  write_bytes(dir / "binary.ply", binary);
  const std::string message = read_error(dir / "binary.ply");
  EXPECT_TRUE(contains(message, "binary.ply: vertex 2 of 1000000000000: file ends at byte")) << message;

  write_bytes(dir / "ascii.ply",
              "ply\nformat ascii 1.0\nelement vertex 1000000000000\n"
              "property float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n");
  EXPECT_TRUE(contains(read_error(dir / "ascii.ply"), "ascii.ply: vertex 1 of 1000000000000: file ends after line 8, expected 3 values"));

  // A huge face count after a valid vertex block.
  std::string faces =
      "ply\nformat binary_little_endian 1.0\nelement vertex 1\n"
      "property float x\nproperty float y\nproperty float z\n"
      "element face 4000000000\nproperty list uchar int vertex_indices\nend_header\n";
  faces.append(12 + 13, '\0');
  write_bytes(dir / "faces.ply", faces);
  EXPECT_TRUE(contains(read_error(dir / "faces.ply"), "faces.ply: face 13 of 4000000000: file ends at byte"));
}

TEST(PlyErrors, NegativeOrAbsurdListCount) {
  const fs::path dir = test::temp_dir("ply_list_count");
  const std::string header =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\n"
      "property float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list int int vertex_indices\nend_header\n";
  std::string negative = header;
  negative.append(36, '\0');
  put<std::int32_t>(negative, -5, false);
  negative.append(12, '\0');
  write_bytes(dir / "negative.ply", negative);
  EXPECT_TRUE(contains(read_error(dir / "negative.ply"), "negative.ply: face 0, property 'vertex_indices': list count -5 is negative: expected an integer >= 0"));

  std::string absurd = header;
  absurd.append(36, '\0');
  put<std::int32_t>(absurd, 2000000000, false);
  absurd.append(12, '\0');
  write_bytes(dir / "absurd.ply", absurd);
  EXPECT_TRUE(contains(read_error(dir / "absurd.ply"), "absurd.ply: face 0 of 1: list 'vertex_indices' of 2000000000 items needs 8000000000 bytes"));

  const std::string ascii_header =
      "ply\nformat ascii 1.0\nelement vertex 3\n"
      "property float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list int int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n";
  write_bytes(dir / "ascii_negative.ply", ascii_header + "-3 0 1 2\n");
  EXPECT_TRUE(contains(read_error(dir / "ascii_negative.ply"), "line 13 (face 0), property 'vertex_indices': list count -3 is negative"));
  write_bytes(dir / "ascii_absurd.ply", ascii_header + "99999999999 0 1 2\n");
  EXPECT_TRUE(contains(read_error(dir / "ascii_absurd.ply"), "line 13 (face 0): list 'vertex_indices' has count 99999999999 but only 3 values follow it on the line"));
}

TEST(PlyErrors, FaceIndexOutOfRange) {
  const fs::path path = test::temp_dir("ply_face_range") / "mesh.ply";
  write_bytes(path,
              "ply\nformat ascii 1.0\nelement vertex 3\n"
              "property float x\nproperty float y\nproperty float z\n"
              "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n");
  const std::string message = error_of<InputError>([&] { read_mesh(path); });
  EXPECT_TRUE(contains(message, "mesh.ply: face 0: vertex index 3 out of range [0, 3)")) << message;
}

TEST(PlyErrors, NotAPlyFile) {
  const fs::path path = test::temp_dir("ply_magic") / "scan.ply";
  write_bytes(path, "plyx\nformat ascii 1.0\n");
  ReadOptions options;
  options.format = "ply";
  const std::string message = error_of<InputError>([&] { read_point_cloud(path, options); });
  EXPECT_TRUE(contains(message, "scan.ply: line 1: expected 'ply'")) << message;
}

}  // namespace
}  // namespace pointsurf
