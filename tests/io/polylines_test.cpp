// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/io/polylines.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "pointsurf/core/error.h"
#include "support/files.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

std::vector<Polyline> two_lines() {
  Polyline square{{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}, true};
  Polyline open{{{5e6, 1e6, 3}, {5e6 + 0.25, 1e6, 3}}, false};
  return {square, open};
}

TEST(WritePolylines, LengthsAndEachFormat) {
  const std::vector<Polyline> lines = two_lines();
  EXPECT_DOUBLE_EQ(lines[0].length(), 4.0);
  EXPECT_DOUBLE_EQ(lines[1].length(), 0.25);
  const std::filesystem::path dir = test::temp_dir("polylines");
  PolylineWriteOptions options;
  options.crs = "EPSG:25832";
  options.group = {7, 8};
  write_polylines(dir / "l.ply", lines, options);
  const std::string ply = test::read_bytes(dir / "l.ply");
  EXPECT_TRUE(test::contains(ply, "element vertex 6\n"));
  EXPECT_TRUE(test::contains(ply, "element edge 5\n"));
  EXPECT_TRUE(test::contains(ply, "\n3 0 7\n"));  // the closing edge
  write_polylines(dir / "l.obj", lines, options);
  EXPECT_TRUE(test::contains(test::read_bytes(dir / "l.obj"), "l 1 2 3 4 1\n"));
  write_polylines(dir / "l.geojson", lines, options);
  const nlohmann::json doc = nlohmann::json::parse(test::read_bytes(dir / "l.geojson"));
  EXPECT_EQ(doc["crs"]["properties"]["name"], "EPSG:25832");
  ASSERT_EQ(doc["features"].size(), 2u);
  EXPECT_EQ(doc["features"][0]["geometry"]["type"], "Polygon");
  EXPECT_EQ(doc["features"][1]["geometry"]["type"], "LineString");
  EXPECT_EQ(doc["features"][1]["geometry"]["coordinates"][0][0].get<double>(), 5e6);
  EXPECT_EQ(doc["features"][0]["properties"]["group"], 7);
  EXPECT_EQ(doc["features"][1]["properties"]["closed"], false);
}

// The rings of GeoJSON Polygon `geometry` as lists of x, y, z.
std::vector<std::vector<Eigen::Vector3d>> polygon_rings(const nlohmann::json& geometry) {
  std::vector<std::vector<Eigen::Vector3d>> rings;
  for (const nlohmann::json& ring : geometry["coordinates"]) {
    rings.emplace_back();
    for (const nlohmann::json& p : ring) rings.back().emplace_back(p[0].get<double>(), p[1].get<double>(), p[2].get<double>());
  }
  return rings;
}

TEST(WritePolylines, ClosedOutlineIsACounterClockwisePolygon) {
  // Given clockwise, at a georeferenced offset.
  const Eigen::Vector3d o(5e5, 5.4e6, 100.0);
  const std::vector<Polyline> lines = {Polyline{{o, o + Eigen::Vector3d(0, 2, 0), o + Eigen::Vector3d(2, 2, 0), o + Eigen::Vector3d(2, 0, 0)}, true}};
  const std::filesystem::path file = test::temp_dir("polylines_square") / "square.geojson";
  write_polylines(file, lines);
  const nlohmann::json doc = nlohmann::json::parse(test::read_bytes(file));
  EXPECT_FALSE(doc.contains("crs"));
  ASSERT_EQ(doc["features"].size(), 1u);
  const nlohmann::json& f = doc["features"][0];
  EXPECT_EQ(f["geometry"]["type"], "Polygon");
  const std::vector<std::vector<Eigen::Vector3d>> rings = polygon_rings(f["geometry"]);
  ASSERT_EQ(rings.size(), 1u);
  // Closed (first repeated last), counter-clockwise, from the same first vertex.
  const std::vector<Eigen::Vector3d> expected = {o, o + Eigen::Vector3d(2, 0, 0), o + Eigen::Vector3d(2, 2, 0), o + Eigen::Vector3d(0, 2, 0), o};
  EXPECT_EQ(rings[0], expected);
  EXPECT_EQ(f["properties"]["closed"], true);
  EXPECT_EQ(f["properties"]["holes"], 0);
  EXPECT_DOUBLE_EQ(f["properties"]["length"].get<double>(), 8.0);
  // A polyline that ends where it starts is a ring too, written with that vertex once at each end.
  Polyline repeated = lines[0];
  repeated.closed = false;
  repeated.points.push_back(o);
  write_polylines(file, std::vector<Polyline>{repeated});
  EXPECT_EQ(polygon_rings(nlohmann::json::parse(test::read_bytes(file))["features"][0]["geometry"])[0], expected);
}

