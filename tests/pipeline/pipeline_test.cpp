// SPDX-License-Identifier: GPL-3.0-or-later
// Pipelines through the library: checking, --set overrides, the context's tree cache, the
// report's values, intermediate outputs.
#include "pointsurf/pipeline/pipeline.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "pointsurf/core/error.h"
#include "pointsurf/io/io.h"
#include "pointsurf/pipeline/context.h"
#include "pointsurf/pipeline/registry.h"
#include "support/files.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

class PipelineRun : public ::testing::Test {
protected:
  void SetUp() override { dir_ = test::temp_dir(std::string("pipeline_") + ::testing::UnitTest::GetInstance()->current_test_info()->name()); }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::filesystem::path dir_;
};

const StageRecord& record(const RunReport& r, const std::string& tag) {
  for (const StageRecord& s : r.stages)
    if (s.tag == tag) return s;
  ADD_FAILURE() << "no stage " << tag;
  return r.stages.front();
}

ParamValue parameter(const StageRecord& r, const std::string& key) {
  for (const auto& [k, v] : r.parameters)
    if (k == key) return v;
  ADD_FAILURE() << r.type << " has no parameter " << key;
  return {};
}

TEST(Context, CachesTheTreeUntilThePositionsChange) {
  Context ctx;
  ctx.set_cloud("a", test::sample_sphere(500));
  const KdTree* first = &ctx.tree("a");
  const double spacing = ctx.mean_spacing("a");
  EXPECT_EQ(&ctx.tree("a"), first);
  EXPECT_EQ(ctx.mean_spacing("a"), spacing);
  EXPECT_EQ(ctx.tree_builds(), 1u);
  ctx.item("a").cloud().normals.clear();  // attributes do not invalidate
  ctx.tree("a");
  EXPECT_EQ(ctx.tree_builds(), 1u);
  ctx.rename("a", "b");  // a chain passes its cloud on with its tree
  ctx.tree("b");
  EXPECT_EQ(ctx.tree_builds(), 1u);
  ctx.copy("b", "c");  // a copy shares the tree until it changes
  ctx.tree("c");
  EXPECT_EQ(ctx.tree_builds(), 1u);
  ctx.item("c").cloud().positions[7].x() += 1e-3;  // moved: noticed without being told
  ctx.tree("c");
  EXPECT_EQ(ctx.tree_builds(), 2u);
  ctx.tree("b");
  EXPECT_EQ(ctx.tree_builds(), 2u);
  EXPECT_NE(ctx.mean_spacing("c"), 0.0);
  test::expect_error<UsageError>([&] { ctx.item("zz"); }, "no data named \"zz\" (known: b, c)");
}

TEST_F(PipelineRun, FiveStageChainBuildsOneTreePerCloud) {
  PointCloud cube;
  const PointCloud sphere = test::sample_sphere(6000, 1.0, Vector3d(3, 2, 1));
  write_point_cloud(path("sphere.ply"), sphere);
  const std::string json = "[\"" + path("sphere.ply") +
                           "\", {\"type\": \"normals\"}, {\"type\": \"curvature\"}, {\"type\": \"features\"},"
                           " {\"type\": \"simplify\", \"method\": \"regional\", \"ratio\": 0.3}, {\"type\": \"reconstruct\"}, \"" +
                           path("mesh.ply") + "\"]";
  const Pipeline p = parse_pipeline(json, "chain.json");
  Context ctx;
  RunReport report;
  run_pipeline(p, ctx, report);
  ASSERT_TRUE(report.ok);
  // Two clouds: the scan (normals, curvature, features share its tree) and the simplified
  // one (simplify builds it for its distance metrics, reconstruct reuses it).
  EXPECT_EQ(report.tree_builds, 2u);
  EXPECT_EQ(record(report, "normals2").tree_builds, 1u);
  EXPECT_EQ(record(report, "curvature3").tree_builds, 0u);
  EXPECT_EQ(record(report, "features4").tree_builds, 0u);
  EXPECT_EQ(record(report, "simplify5").tree_builds, 1u);
  EXPECT_EQ(record(report, "reconstruct6").tree_builds, 0u);
  const nlohmann::json j = nlohmann::json::parse(report_json(report));
  EXPECT_EQ(j["kdtree_builds"], 2);
  EXPECT_EQ(j["status"], "ok");
  EXPECT_GT(read_mesh(path("mesh.ply")).mesh.triangle_count(), 1000u);
  for (const auto& s : j["stages"]) {
    EXPECT_TRUE(s.contains("seconds") && s.contains("peak_rss_mb") && s.contains("rss_rise_mb")) << s["type"];
    EXPECT_GE(s["rss_rise_mb"].get<double>(), 0.0);
  }
}

