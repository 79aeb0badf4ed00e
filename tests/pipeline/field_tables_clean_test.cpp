// SPDX-License-Identifier: GPL-3.0-or-later
// The field tables of the clean and simplify stages' Params: complete, and the keys of the
// previous release (x_in_spacings) still accepted, with a deprecation warning, as lengths in
// spacings.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_run.h"
#include "field_tables.h"

#include "pointsurf/clean/remove_duplicates.h"
#include "pointsurf/clean/remove_outliers.h"
#include "pointsurf/clean/smooth_points.h"
#include "pointsurf/core/fields.h"
#include "pointsurf/io/io.h"
#include "pointsurf/pipeline/registry.h"
#include "pointsurf/simplify/simplify.h"
#include "support/files.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

TEST(FieldTablesClean, EveryMemberOfEveryStageParamsIsDeclared) {
  test::expect_complete<LocalOutlierParams>("LocalOutlierParams");
  test::expect_complete<StatisticalOutlierParams>("StatisticalOutlierParams");
  test::expect_complete<RadiusOutlierParams>("RadiusOutlierParams");
  test::expect_complete<RansacOutlierParams>("RansacOutlierParams");
  test::expect_complete<DuplicateParams>("DuplicateParams");
  test::expect_complete<BilateralParams>("BilateralParams");
  test::expect_complete<TrilateralParams>("TrilateralParams");
  test::expect_complete<SimplifyTarget>("SimplifyTarget");
  test::expect_complete<GridParams>("GridParams");
  test::expect_complete<RandomParams>("RandomParams");
  test::expect_complete<CurvatureSimplifyParams>("CurvatureSimplifyParams");
  test::expect_complete<RegionalParams>("RegionalParams");
  test::expect_complete<CurvatureDistanceParams>("CurvatureDistanceParams");
  test::expect_complete<LfsParams>("LfsParams");
}

// Each method's parameters are its struct's exposed fields, with the struct's defaults (but
// for the target's cell, which random and curvature do not take).
template <class Params>
void expect_declared(const StageSpec& stage, const std::string& method) {
  for (const Field<Params>& f : Params::fields()) {
    const ParamSpec* p = nullptr;
    for (const ParamSpec& s : stage.params)
      if (s.name == f.spec.name && s.applies_to(method)) p = &s;
    if (!f.exposed || (f.spec.name == "cell" && (method == "random" || method == "curvature"))) {
      EXPECT_EQ(p, nullptr) << method << "." << f.spec.name;
      continue;
    }
    ASSERT_NE(p, nullptr) << method << "." << f.spec.name;
    EXPECT_EQ(format_value(p->default_value), format_value(f.get(Params{}))) << method << "." << f.spec.name;
    EXPECT_EQ(p->range_text(), f.spec.range_text()) << method << "." << f.spec.name;
    EXPECT_EQ(p->doc, f.spec.doc) << method << "." << f.spec.name;
  }
}

TEST(FieldTablesClean, StageParametersComeFromTheTables) {
  const StageSpec& clean = *find_stage("clean");
  expect_declared<LocalOutlierParams>(clean, "local");
  expect_declared<StatisticalOutlierParams>(clean, "sor");
  expect_declared<RadiusOutlierParams>(clean, "radius");
  expect_declared<RansacOutlierParams>(clean, "ransac");
  expect_declared<DuplicateParams>(clean, "duplicates");
  expect_declared<BilateralParams>(clean, "bilateral");
  expect_declared<TrilateralParams>(clean, "trilateral");
  const StageSpec& simplify = *find_stage("simplify");
  expect_declared<GridParams>(simplify, "grid");
  expect_declared<RandomParams>(simplify, "random");
  expect_declared<CurvatureSimplifyParams>(simplify, "curvature");
  expect_declared<RegionalParams>(simplify, "regional");
  expect_declared<CurvatureDistanceParams>(simplify, "curvature-distance");
  expect_declared<LfsParams>(simplify, "lfs");
}

