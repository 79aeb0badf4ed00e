// SPDX-License-Identifier: GPL-3.0-or-later
// End-to-end tests of `pointsurf evaluate` and `pointsurf quality` and of the evaluate stage in
// a pipeline: the deviation and quality blocks of the report, the cloud written with its
// deviation field, the reference defaulting to the cloud as read, and the error paths.
#include <cmath>
#include <filesystem>
#include <string>

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "pipeline/cli_run.h"
#include "pointsurf/core/fields.h"
#include "pointsurf/core/rigid_transform.h"
#include "pointsurf/evaluate/surface_distance.h"
#include "pointsurf/io/io.h"
#include "support/files.h"
#include "support/mesh_shapes.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

class EvaluateCli : public ::testing::Test {
protected:
  void SetUp() override {
    dir_ = test::temp_dir(std::string("evaluate_cli_") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  nlohmann::json stage(const std::string& report, const std::string& type) const {
    const nlohmann::json json = nlohmann::json::parse(test::read_bytes(dir_ / report));
    for (const nlohmann::json& s : json["stages"])
      if (s["type"] == type) return s;
    return nullptr;
  }
  std::filesystem::path dir_;
};

// A sphere mesh far from the origin and points at +-0.01 from its face centres along the face
// normals (convex: the distance is exactly 0.01).
struct Scene {
  TriangleMesh mesh;
  PointCloud cloud;
};
Scene make_scene() {
  const Vector3d center(1.0e6, 2.0e6, 10.0);
  Scene s{test::icosphere_mesh(2, 1.0, center), {}};
  for (std::size_t t = 0; t < s.mesh.triangles.size(); ++t) {
    const Triangle& f = s.mesh.triangles[t];
    const Vector3d a = s.mesh.vertices.positions[std::size_t(f[0])], b = s.mesh.vertices.positions[std::size_t(f[1])], c = s.mesh.vertices.positions[std::size_t(f[2])];
    const Vector3d n = (b - a).cross(c - a).normalized();
    s.cloud.positions.push_back((a + b + c) / 3.0 + (t % 2 == 0 ? 0.01 : -0.01) * n);
  }
  return s;
}

TEST_F(EvaluateCli, ReportsTheDeviationAndQualityBlocksAndWritesTheDeviationField) {
  Scene s = make_scene();
  // Labels: the points outside are region 0, those inside region 1.
  ScalarField& segment = s.cloud.fields.add("segment", s.cloud.size(), ScalarType::Int32);
  for (std::size_t i = 0; i < s.cloud.size(); ++i) segment.values[i] = static_cast<double>(i % 2);
  write_mesh(path("mesh.ply"), s.mesh);
  write_point_cloud(path("scan.ply"), s.cloud);
  const test::CliResult r = test::run_cli("evaluate " + path("mesh.ply") + " --reference " + path("scan.ply") +
                                              " --tolerance 0.02 --out " + path("dev.ply") + " --report " + path("r.json"),
                                          dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json e = stage("r.json", "evaluate");
  ASSERT_FALSE(e.is_null());
  const nlohmann::json& d = e["metrics"]["deviation"];
  EXPECT_NEAR(d["max_positive"].get<double>(), 0.01, 1e-9);
  EXPECT_NEAR(d["max_negative"].get<double>(), -0.01, 1e-9);
  EXPECT_NEAR(d["mean_positive"].get<double>(), 0.01, 1e-9);
  EXPECT_NEAR(d["mean_negative"].get<double>(), -0.01, 1e-9);
  EXPECT_NEAR(d["rms"].get<double>(), 0.01, 1e-9);
  EXPECT_NEAR(d["std"].get<double>(), 0.01, 1e-9);
  EXPECT_DOUBLE_EQ(d["within_tolerance"].get<double>(), 1.0);
  EXPECT_TRUE(d["percentiles"].contains("p50"));
  EXPECT_EQ(d["histogram"]["edges"].size(), d["histogram"]["counts"].size() + 1);
  EXPECT_EQ(e["metrics"]["sign"], "pseudo-normal");
  const nlohmann::json& regions = e["metrics"]["deviation_by_region"];
  EXPECT_NEAR(regions["segment_0"]["max_positive"].get<double>(), 0.01, 1e-9);
  EXPECT_DOUBLE_EQ(regions["segment_0"]["max_negative"].get<double>(), 0.0);
  EXPECT_NEAR(regions["segment_1"]["max_negative"].get<double>(), -0.01, 1e-9);
  EXPECT_EQ(e["counts"]["regions"], 2);
  const nlohmann::json& q = e["metrics"]["quality"];
  EXPECT_EQ(q["watertight"], true);
  EXPECT_EQ(q["genus"], 0);
  EXPECT_EQ(q["self_intersections"], 0);
  EXPECT_TRUE(q.contains("angles_deg"));
  EXPECT_GT(e["metrics"]["distance"]["hausdorff"].get<double>(), 0.0);
  EXPECT_EQ(e["counts"]["mesh_samples"], 100000);
  EXPECT_EQ(e["parameters"]["tolerance"], 0.02);
  const CloudReadResult out = read_point_cloud(path("dev.ply"));
  const ScalarField* field = out.cloud.fields.find("deviation");
  ASSERT_NE(field, nullptr);
  ASSERT_EQ(field->values.size(), s.cloud.size());
  EXPECT_NEAR(field->values[0], 0.01, 1e-9);
  EXPECT_NEAR(field->values[1], -0.01, 1e-9);

  // quality alone: the same keys.
  const test::CliResult qr = test::run_cli("quality " + path("mesh.ply") + " --report " + path("q.json"), dir_);
  ASSERT_EQ(qr.exit_code, 0) << qr.err;
  const nlohmann::json qs = stage("q.json", "quality");
  for (const auto& [key, value] : q.items()) EXPECT_TRUE(qs["metrics"]["quality"].contains(key)) << key;
  EXPECT_NEAR(qs["metrics"]["quality"]["area"].get<double>(), q["area"].get<double>(), 1e-12);
}

// A torus of major radius 1 and minor r as a u x v grid, outward, closed.
TriangleMesh torus_mesh(double r, int nu, int nv) {
  TriangleMesh m;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double u = 2 * M_PI * i / nu, v = 2 * M_PI * j / nv;
      m.vertices.positions.emplace_back((1 + r * std::cos(v)) * std::cos(u), (1 + r * std::cos(v)) * std::sin(u), r * std::sin(v));
    }
  const auto id = [&](int i, int j) { return ((i + nu) % nu) * nv + (j + nv) % nv; };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      m.triangles.emplace_back(id(i, j), id(i + 1, j), id(i + 1, j + 1));
      m.triangles.emplace_back(id(i, j), id(i + 1, j + 1), id(i, j + 1));
    }
  return m;
}

// Issue 28 item 7: quality counts short handles of any mesh, spacings being its mean edge
// length; a thin ring (meridian 0.31, under 10 edges of about 0.06) is one, a fat one is not.
TEST_F(EvaluateCli, QualityCountsShortHandles) {
  write_mesh(path("thin.ply"), torus_mesh(0.05, 100, 8));
  write_mesh(path("fat.ply"), torus_mesh(0.4, 100, 40));
  test::CliResult r = test::run_cli("quality " + path("thin.ply") + " --report " + path("q.json"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(test::contains(r.err, "1 short handle with a loop at most 10 mean edge lengths")) << r.err;
  nlohmann::json q = stage("q.json", "quality");
  EXPECT_EQ(q["counts"]["short_handles"], 1);
  EXPECT_NEAR(q["metrics"]["shortest_handle_loop"].get<double>(), 2 * M_PI * 0.05, 0.03);
  EXPECT_EQ(q["metrics"]["quality"]["genus"], 1);
  r = test::run_cli("quality " + path("thin.ply") + " --max-handle-loop 2 --report " + path("q.json"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(stage("q.json", "quality")["counts"]["short_handles"], 0);
  r = test::run_cli("quality " + path("fat.ply") + " --report " + path("q.json"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  q = stage("q.json", "quality");
  EXPECT_EQ(q["counts"]["short_handles"], 0);
  EXPECT_EQ(q["metrics"]["shortest_handle_loop"], 0.0);
  EXPECT_FALSE(test::contains(r.err, "short handle")) << r.err;
}

TEST_F(EvaluateCli, BadInputGetsAClearAnswer) {
  const Scene s = make_scene();
  write_mesh(path("mesh.ply"), s.mesh);
  write_point_cloud(path("scan.ply"), s.cloud);
  test::CliResult r = test::run_cli("evaluate " + path("scan.ply") + " --reference " + path("scan.ply"), dir_);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(test::contains(r.err, "has no faces")) << r.err;
  r = test::run_cli("evaluate " + path("mesh.ply"), dir_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(test::contains(r.err, "--reference FILE is required")) << r.err;
  // The same scan in millimetres: far away and a thousand times larger.
  PointCloud mm = s.cloud;
  for (Vector3d& p : mm.positions) p *= 1000.0;
  write_point_cloud(path("mm.ply"), mm);
  r = test::run_cli("evaluate " + path("mesh.ply") + " --reference " + path("mm.ply") + " --out " + path("dev.ply"), dir_);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_TRUE(test::contains(r.err, "another unit or coordinate system")) << r.err;
  EXPECT_FALSE(std::filesystem::exists(path("dev.ply")));
  r = test::run_cli("evaluate " + path("mesh.ply") + " --reference " + path("scan.ply") + " --tolerance -1", dir_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_TRUE(test::contains(r.err, "--tolerance")) << r.err;
}

// A scan of a box moved by a small rigid motion measures the motion without --align and ~0 with
// it; the report gives the transform (the motion's inverse) and the written cloud is moved.
TEST_F(EvaluateCli, AlignMovesTheReferenceOntoTheMeshBeforeMeasuring) {
  const Vector3d center(1.0e6, 2.0e6, 10.0);
  TriangleMesh mesh = test::cube_mesh(1.0, Vector3d::Zero());
  for (Vector3d& v : mesh.vertices.positions) v = center + Vector3d(v.x(), 0.6 * v.y(), 0.3 * v.z());
  PointCloud scan;
  scan.positions = sample_mesh_surface(mesh, 20000, 5);
  const Eigen::Matrix3d rotation = Eigen::AngleAxisd(0.02, Vector3d(0.3, 1.0, -0.4).normalized()).toRotationMatrix();
  const RigidTransform motion = RigidTransform::about(center, rotation, Vector3d(0.01, 0.02, -0.015));
  motion.apply(scan);
  write_mesh(path("mesh.ply"), mesh);
  write_point_cloud(path("scan.ply"), scan);
  const std::string common = "evaluate " + path("mesh.ply") + " --reference " + path("scan.ply");
  test::CliResult r = test::run_cli(common + " --report " + path("plain.json"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = test::run_cli(common + " --align --out " + path("dev.ply") + " --report " + path("fit.json"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json plain = stage("plain.json", "evaluate"), fit = stage("fit.json", "evaluate");
  EXPECT_FALSE(plain["metrics"].contains("align"));
  EXPECT_GT(plain["metrics"]["deviation"]["rms"].get<double>(), 0.01);
  EXPECT_LT(fit["metrics"]["deviation"]["rms"].get<double>(), 1e-4);
  const nlohmann::json& align = fit["metrics"]["align"];
  EXPECT_TRUE(align["converged"].get<bool>());
  EXPECT_NEAR(align["rotation_deg"].get<double>(), 0.02 * 180.0 / std::numbers::pi, 1e-3);
  Eigen::Matrix4d m;
  for (int i = 0; i < 16; ++i) m(i / 4, i % 4) = align["matrix"][static_cast<std::size_t>(i)].get<double>();
  EXPECT_LT(RigidTransform::translation_error(RigidTransform::from_matrix(m), motion.inverse(), center), 1e-4);
  EXPECT_EQ(fit["parameters"]["align_max_distance"].get<std::string>(), "10sp");
  const double used = fit["parameters"]["align_max_distance_used"].get<double>();
  EXPECT_GT(used, 0.0);
  // The same distance given in cloud units fits the same.
  r = test::run_cli(common + " --align --align-max-distance " + format_value(ParamValue(used)) + " --report " + path("fit_cloud.json"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json fit_cloud = stage("fit_cloud.json", "evaluate");
  EXPECT_EQ(fit_cloud["metrics"]["align"]["matrix"], align["matrix"]);
  EXPECT_EQ(fit_cloud["parameters"]["align_max_distance_used"].get<double>(), used);
  const PointCloud written = read_point_cloud(path("dev.ply")).cloud;
  ASSERT_EQ(written.size(), scan.size());
  EXPECT_LT((written.positions[7] - motion.inverse().apply(scan.positions[7])).norm(), 1e-4);
}

TEST_F(EvaluateCli, InAPipelineTheReferenceIsTheCloudAsRead) {
  write_point_cloud(path("sphere.ply"), test::sample_sphere(3000, 1.0, Vector3d(5.0, 0.0, 0.0), 3));
  const std::string json = "[\"" + path("sphere.ply") +
                           "\", {\"type\": \"simplify\", \"method\": \"random\", \"ratio\": 0.5}, {\"type\": \"reconstruct\", \"method\": "
                           "\"ball-pivot\"}, {\"type\": \"evaluate\"}, \"" + path("dev.ply") + "\"]";
  test::write_bytes(dir_ / "p.json", json);
  const test::CliResult r = test::run_cli("run " + path("p.json") + " --report " + path("r.json"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json e = stage("r.json", "evaluate");
  EXPECT_EQ(e["parameters"]["reference"], "read1");
  EXPECT_EQ(e["counts"]["reference_points"], 3000);
  // Half of the points were simplified away: they are measured on their own too.
  EXPECT_GE(e["counts"]["points_not_vertices"].get<int>(), 1400);
  EXPECT_TRUE(e["metrics"]["deviation_not_vertices"].contains("rms"));
  EXPECT_LT(e["metrics"]["deviation"]["rms"].get<double>(), 0.05);
  EXPECT_EQ(read_point_cloud(path("dev.ply")).cloud.size(), 3000u);
  // An unknown reference tag is refused before any work.
  test::write_bytes(dir_ / "bad.json", "[\"" + path("sphere.ply") + "\", {\"type\": \"reconstruct\", \"method\": \"ball-pivot\"}, "
                                      "{\"type\": \"evaluate\", \"reference\": \"raed1\"}]");
  const test::CliResult bad = test::run_cli("run " + path("bad.json"), dir_);
  EXPECT_EQ(bad.exit_code, 1);
  EXPECT_TRUE(test::contains(bad.err, "did you mean \"read1\"")) << bad.err;
}

// A reference mesh is measured by its surface, not its corners: a 2-triangle square 0.01
// above a larger one gives `samples` points, all at +0.01, written out with their deviation.
TEST_F(EvaluateCli, AReferenceMeshIsMeasuredByItsSurfaceSamples) {
  const Vector3d at(7e5, 4e6, 30.0);
  auto square = [&](double half, double z) {
    TriangleMesh m;
    for (const auto& [x, y] : {std::pair{-half, -half}, std::pair{half, -half}, std::pair{half, half}, std::pair{-half, half}})
      m.vertices.positions.push_back(at + Vector3d(x, y, z));
    m.triangles = {Triangle(0, 1, 2), Triangle(0, 2, 3)};  // counter-clockwise from +z
    return m;
  };
  write_mesh(path("mesh.ply"), square(1.0, 0.0));
  write_mesh(path("ref.ply"), square(0.5, 0.01));
  const test::CliResult r = test::run_cli("evaluate " + path("mesh.ply") + " --reference " + path("ref.ply") + " --samples 5000 --out " +
                                              path("dev.ply") + " --report " + path("r.json") + " --quiet",
                                          dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json st = stage("r.json", "evaluate");
  EXPECT_EQ(st["counts"]["reference_points"], 5000);  // not its 4 vertices
  EXPECT_NEAR(st["metrics"]["deviation"]["max_positive"].get<double>(), 0.01, 1e-9);
  EXPECT_NEAR(st["metrics"]["deviation"]["abs_p95"].get<double>(), 0.01, 1e-9);
  EXPECT_NEAR(st["metrics"]["deviation"]["max_negative"].get<double>(), 0.0, 1e-12);
  const PointCloud out = read_point_cloud(path("dev.ply")).cloud;
  ASSERT_EQ(out.size(), 5000u);
  const ScalarField* d = out.fields.find("deviation");
  ASSERT_NE(d, nullptr);
  for (std::size_t i = 0; i < out.size(); ++i) {
    EXPECT_NEAR(d->values[i], 0.01, 1e-9);
    EXPECT_NEAR(out.positions[i].z() - at.z(), 0.01, 1e-9);
    ASSERT_LE((out.positions[i] - at).head<2>().cwiseAbs().maxCoeff(), 0.5 + 1e-9);
  }
  // The way back is exact to the reference's triangles: the mesh's corners lie 0.5 beyond it.
  EXPECT_NEAR(st["metrics"]["distance"]["mesh_to_reference_max"].get<double>(), std::sqrt(0.5 * 0.5 * 2 + 0.01 * 0.01), 0.02);
}

}  // namespace
}  // namespace pointsurf