TEST(WritePolylines, HolesAreInnerRingsOfTheirOuterPolygon) {
  // Two squares of one segment, the second with a square hole; an open polyline after them.
  const std::vector<Polyline> lines = {
      Polyline{{{0, 0, 1}, {4, 0, 1}, {4, 4, 1}, {0, 4, 1}}, true},
      Polyline{{{10, 0, 1}, {12, 0, 1}, {12, 2, 1}, {10, 2, 1}}, true},
      Polyline{{{1, 1, 1}, {3, 1, 1}, {3, 3, 1}, {1, 3, 1}}, true},
      Polyline{{{0, -1, 0}, {5, -1, 0}, {5, -2, 0}}, false},
  };
  PolylineWriteOptions options;
  options.group = {3, 3, 3, 4};
  options.outer = {-1, -1, 0, -1};
  const std::filesystem::path dir = test::temp_dir("polylines_holes");
  write_polylines(dir / "holes.geojson", lines, options);
  const nlohmann::json doc = nlohmann::json::parse(test::read_bytes(dir / "holes.geojson"));
  ASSERT_EQ(doc["features"].size(), 3u);
  const nlohmann::json& holed = doc["features"][0];
  EXPECT_EQ(holed["geometry"]["type"], "Polygon");
  EXPECT_EQ(holed["properties"]["holes"], 1);
  EXPECT_DOUBLE_EQ(holed["properties"]["length"].get<double>(), 16.0 + 8.0);
  const std::vector<std::vector<Eigen::Vector3d>> rings = polygon_rings(holed["geometry"]);
  ASSERT_EQ(rings.size(), 2u);
  const std::vector<Eigen::Vector3d> outer = {{0, 0, 1}, {4, 0, 1}, {4, 4, 1}, {0, 4, 1}, {0, 0, 1}};
  const std::vector<Eigen::Vector3d> hole = {{1, 1, 1}, {1, 3, 1}, {3, 3, 1}, {3, 1, 1}, {1, 1, 1}};  // clockwise
  EXPECT_EQ(rings[0], outer);
  EXPECT_EQ(rings[1], hole);
  EXPECT_EQ(doc["features"][1]["geometry"]["type"], "Polygon");
  EXPECT_EQ(polygon_rings(doc["features"][1]["geometry"]).size(), 1u);
  EXPECT_EQ(doc["features"][1]["properties"]["id"], 1);
  const nlohmann::json& open = doc["features"][2];
  EXPECT_EQ(open["geometry"]["type"], "LineString");
  EXPECT_EQ(open["properties"]["id"], 3);
  EXPECT_EQ(open["properties"]["group"], 4);
  EXPECT_EQ(open["geometry"]["coordinates"], nlohmann::json::parse("[[0.0,-1.0,0.0],[5.0,-1.0,0.0],[5.0,-2.0,0.0]]"));
  // PLY and OBJ keep every polyline, holes included, as before.
  write_polylines(dir / "holes.obj", lines, options);
  EXPECT_TRUE(test::contains(test::read_bytes(dir / "holes.obj"), "o polyline_2_group_3\nv 1 1 1\nv 3 1 1\nv 3 3 1\nv 1 3 1\nl 9 10 11 12 9\n"));
  write_polylines(dir / "holes.ply", lines, options);
  EXPECT_TRUE(test::contains(test::read_bytes(dir / "holes.ply"), "element vertex 15\n"));
  // A hole of an open polyline, or of another hole, is refused.
  options.outer = {-1, -1, 3, -1};
  EXPECT_THROW(write_polylines(dir / "bad.geojson", lines, options), UsageError);
  options.outer = {-1, 0, 1, -1};
  EXPECT_THROW(write_polylines(dir / "bad.geojson", lines, options), UsageError);
}

TEST(WritePolylines, RejectsUnknownFormatsAndMismatchedOptions) {
  const std::filesystem::path dir = test::temp_dir("polylines_bad");
  EXPECT_THROW(write_polylines(dir / "l.xyz", two_lines()), UsageError);
  PolylineWriteOptions options;
  options.group = {1};
  EXPECT_THROW(write_polylines(dir / "l.ply", two_lines(), options), UsageError);
  EXPECT_THROW(write_polylines(dir / "missing" / "l.ply", two_lines()), Error);
}

}  // namespace
}  // namespace pointsurf