class DeprecatedKeys : public ::testing::Test {
protected:
  void SetUp() override {
    dir_ = test::temp_dir(std::string("field_tables_clean_") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    PointCloud sphere = test::sample_sphere(2000, 1.0, Vector3d(2, 0, 1));
    test::add_noise(sphere, 0.005, 7);
    write_point_cloud(path("in.ply"), sphere);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  // Runs the pipeline [in.ply, {"type": STAGE, KEYS}, NAME.ply] with --report NAME.json; the
  // output's bytes and the stage's record.
  std::pair<std::string, nlohmann::json> run(const std::string& stage, const std::string& name, const std::string& keys) {
    test::write_bytes(dir_ / (name + "_pipeline.json"),
                      "[\"" + path("in.ply") + "\", {\"type\": \"" + stage + "\", " + keys + "}, \"" + path(name + ".ply") + "\"]");
    const test::CliResult r = test::run_cli("run " + path(name + "_pipeline.json") + " --quiet --report " + path(name + ".json"), dir_);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    if (r.exit_code != 0) return {};
    const nlohmann::json report = nlohmann::json::parse(test::read_bytes(path(name + ".json")));
    return {test::read_bytes(path(name + ".ply")), report["stages"][1]};
  }
  static bool warns(const nlohmann::json& record, const std::string& text) {
    for (const auto& w : record["warnings"])
      if (w.get<std::string>().find(text) != std::string::npos) return true;
    return false;
  }
  std::filesystem::path dir_;
};

// A former X_in_spacings key is the length X in spacings, with a deprecation warning: the same
// output and recorded parameter as the new key.
TEST_F(DeprecatedKeys, OldInSpacingsKeysAreLengthsInSpacings) {
  struct Case {
    std::string stage, method, old_key, old_value, key, new_value, recorded;
  };
  const std::vector<Case> cases = {
      {"clean", "radius", "radius_in_spacings", "5", "radius", "\"5sp\"", "radius.radius"},
      {"clean", "ransac", "distance_in_spacings", "1.5", "distance", "\"1.5sp\"", "ransac.distance"},
      {"clean", "duplicates", "distance_in_spacings", "0.5", "distance", "\"0.5sp\"", "duplicates.distance"},
      {"clean", "bilateral", "height_sigma_in_spacings", "2", "height_sigma", "\"2sp\"", "bilateral.height_sigma"},
      {"clean", "trilateral", "radius_in_spacings", "4", "radius", "\"4sp\"", "trilateral.radius"},
      {"simplify", "regional", "region_in_spacings", "8", "region_size", "\"8sp\"", "region_size"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.stage + " " + c.method + " " + c.old_key);
    const std::string method = "\"method\": \"" + c.method + "\", ";
    const auto [old_bytes, old_record] = run(c.stage, "old", method + "\"" + c.old_key + "\": " + c.old_value);
    const auto [new_bytes, new_record] = run(c.stage, "new", method + "\"" + c.key + "\": " + c.new_value);
    ASSERT_FALSE(old_bytes.empty());
    EXPECT_EQ(old_bytes, new_bytes);
    EXPECT_TRUE(warns(old_record, "key \"" + c.old_key + "\" is deprecated")) << old_record["warnings"];
    EXPECT_FALSE(warns(new_record, "deprecated")) << new_record["warnings"];
    EXPECT_EQ(old_record["parameters"][c.recorded], new_record["parameters"][c.recorded]);
  }
}

// A length in cloud units gives the same result as the same length in spacings; the report
// holds the length as given and the one used in cloud units.
TEST_F(DeprecatedKeys, LengthsInCloudUnitsOrSpacings) {
  const auto [sp_bytes, sp_record] = run("clean", "sp", "\"method\": \"radius\", \"radius\": \"4sp\"");
  ASSERT_FALSE(sp_bytes.empty());
  EXPECT_EQ(sp_record["parameters"]["radius.radius"], "4sp");
  const double used = sp_record["parameters"]["radius.radius_used"].get<double>();
  const auto [cloud_bytes, cloud_record] = run("clean", "cloud", "\"method\": \"radius\", \"radius\": " + format_value(ParamValue(used)));
  EXPECT_EQ(sp_bytes, cloud_bytes);
  EXPECT_EQ(cloud_record["parameters"]["radius.radius"].get<double>(), used);
  EXPECT_EQ(cloud_record["parameters"]["radius.radius_used"].get<double>(), used);
}

}  // namespace
}  // namespace pointsurf