TEST_F(PipelineRun, ReportHoldsTheValuesUsedNotPlaceholders) {
  write_point_cloud(path("sphere.ply"), test::sample_sphere(3000));
  const Pipeline p = parse_pipeline("[\"" + path("sphere.ply") +
                                        "\", {\"type\": \"normals\", \"radius\": \"3sp\"}, {\"type\": \"features\"},"
                                        " {\"type\": \"reconstruct\", \"method\": \"ball-pivot\"}, \"" + path("m.ply") + "\"]",
                                    "p.json");
  Context ctx;
  RunReport report;
  run_pipeline(p, ctx, report);
  const StageRecord& normals = record(report, "normals2");
  EXPECT_EQ(std::get<std::string>(parameter(normals, "neighborhood")), "radius");  // inferred from the radius given
  EXPECT_EQ(std::get<Length>(parameter(normals, "radius")), Length::spacings(3));   // as given
  EXPECT_GT(std::get<double>(parameter(normals, "radius_used")), 0.0);                // the radius used, cloud units
  EXPECT_GT(std::get<double>(parameter(record(report, "features3"), "variation_threshold")), 0.0);
  EXPECT_GT(std::get<double>(parameter(record(report, "features3"), "plane_distance_used")), 0.0);
  const auto radii = std::get<std::vector<double>>(parameter(record(report, "reconstruct4"), "radii"));
  EXPECT_EQ(radii.size(), 3u);
  EXPECT_GT(radii.front(), 0.0);
}

// A key of the previous release still works for one release, with a warning, and gives the
// same result as the key that replaced it; a length in a pipeline is a number (cloud units) or
// a text in spacings.
TEST_F(PipelineRun, FormerKeysWorkWithAWarning) {
  write_point_cloud(path("sphere.ply"), test::sample_sphere(2000));
  auto run = [&](const std::string& normals, const std::string& out) {
    const Pipeline p = parse_pipeline("[\"" + path("sphere.ply") + "\", {\"type\": \"normals\", " + normals + "}, \"" + path(out) + "\"]", "p.json");
    Context ctx;
    RunReport report;
    run_pipeline(p, ctx, report);
    return report;
  };
  const RunReport old_key = run("\"radius_in_spacings\": 4", "old.ply");
  const RunReport new_key = run("\"radius\": \"4sp\"", "new.ply");
  ASSERT_EQ(old_key.warnings.size(), 1u);
  EXPECT_NE(old_key.warnings[0].find("key \"radius_in_spacings\" is deprecated: use \"radius\""), std::string::npos) << old_key.warnings[0];
  EXPECT_TRUE(new_key.warnings.empty());
  EXPECT_EQ(std::get<Length>(parameter(record(old_key, "normals2"), "radius")), Length::spacings(4));
  EXPECT_EQ(read_point_cloud(path("old.ply")).cloud.normals, read_point_cloud(path("new.ply")).cloud.normals);
  const RunReport cloud_units = run("\"radius\": 0.2", "cloud.ply");
  EXPECT_EQ(std::get<Length>(parameter(record(cloud_units, "normals2"), "radius")), Length::cloud(0.2));
  EXPECT_DOUBLE_EQ(std::get<double>(parameter(record(cloud_units, "normals2"), "radius_used")), 0.2);
  test::expect_error<UsageError>([&] { run("\"radius\": \"4cm\"", "x.ply"); }, "radius: \"4cm\" is not a length");
}

