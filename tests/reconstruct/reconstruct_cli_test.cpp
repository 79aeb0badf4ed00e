// SPDX-License-Identifier: GPL-3.0-or-later
// End-to-end tests of `pointsurf reconstruct`: the mesh written, the topology in the report,
// normals estimated when absent, and the error paths (exit codes, messages, no output left).
// The command-line tool must be built (target pointsurf_cli) before these run.
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <random>
#include <set>
#include <string>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "pointsurf/core/mesh_topology.h"
#include "pointsurf/io/io.h"
#include "support/files.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

struct RunResult {
  int exit_code = -1;
  std::string err;
};

RunResult run_cli(const std::string& args, const std::filesystem::path& dir) {
  const std::filesystem::path err = dir / "stderr.txt";
  const std::string command = std::string(POINTSURF_CLI_PATH) + " " + args + " >/dev/null 2>" + err.string();
  const int status = std::system(command.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, test::read_bytes(err)};
}

class ReconstructCli : public ::testing::Test {
protected:
  void SetUp() override {
    dir_ = test::temp_dir(std::string("reconstruct_cli_") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  // The report's record of the stage of type `type`, with "figures": its counts and metrics
  // together.
  nlohmann::json stage(const std::string& report, const std::string& type) const {
    const nlohmann::json json = nlohmann::json::parse(test::read_bytes(dir_ / report));
    for (nlohmann::json s : json["stages"])
      if (s["type"] == type) {
        s["figures"] = s["counts"];
        s["figures"].update(s["metrics"]);
        return s;
      }
    return nullptr;
  }
  std::filesystem::path dir_;
};

TEST_F(ReconstructCli, BallPivotWritesAClosedSphereWithNormalsAndReportsItsTopology) {
  const PointCloud sphere = test::sample_sphere(4000, 1.0, Vector3d(10.0, -5.0, 2.0));
  write_point_cloud(path("sphere.ply"), sphere);
  const RunResult r =
      run_cli("reconstruct " + path("sphere.ply") + " " + path("mesh.ply") + " --method ball-pivot --report " + path("run.json"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(test::contains(r.err, "ball-pivot")) << r.err;
  EXPECT_TRUE(test::contains(r.err, "0 holes")) << r.err;
  EXPECT_TRUE(test::contains(r.err, "genus 0")) << r.err;

  const TriangleMesh mesh = read_mesh(path("mesh.ply")).mesh;
  ASSERT_EQ(mesh.vertex_count(), sphere.size());
  ASSERT_EQ(mesh.vertices.normals.size(), sphere.size());  // the input normals are kept
  const MeshTopology t = analyze_topology(mesh);
  EXPECT_TRUE(t.watertight());
  EXPECT_EQ(t.genus(), 0);

  const nlohmann::json bp = stage("run.json", "reconstruct");
  ASSERT_FALSE(bp.is_null());
  EXPECT_EQ(bp["parameters"]["method"], "ball-pivot");
  const nlohmann::json& m = bp["figures"];
  EXPECT_EQ(m["holes"], 0);
  EXPECT_EQ(m["holes_total_perimeter"], 0.0);
  EXPECT_EQ(m["non_manifold_edges"], 0);
  EXPECT_EQ(m["components"], 1);
  EXPECT_EQ(m["genus"], 0);
  EXPECT_EQ(m["triangles"], mesh.triangle_count());
  // Default radii: 1.5, 3 and 6 mean spacings, reported in cloud units as the radii used.
  const double spacing = m["mean_spacing"].get<double>();
  ASSERT_EQ(bp["parameters"]["radii"].size(), 3u);
  EXPECT_NEAR(bp["parameters"]["radii"][0].get<double>(), 1.5 * spacing, 1e-12);
  EXPECT_NEAR(bp["parameters"]["radii"][2].get<double>(), 6.0 * spacing, 1e-12);
  EXPECT_FALSE(m["normals_estimated"].get<bool>());  // the input had normals
}

TEST_F(ReconstructCli, EstimatesMissingNormalsAndSaysSo) {
  PointCloud torus = test::sample_torus(6000, 1.0, 0.35);
  torus.normals.clear();
  write_point_cloud(path("torus.xyz"), torus);
  const RunResult r = run_cli("reconstruct " + path("torus.xyz") + " " + path("mesh.ply") + " --method ball-pivot --report " +
                                  path("run.json"),
                              dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(test::contains(r.err, "no normals in the input; estimated")) << r.err;
  EXPECT_TRUE(test::contains(r.err, "(normals estimated)")) << r.err;
  EXPECT_TRUE(stage("run.json", "reconstruct")["figures"]["normals_estimated"].get<bool>());
  const TriangleMesh mesh = read_mesh(path("mesh.ply")).mesh;
  EXPECT_EQ(mesh.vertices.normals.size(), torus.size());
  const MeshTopology t = analyze_topology(mesh);
  EXPECT_TRUE(t.edge_manifold());
  EXPECT_EQ(t.components, 1u);
  EXPECT_EQ(stage("run.json", "reconstruct")["figures"]["non_manifold_edges"], 0);
}

TEST_F(ReconstructCli, ExplicitRadiiAreInCloudUnits) {
  const PointCloud sphere = test::sample_sphere(2000, 1.0);
  write_point_cloud(path("sphere.ply"), sphere);
  const RunResult r = run_cli("reconstruct " + path("sphere.ply") + " " + path("mesh.off") + " --method ball-pivot --radii 0.2,0.1 --report " +
                                  path("run.json"),
                              dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json bp = stage("run.json", "reconstruct");
  EXPECT_EQ(bp["parameters"]["radii"], nlohmann::json::parse("[0.1, 0.2]"));
  EXPECT_GT(read_mesh(path("mesh.off")).mesh.triangle_count(), 0u);
}

// Keys of the previous release still work in a pipeline (radius_in_spacings: the radius in
// spacings; confidence: weight_by_normal_length), with a warning: the same mesh.
TEST_F(ReconstructCli, FormerKeysGiveTheSameMeshWithAWarning) {
  const PointCloud sphere = test::sample_sphere(2000, 1.0);
  write_point_cloud(path("sphere.ply"), sphere);
  const auto run = [&](const std::string& name, const std::string& step) {
    test::write_bytes(path(name + "_pipeline.json"), "[\"" + path("sphere.ply") + "\", " + step + ", \"" + path(name + ".ply") + "\"]");
    const RunResult r = run_cli("run " + path(name + "_pipeline.json") + " --report " + path(name + ".json"), dir_);
    EXPECT_EQ(r.exit_code, 0) << step << ": " << r.err;
    return test::read_bytes(dir_ / (name + ".json"));
  };
  const auto same_mesh = [&](const std::string& a, const std::string& b) {
    const std::string x = test::read_bytes(dir_ / (a + ".ply")), y = test::read_bytes(dir_ / (b + ".ply"));
    return !x.empty() && x == y;
  };
  run("new", R"({"type": "reconstruct", "radius": "4sp"})");
  const std::string old_key = run("old", R"({"type": "reconstruct", "radius_in_spacings": 4})");
  EXPECT_TRUE(same_mesh("new", "old"));
  EXPECT_EQ(stage("new.json", "reconstruct")["parameters"]["radius"], "4sp");
  EXPECT_TRUE(test::contains(old_key, R"(key \"radius_in_spacings\" is deprecated)")) << old_key;
  run("new2", R"({"type": "reconstruct", "method": "poisson", "depth": 5, "weight_by_normal_length": true})");
  const std::string old2 = run("old2", R"({"type": "reconstruct", "method": "poisson", "depth": 5, "confidence": true})");
  EXPECT_TRUE(same_mesh("new2", "old2"));
  EXPECT_TRUE(test::contains(old2, R"(key \"confidence\" is deprecated)")) << old2;
}

TEST_F(ReconstructCli, EveryMethodRunsThroughTheSameCommandAndReportsTheSameCounts) {
  PointCloud sphere = test::sample_sphere(2000, 1.0);
  sphere.positions.push_back(sphere.positions[7]);  // one exact duplicate
  sphere.normals.push_back(sphere.normals[7]);
  write_point_cloud(path("sphere.ply"), sphere);
  for (const std::string method : {"triangulate", "cocone", "crust", "ball-pivot"}) {
    const RunResult r = run_cli("reconstruct " + path("sphere.ply") + " " + path(method + ".ply") + " --method " + method +
                                    " --report " + path(method + ".json"),
                                dir_);
    ASSERT_EQ(r.exit_code, 0) << method << ": " << r.err;
    EXPECT_TRUE(test::contains(r.err, method + " ")) << r.err;
    const std::size_t faces = read_mesh(path(method + ".ply")).mesh.triangle_count();
    EXPECT_GT(faces, 0u) << method;
    const nlohmann::json f = stage(method + ".json", "reconstruct")["figures"];
    for (const char* key : {"candidate_triangles", "holes_filled", "fill_triangles", "duplicate_points", "method_seconds",
                            "noise_in_spacings", "holes", "border_loops", "regions", "components_removed"})
      EXPECT_TRUE(f.contains(key)) << method << " lacks " << key;
    EXPECT_EQ(f["duplicate_points"], 1) << method;
    EXPECT_GT(f["candidate_triangles"].get<std::size_t>(), faces / 2) << method;
    EXPECT_GT(f["method_seconds"].get<double>(), 0.0) << method;
  }
}

// A sphere and, far from it, a small flat patch: the patch is a separate component that
// min_component_share removes, and each face of the mesh carries its flat region.
TEST_F(ReconstructCli, RemovesSmallComponentsAndLabelsFlatRegions) {
  PointCloud cloud = test::sample_sphere(3000, 1.0);
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) {
      cloud.positions.emplace_back(5.0 + 0.03 * i + 0.004 * j, 5.0 + 0.03 * j, 5.0);
      cloud.normals.emplace_back(0.0, 0.0, 1.0);
    }
  write_point_cloud(path("cloud.ply"), cloud);
  const std::string base = "reconstruct " + path("cloud.ply") + " --method ball-pivot ";
  RunResult r = run_cli(base + path("all.ply") + " --min-component-share 0 --report " + path("all.json"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json all = stage("all.json", "reconstruct")["figures"];
  ASSERT_GE(all["components"].get<int>(), 2) << "the patch must be triangulated for this test";
  EXPECT_EQ(all["components_removed"], 0);
  EXPECT_EQ(all["faces_removed"], 0);

  r = run_cli(base + path("mesh.ply") + " --min-component-share 0.01 --report " + path("run.json"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json rec = stage("run.json", "reconstruct");
  const nlohmann::json& m = rec["figures"];
  EXPECT_EQ(rec["parameters"]["min_component_share"], 0.01);
  EXPECT_EQ(m["components"], 1);
  EXPECT_EQ(m["components_removed"].get<int>(), all["components"].get<int>() - 1);
  EXPECT_EQ(m["faces_removed"].get<int>(), all["triangles"].get<int>() - m["triangles"].get<int>());
  EXPECT_EQ(m["unused_points"].get<int>(), all["unused_points"].get<int>() + 16);  // the patch's points
  const TriangleMesh mesh = read_mesh(path("mesh.ply")).mesh;
  EXPECT_EQ(mesh.vertex_count(), cloud.size());  // the points stay, as vertices
  EXPECT_EQ(mesh.triangle_count(), m["triangles"].get<std::size_t>());
  const ScalarField* region = mesh.face_fields.find("region");
  ASSERT_NE(region, nullptr);
  EXPECT_EQ(region->type, ScalarType::Int32);
  std::set<double> labels(region->values.begin(), region->values.end());
  EXPECT_EQ(labels.size(), m["regions"].get<std::size_t>());
  EXPECT_EQ(*labels.begin(), 0.0);
  EXPECT_EQ(*labels.rbegin(), static_cast<double>(labels.size() - 1));
  EXPECT_GE(labels.size(), 15u);  // caps of at most 30 degrees (region_seed_angle_deg)
  EXPECT_GT(m["largest_region_faces"].get<int>(), 0);

  // OBJ has no face properties: the write says what it drops.
  r = run_cli(base + path("mesh.obj"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(test::contains(r.err, "cannot hold: face field 'region'")) << r.err;
  r = run_cli(base + path("bad.ply") + " --region-seed-angle-deg 0", dir_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(test::contains(r.err, "--region-seed-angle-deg: 0 is out of range (0, 180]")) << r.err;
}

// An open patch whose middle (a disc) has points the region growing cannot use (zero normals):
// the mesh has a wide hole there although the cloud has none. The outer rim is reported as a
// border loop, the hole (wider than the hole filler's limit) as a hole, and only the hole is
// warned about. (Where the cloud itself has a gap, its rim is a border of the scan.)
TEST_F(ReconstructCli, TellsTheBorderOfTheScanFromAHole) {
  PointCloud patch;
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> jitter(-0.15, 0.15);
  for (int j = 0; j < 40; ++j)
    for (int i = 0; i < 40; ++i) {
      const Vector3d x(i + jitter(rng), j + jitter(rng), 0.0);
      const bool in_disc = (x - Vector3d(20, 20, 0)).norm() < 6.0;  // perimeter ~38 spacings, above the default 20
      patch.positions.push_back(x + Vector3d(6e5, 5e6, 30.0));
      patch.normals.push_back(in_disc ? Vector3d::Zero() : Vector3d(0.0, 0.0, 1.0));
    }
  write_point_cloud(path("patch.ply"), patch);
  const RunResult r = run_cli("reconstruct " + path("patch.ply") + " " + path("mesh.ply") + " --report " + path("run.json"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json f = stage("run.json", "reconstruct")["figures"];
  EXPECT_EQ(f["holes"], 1) << f.dump();
  EXPECT_EQ(f["border_loops"], 1) << f.dump();
  EXPECT_NEAR(f["largest_hole_perimeter"].get<double>(), 2.0 * 3.14159265358979 * 6.0, 8.0);
  EXPECT_GT(f["border_perimeter"].get<double>(), 4.0 * 39.0 - 8.0);  // the jittered rim zigzags: longer
  EXPECT_LT(f["border_perimeter"].get<double>(), 1.5 * 4.0 * 39.0);
  EXPECT_TRUE(test::contains(r.err, "1 hole remains")) << r.err;
  EXPECT_TRUE(test::contains(r.err, "1 boundary loop along the border of the scan")) << r.err;
  EXPECT_FALSE(test::contains(r.err, "noisy")) << r.err;
}

// Noise of about one spacing: the stage says so and what to do.
TEST_F(ReconstructCli, WarnsWhenThePointsAreTooNoisyForAnInterpolatingSurface) {
  PointCloud sphere = test::sample_sphere(6000, 1.0, Vector3d::Zero(), 8);
  std::mt19937_64 rng(5);
  std::normal_distribution<double> g(0.0, 0.04);  // 1.2 mean spacings of 0.032
  for (Vector3d& x : sphere.positions) x *= 1.0 + g(rng);
  sphere.normals.clear();
  write_point_cloud(path("noisy.xyz"), sphere);
  const RunResult r = run_cli("reconstruct " + path("noisy.xyz") + " " + path("mesh.ply") + " --method cocone --report " + path("run.json"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(test::contains(r.err, "the points are noisy")) << r.err;
  EXPECT_TRUE(test::contains(r.err, "pointsurf clean --method bilateral")) << r.err;
  EXPECT_GT(stage("run.json", "reconstruct")["figures"]["noise_in_spacings"].get<double>(), 0.4);
}

TEST_F(ReconstructCli, PoissonWritesAWatertightSphereWithDensityAndReportsTheOctree) {
  PointCloud sphere = test::sample_sphere(6000, 1.0, Vector3d(10.0, -5.0, 2.0));
  sphere.normals[3] = Vector3d::Zero();
  write_point_cloud(path("sphere.ply"), sphere);
  const RunResult r = run_cli("reconstruct " + path("sphere.ply") + " " + path("mesh.ply") + " --method poisson --depth 6 --report " +
                                  path("run.json"),
                              dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(test::contains(r.err, "poisson")) << r.err;
  EXPECT_TRUE(test::contains(r.err, "genus 0")) << r.err;
  EXPECT_TRUE(test::contains(r.err, "1 point skipped: zero or non-finite normal")) << r.err;
  const MeshReadResult mesh = read_mesh(path("mesh.ply"));
  const MeshTopology t = analyze_topology(mesh.mesh);
  EXPECT_TRUE(t.watertight());
  EXPECT_EQ(t.genus(), 0);
  EXPECT_EQ(mesh.mesh.vertices.normals.size(), mesh.mesh.vertex_count());
  EXPECT_TRUE(mesh.mesh.vertices.fields.contains("density"));
  for (const Vector3d& v : mesh.mesh.vertices.positions) EXPECT_NEAR((v - Vector3d(10.0, -5.0, 2.0)).norm(), 1.0, 0.02);
  const nlohmann::json s = stage("run.json", "reconstruct");
  ASSERT_FALSE(s.is_null());
  EXPECT_EQ(s["parameters"]["method"], "poisson");
  EXPECT_EQ(s["parameters"]["depth"], 6);
  EXPECT_EQ(s["figures"]["skipped_normals"], 1);
  EXPECT_EQ(s["figures"]["nodes_per_level"].size(), 6u);
  EXPECT_EQ(s["figures"]["watertight"], true);
  EXPECT_GT(s["figures"]["peak_megabytes"].get<double>(), 0.0);
  // bad option values are usage errors
  EXPECT_EQ(run_cli("reconstruct " + path("sphere.ply") + " " + path("bad.ply") + " --method poisson --point-weight -1", dir_).exit_code, 1);
  EXPECT_FALSE(std::filesystem::exists(dir_ / "bad.ply"));
}

// Issue 28 item 7: real handles (a torus, the kitten's tail) stay; a handle counts as short
// only below max_handle_loop cloud spacings, and is then cut, or only counted.
TEST_F(ReconstructCli, PoissonKeepsRealHandlesAndCutsThemOnlyBelowTheLimit) {
  const PointCloud torus = test::sample_torus(20000, 1.0, 0.3, 7);  // meridian 1.88, about 80 spacings
  write_point_cloud(path("torus.ply"), torus);
  const std::string base = "reconstruct " + path("torus.ply") + " " + path("mesh.ply") + " --method poisson --depth 7 --report " + path("run.json");
  RunResult r = run_cli(base, dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  nlohmann::json s = stage("run.json", "reconstruct");
  EXPECT_EQ(s["figures"]["handles_before"], 1);
  EXPECT_EQ(s["figures"]["short_handles"], 0);
  EXPECT_EQ(s["figures"]["handles_removed"], 0);
  EXPECT_EQ(s["figures"]["genus"], 1);
  EXPECT_EQ(s["figures"]["handles"], 1);
  EXPECT_NEAR(s["figures"]["max_handle_loop_length"].get<double>(), 10.0 * s["figures"]["mean_spacing"].get<double>(), 1e-12);
  EXPECT_EQ(analyze_topology(read_mesh(path("mesh.ply")).mesh).genus(), 1);

  // Counted, not cut, when asked: a warning names them.
  r = run_cli(base + " --max-handle-loop 200 --no-remove-handles", dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(test::contains(r.err, "1 short handle with a loop at most 200 spacings")) << r.err;
  s = stage("run.json", "reconstruct");
  EXPECT_EQ(s["figures"]["short_handles"], 1);
  EXPECT_EQ(s["figures"]["handles_removed"], 0);
  EXPECT_EQ(s["figures"]["genus"], 1);

  // Above the meridian's length the torus is cut and closed: a watertight genus-0 mesh.
  r = run_cli(base + " --max-handle-loop 200", dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(test::contains(r.err, "1 short handle cut")) << r.err;
  s = stage("run.json", "reconstruct");
  EXPECT_EQ(s["figures"]["handles_removed"], 1);
  EXPECT_GT(s["figures"]["shortest_handle_loop"].get<double>(), 1.8);
  EXPECT_LT(s["figures"]["shortest_handle_loop"].get<double>(), 2.2);
  const MeshTopology t = analyze_topology(read_mesh(path("mesh.ply")).mesh);
  EXPECT_TRUE(t.watertight());
  EXPECT_EQ(t.genus(), 0);

  // The kitten keeps its tail.
  r = run_cli("reconstruct " + test::data_path("kitten.xyz").string() + " " + path("kitten.ply") + " --method poisson --report " + path("run.json"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  s = stage("run.json", "reconstruct");
  EXPECT_EQ(s["figures"]["genus"], 1);
  EXPECT_EQ(s["figures"]["handles_removed"], 0);
}

TEST_F(ReconstructCli, BadInputAndOptionsFailClearlyAndLeaveNoOutput) {
  test::write_bytes(dir_ / "two.xyz", "0 0 0 0 0 1\n1 0 0 0 0 1\n");
  RunResult r = run_cli("reconstruct " + path("two.xyz") + " " + path("out.ply") + " --method ball-pivot", dir_);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(test::contains(r.err, "2 points; a surface needs at least 3")) << r.err;

  PointCloud line;
  for (int i = 0; i < 20; ++i) {
    line.positions.emplace_back(0.1 * i, 0.0, 0.0);
    line.normals.emplace_back(0.0, 0.0, 1.0);
  }
  write_point_cloud(path("line.ply"), line);
  r = run_cli("reconstruct " + path("line.ply") + " " + path("out.ply") + " --method ball-pivot", dir_);
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_TRUE(test::contains(r.err, "no triangle could be formed from 20 points")) << r.err;

  write_point_cloud(path("sphere.ply"), test::sample_sphere(500, 1.0));
  r = run_cli("reconstruct " + path("sphere.ply") + " " + path("out.ply") + " --method rbf", dir_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(test::contains(r.err, "--method: \"rbf\" is not one of triangulate, cocone, crust, ball-pivot or poisson")) << r.err;
  r = run_cli("reconstruct " + path("sphere.ply") + " " + path("out.ply") + " --method ball-pivot --radii 0.1,abc", dir_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(test::contains(r.err, "--radii: \"0.1,abc\": \"abc\" is not a number")) << r.err;
  r = run_cli("reconstruct " + path("sphere.ply") + " " + path("out.ply") + " --method ball-pivot --max-normal-angle-deg 0", dir_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(test::contains(r.err, "--max-normal-angle-deg: 0 is out of range (0, 180]")) << r.err;
  // A parameter of another method is an error naming both, not silently ignored.
  r = run_cli("reconstruct " + path("sphere.ply") + " " + path("out.ply") + " --method triangulate --radii 0.1", dir_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(test::contains(r.err, "--radii belongs to method ball-pivot, not to method triangulate")) << r.err;
  r = run_cli("reconstruct " + path("sphere.ply") + " " + path("out.xyzw") + " --method ball-pivot", dir_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_FALSE(std::filesystem::exists(dir_ / "out.ply"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "out.xyzw"));
}

}  // namespace
}  // namespace pointsurf
