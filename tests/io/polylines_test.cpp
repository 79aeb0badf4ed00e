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
  options.hole = {0, 1};
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
  EXPECT_EQ(doc["features"][0]["geometry"]["coordinates"].size(), 5u);  // closed: first repeated
  EXPECT_EQ(doc["features"][1]["geometry"]["coordinates"][0][0].get<double>(), 5e6);
  EXPECT_EQ(doc["features"][1]["properties"]["hole"], true);
  EXPECT_EQ(doc["features"][0]["properties"]["group"], 7);
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
