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

// A CRS given by its WKT alone.
CoordinateSystem wkt_crs_of(std::string wkt) {
  CoordinateSystem crs;
  crs.wkt = std::move(wkt);
  return crs;
}

TEST(CoordinateSystem, EpsgIsTheCrsOwnAuthorityNotANestedOne) {
  // WKT1: the CRS's AUTHORITY comes after those of its datum, base CRS and units.
  const CoordinateSystem utm = wkt_crs_of(
      R"w(PROJCS["ETRS89 / UTM zone 32N",GEOGCS["ETRS89",DATUM["European_Terrestrial_Reference_System_1989",)w"
      R"w(SPHEROID["GRS 1980",6378137,298.257222101,AUTHORITY["EPSG","7019"]],AUTHORITY["EPSG","6258"]],)w"
      R"w(PRIMEM["Greenwich",0,AUTHORITY["EPSG","8901"]],UNIT["degree",0.0174532925199433,AUTHORITY["EPSG","9122"]],)w"
      R"w(AUTHORITY["EPSG","4258"]],PROJECTION["Transverse_Mercator"],PARAMETER["central_meridian",9],)w"
      R"w(UNIT["metre",1,AUTHORITY["EPSG","9001"]],AXIS["Easting",EAST],AXIS["Northing",NORTH],AUTHORITY["EPSG","25832"]])w");
  EXPECT_EQ(utm.epsg(), 25832);
  EXPECT_EQ(utm.describe(), "ETRS89 / UTM zone 32N (EPSG:25832)");
  // The same CRS with brackets of the other kind and line breaks.
  const CoordinateSystem round = wkt_crs_of("PROJCS (\"ETRS89 / UTM zone 32N\",\n  GEOGCS(\"ETRS89\", AUTHORITY(\"EPSG\",\"4258\")),\n  AUTHORITY(\"EPSG\", \"25832\"))");
  EXPECT_EQ(round.epsg(), 25832);
}

TEST(CoordinateSystem, AWktWithoutItsOwnCodeHasNoneAndSaysSo) {
  // The only authorities are the datum's and the unit's (foot, EPSG:9002).
  const CoordinateSystem feet = wkt_crs_of(
      R"w(PROJCS["NAD83 / local grid (ftUS)",GEOGCS["NAD83",DATUM["North_American_Datum_1983",)w"
      R"w(SPHEROID["GRS 1980",6378137,298.257222101],AUTHORITY["EPSG","6269"]],PRIMEM["Greenwich",0],)w"
      R"w(UNIT["degree",0.0174532925199433]],PROJECTION["Transverse_Mercator"],PARAMETER["scale_factor",0.9999],)w"
      R"w(UNIT["foot",0.3048,AUTHORITY["EPSG","9002"]]])w");
  EXPECT_EQ(feet.epsg(), 0);
  EXPECT_EQ(feet.describe(), "NAD83 / local grid (ftUS) (no EPSG code)");
  // A base CRS's code is not the projected CRS's.
  const CoordinateSystem based = wkt_crs_of(R"w(PROJCS["local",GEOGCS["WGS 84",AUTHORITY["EPSG","4326"]],UNIT["metre",1]])w");
  EXPECT_EQ(based.epsg(), 0);
  EXPECT_EQ(based.describe(), "local (no EPSG code)");
  EXPECT_EQ(wkt_crs_of(R"w(LOCAL_CS["site grid"])w").describe(), "site grid (no EPSG code)");
  EXPECT_EQ(wkt_crs_of("not a WKT").describe(), "not a WKT (no EPSG code)");
  EXPECT_EQ(wkt_crs_of("not a WKT").epsg(), 0);
  // A truncated WKT still names its CRS.
  EXPECT_EQ(wkt_crs_of(R"w(GEOGCS["WGS 84",DATUM["WGS_1984")w").describe(), "WGS 84 (no EPSG code)");
}