TEST_F(PipelineRun, SetOverridesByTypeOrTagAndChecksTypes) {
  const std::string json = "[\"in.ply\", {\"type\": \"normals\", \"k\": 20}, {\"type\": \"normals\", \"tag\": \"again\"}, \"out.ply\"]";
  const Pipeline p = parse_pipeline(json, "p.json", {"again.k=12", "normals2.orient=none", "write.ascii=true"});
  EXPECT_EQ(p.steps[1].args.integer("k"), 20);
  EXPECT_EQ(p.steps[1].args.text("orient"), "none");
  EXPECT_EQ(p.steps[2].args.integer("k"), 12);
  EXPECT_TRUE(p.steps[2].args.given("k"));
  EXPECT_TRUE(p.steps[3].args.boolean("ascii"));
  test::expect_error<UsageError>([&] { parse_pipeline(json, "p.json", {"normals.k=12"}); },
                                 "--set \"normals.k=12\": 2 stages have type \"normals\"; name one by its tag: "
                                 "\"normals2.k=12\" or \"again.k=12\"");
  test::expect_error<UsageError>([&] { parse_pipeline(json, "p.json", {"again.k=abc"}); }, "p.json: stage 3 (normals): k: \"abc\" is not an integer");
  test::expect_error<UsageError>([&] { parse_pipeline(json, "p.json", {"again.k=2"}); }, "p.json: stage 3 (normals): k: 2 is out of range [3, inf)");
  test::expect_error<UsageError>([&] { parse_pipeline(json, "p.json", {"agian.k=12"}); }, "no stage tagged or typed \"agian\"; did you mean \"again\"?");
  test::expect_error<UsageError>([&] { parse_pipeline(json, "p.json", {"again.kk=12"}); }, "stage 3 (normals): unknown key \"kk\"; did you mean \"k\"?");
  test::expect_error<UsageError>([&] { parse_pipeline(json, "p.json", {"again"}); }, "expected STAGE.KEY=VALUE");
}

TEST_F(PipelineRun, TwoScansTaggedCroppedMergedAndTransformed) {
  write_point_cloud(path("a.ply"), test::sample_sphere(1000, 1.0));
  write_point_cloud(path("b.ply"), test::sample_sphere(800, 1.0, Vector3d(5, 0, 0)));
  const std::string json = "[{\"type\": \"read\", \"filename\": \"" + path("a.ply") + "\", \"tag\": \"a\"},"
                           " {\"type\": \"read\", \"filename\": \"" + path("b.ply") + "\", \"tag\": \"b\"},"
                           " {\"type\": \"crop\", \"inputs\": \"b\", \"tag\": \"b_top\", \"min\": [-10, -10, 0], \"max\": [10, 10, 10]},"
                           " {\"type\": \"merge\", \"inputs\": [\"a\", \"b_top\"]},"
                           " {\"type\": \"transform\", \"matrix\": [0, -1, 0, 1, 1, 0, 0, 2, 0, 0, 1, 3, 0, 0, 0, 1]},"
                           " {\"type\": \"range\", \"field\": \"z\", \"min\": 2, \"max\": 100}, \"" + path("m.ply") + "\"]";
  Context ctx;
  RunReport report;
  run_pipeline(parse_pipeline(json, "two.json"), ctx, report);
  const PointCloud out = read_point_cloud(path("m.ply")).cloud;
  // z after the transform is z + 3: the range keeps z >= -1 of the merged cloud: all of b's top
  // half, and a's points with z >= -1 (all of them).
  std::size_t b_top = 0;
  for (const Vector3d& p : read_point_cloud(path("b.ply")).cloud.positions) b_top += p.z() >= 0.0;
  EXPECT_EQ(out.size(), 1000u + b_top);
  for (const Vector3d& p : out.positions) EXPECT_GE(p.z(), 2.0);
  EXPECT_EQ(record(report, "merge4").inputs, (std::vector<std::string>{"a", "b_top"}));
}

TEST_F(PipelineRun, AFailureRemovesWhatTheRunWroteAndReportsTheStage) {
  write_point_cloud(path("s.ply"), test::sample_sphere(500));
  const std::string json = "[\"" + path("s.ply") + "\", {\"type\": \"normals\"}, \"" + path("copy.ply") +
                           "\", {\"type\": \"crop\", \"min\": [0.99, 0.99, 0.99], \"max\": [1, 1, 1]}, {\"type\": \"reconstruct\"}, \"" +
                           path("m.ply") + "\"]";
  Context ctx;
  RunReport report;
  const Pipeline p = parse_pipeline(json, "f.json");
  test::expect_error<InputError>([&] { run_pipeline(p, ctx, report); }, "stage 4 (crop): no point is left");
  EXPECT_FALSE(report.ok);
  EXPECT_EQ(report.exit_code, 2);
  EXPECT_FALSE(std::filesystem::exists(path("copy.ply")));  // the intermediate output is gone
  EXPECT_FALSE(std::filesystem::exists(path("m.ply")));
  EXPECT_EQ(nlohmann::json::parse(report_json(report))["status"], "failed");
}

}  // namespace
}  // namespace pointsurf