TEST(CoordinateSystem, Wkt2IdAfterIdsOfUnitsAndMethods) {
  const CoordinateSystem lv95 = wkt_crs_of(
      R"w(PROJCRS["CH1903+ / LV95",BASEGEOGCRS["CH1903+",DATUM["CH1903+",ELLIPSOID["Bessel 1841",6377397.155,299.1528128,)w"
      R"w(LENGTHUNIT["metre",1]]],PRIMEM["Greenwich",0,ANGLEUNIT["degree",0.0174532925199433]],ID["EPSG",4150]],)w"
      R"w(CONVERSION["Swiss Oblique Mercator 1995",METHOD["Hotine Oblique Mercator (variant B)",ID["EPSG",9815]],)w"
      R"w(PARAMETER["Latitude of projection centre",46.9524055555556,ANGLEUNIT["degree",0.0174532925199433],ID["EPSG",8811]]],)w"
      R"w(CS[Cartesian,2],AXIS["(E)",east,ORDER[1],LENGTHUNIT["metre",1,ID["EPSG",9001]]],)w"
      R"w(AXIS["(N)",north,ORDER[2],LENGTHUNIT["metre",1,ID["EPSG",9001]]],)w"
      R"w(USAGE[SCOPE["Cadastre, engineering survey."],AREA["Liechtenstein; Switzerland."],BBOX[45.82,5.96,47.81,10.49]],ID["EPSG",2056]])w");
  EXPECT_EQ(lv95.epsg(), 2056);
  EXPECT_EQ(lv95.describe(), "CH1903+ / LV95 (EPSG:2056)");
  // A bound CRS is its source CRS.
  const CoordinateSystem bound = wkt_crs_of(
      R"w(BOUNDCRS[SOURCECRS[PROJCRS["CH1903+ / LV95",BASEGEOGCRS["CH1903+",ID["EPSG",4150]],ID["EPSG",2056]]],)w"
      R"w(TARGETCRS[GEOGCRS["WGS 84",ID["EPSG",4326]]],ABRIDGEDTRANSFORMATION["CH1903+ to WGS 84 (1)",METHOD["Geocentric translations",ID["EPSG",9603]]]])w");
  EXPECT_EQ(bound.epsg(), 2056);
  EXPECT_EQ(bound.describe(), "CH1903+ / LV95 (EPSG:2056)");
}

TEST(CoordinateSystem, CompoundCrsIsItsOwnCodeNotAComponents) {
  const std::string horizontal = R"w(PROJCS["ETRS89 / UTM zone 32N",GEOGCS["ETRS89",AUTHORITY["EPSG","4258"]],AUTHORITY["EPSG","25832"]])w";
  const std::string vertical = R"w(VERT_CS["NN2000 height",VERT_DATUM["Norwegian Normal Null 2000",2005,AUTHORITY["EPSG","1096"]],)w"
                               R"w(UNIT["metre",1,AUTHORITY["EPSG","9001"]],AXIS["Gravity-related height",UP],AUTHORITY["EPSG","5941"]])w";
  const CoordinateSystem compound =
      wkt_crs_of(R"w(COMPD_CS["ETRS89 / UTM zone 32N + NN2000 height",)w" + horizontal + "," + vertical + R"w(,AUTHORITY["EPSG","5972"]])w");
  EXPECT_EQ(compound.epsg(), 5972);
  EXPECT_EQ(compound.describe(), "ETRS89 / UTM zone 32N + NN2000 height (EPSG:5972)");
  const CoordinateSystem unnamed = wkt_crs_of(R"w(COMPD_CS["UTM 32N + NN2000",)w" + horizontal + "," + vertical + "]");
  EXPECT_EQ(unnamed.epsg(), 0);
  EXPECT_EQ(unnamed.describe(), "UTM 32N + NN2000 (no EPSG code)");
}

TEST(CoordinateSystem, ADeeplyNestedWktIsReadWithoutRecursingWithoutEnd) {
  // The largest WKT a LAS record holds (64 KiB), all opening brackets: no crash, no code, and a
  // real CRS with its own code after a deep but legal nesting still reads.
  std::string deep;
  while (deep.size() + 2 <= 65535) deep += "A[";
  EXPECT_EQ(wkt_crs_of(deep).epsg(), 0);
  EXPECT_FALSE(wkt_crs_of(deep).describe().empty());
  std::string nested = "PROJCS[\"n\",";
  for (int i = 0; i < 20; ++i) nested += "X[";
  nested += "1";
  for (int i = 0; i < 20; ++i) nested += "]";
  nested += ",AUTHORITY[\"EPSG\",\"25832\"]]";
  EXPECT_EQ(wkt_crs_of(nested).epsg(), 25832);
}

TEST(CoordinateSystem, QuotedNamesMayHoldBracketsAndQuotes) {
  const CoordinateSystem odd = wkt_crs_of(
      R"w(PROJCS["grid ]), AUTHORITY[EPSG,1] (",GEOGCS["WGS 84",AUTHORITY["EPSG","4326"]],UNIT["metre",1,AUTHORITY["EPSG","9001"]],)w"
      R"w(AUTHORITY["EPSG","3857"]])w");
  EXPECT_EQ(odd.epsg(), 3857);
  EXPECT_EQ(odd.describe(), "grid ]), AUTHORITY[EPSG,1] ( (EPSG:3857)");
  // WKT2 doubles a quote inside a quoted text.
  const CoordinateSystem quoted = wkt_crs_of(R"w(PROJCRS["the ""best"" grid (v2]",BASEGEOGCRS["ETRS89",ID["EPSG",4258]],ID["EPSG",25833]])w");
  EXPECT_EQ(quoted.epsg(), 25833);
  EXPECT_EQ(quoted.describe(), R"w(the "best" grid (v2] (EPSG:25833))w");
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
