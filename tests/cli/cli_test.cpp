// SPDX-License-Identifier: GPL-3.0-or-later
// End-to-end tests of the pointsurf command line: exit codes, messages, reports, outputs.
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "pointsurf/io/io.h"
#include "support/cli_run.h"
#include "support/files.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

using test::RunResult;
RunResult run(const std::string& args, const std::filesystem::path& dir) { return test::run_cli(args, dir); }

class Cli : public ::testing::Test {
protected:
  void SetUp() override { dir_ = test::temp_dir(::testing::UnitTest::GetInstance()->current_test_info()->name()); }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::filesystem::path dir_;
};

TEST_F(Cli, HelpListsCommandsAndExitsZero) {
  const RunResult r = run("--help", dir_);
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.out.find("normals"), std::string::npos);
  EXPECT_NE(r.out.find("convert"), std::string::npos);
  EXPECT_NE(r.out.find("Exit codes"), std::string::npos);
}

TEST_F(Cli, UsageErrorsExitOne) {
  EXPECT_EQ(run("", dir_).exit_code, 1);
  EXPECT_EQ(run("info", dir_).exit_code, 1);
  EXPECT_EQ(run("info x.ply --no-such-option", dir_).exit_code, 1);
  const std::string kitten = test::data_path("kitten.xyz").string();
  RunResult r = run("normals " + kitten + " " + path("o.ply") + " --k 2", dir_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--k: 2 is out of range [3, inf)"), std::string::npos) << r.err;
  r = run("normals " + kitten + " " + path("o.ply") + " --orient sideways", dir_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("sideways"), std::string::npos) << r.err;
  r = run("normals " + kitten + " " + path("o.ply") + " --orient viewpoint --viewpoint 1,2", dir_);
  EXPECT_EQ(r.exit_code, 1);
  r = run("convert " + kitten + " " + path("o.unknown"), dir_);
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("unknown output format"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(path("o.ply")));
}

TEST_F(Cli, BadInputExitsTwoAndNamesTheFile) {
  RunResult r = run("info " + path("missing.ply"), dir_);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("missing.ply"), std::string::npos) << r.err;
  {
    std::ofstream f(path("broken.ply"));
    f << "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n1 1\n";
  }
  r = run("normals " + path("broken.ply") + " " + path("out.ply"), dir_);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("broken.ply"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(path("out.ply")));
  { std::ofstream f(path("empty.xyz")); }
  r = run("info " + path("empty.xyz"), dir_);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("empty"), std::string::npos) << r.err;
}

TEST_F(Cli, InfoJsonDescribesTheGeoreferencedTile) {
  const RunResult r = run("info " + test::data_path("b9_training.ply").string() + " --json --report " + path("r.json"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json info = nlohmann::json::parse(r.out);
  EXPECT_EQ(info["format"], "ply");
  EXPECT_EQ(info["points"], 22300);
  EXPECT_TRUE(info["colors"].get<bool>());
  EXPECT_GT(info["bbox_min"][0].get<double>(), 5.9e5);
  EXPECT_GT(info["mean_spacing"].get<double>(), 0.0);
  bool has_label = false;
  for (const auto& f : info["fields"]) has_label |= f["name"] == "label";
  EXPECT_TRUE(has_label);
  const nlohmann::json report = nlohmann::json::parse(test::read_bytes(path("r.json")));
  for (const char* key : {"command", "version", "status", "outputs", "stages", "total_seconds", "peak_rss_mb", "warnings"})
    EXPECT_TRUE(report.contains(key)) << key;
}

TEST_F(Cli, NormalsAgreeWithTheScansOwnNormals) {
  const RunResult r = run("normals " + test::data_path("kitten.xyz").string() + " " + path("kitten.ply") + " --orient mst --report " +
                              path("r.json") + " --quiet",
                          dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(r.err.empty()) << r.err;
  const nlohmann::json report = nlohmann::json::parse(test::read_bytes(path("r.json")));
  EXPECT_EQ(report["command"], "normals");
  EXPECT_EQ(report["status"], "ok");
  bool found = false;
  for (const auto& stage : report["stages"]) {
    if (!stage["metrics"].contains("orientation_agreement_with_input")) continue;
    found = true;
    // kitten.xyz carries outward normals: MST orientation must agree almost everywhere.
    EXPECT_GT(stage["metrics"]["orientation_agreement_with_input"].get<double>(), 0.98);
    EXPECT_LT(stage["metrics"]["mean_angle_to_input_deg"].get<double>(), 10.0);
  }
  EXPECT_TRUE(found);
  const CloudReadResult out = read_point_cloud(path("kitten.ply"));
  EXPECT_EQ(out.cloud.size(), 5210u);
  EXPECT_TRUE(out.cloud.has_normals());
  EXPECT_TRUE(out.cloud.fields.contains("variation"));
}

// Runs `args`, expecting exit code `code` and `message` on stderr.
void expect_failure(const std::string& args, const std::filesystem::path& dir, int code, const std::string& message) {
  const RunResult r = run(args, dir);
  EXPECT_EQ(r.exit_code, code) << args;
  EXPECT_TRUE(test::contains(r.err, message)) << args << ": " << r.err;
}

// The report's first stage that has metric `key`.
nlohmann::json stage_with(const nlohmann::json& report, const std::string& key) {
  for (const auto& stage : report["stages"])
    if (stage["metrics"].contains(key) || stage["counts"].contains(key)) return stage;
  return {};
}

TEST_F(Cli, NormalsTakeTheInputsSidesAndWarnWhenAnotherOrientationDisagrees) {
  // A sphere whose file carries inward normals (a choice MST would not make): by default the
  // new normals keep the input's side everywhere; --orient mst turns them outward and warns.
  PointCloud sphere = test::sample_sphere(3000);
  for (Vector3d& n : sphere.normals) n = -n;
  write_point_cloud(path("inward.ply"), sphere);
  RunResult r = run("normals " + path("inward.ply") + " " + path("o.ply") + " --report " + path("r.json"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(test::contains(r.out + r.err, "oriented to the input's normals")) << r.out << r.err;
  nlohmann::json report = nlohmann::json::parse(test::read_bytes(path("r.json")));
  nlohmann::json stage = stage_with(report, "orientation_agreement_with_input");
  ASSERT_FALSE(stage.is_null());
  EXPECT_EQ(stage["metrics"]["orientation_agreement_with_input"].get<double>(), 1.0);
  EXPECT_EQ(stage["parameters"]["orient"], "input");
  EXPECT_TRUE(stage["warnings"].empty()) << stage["warnings"];

  r = run("normals " + path("inward.ply") + " " + path("o.ply") + " --orient mst --report " + path("r.json"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(test::contains(r.err, "the new orientation (mst) disagrees with the input's normals on 100.0 % of 3000 points")) << r.err;
  report = nlohmann::json::parse(test::read_bytes(path("r.json")));
  EXPECT_LT(stage_with(report, "orientation_agreement_with_input")["metrics"]["orientation_agreement_with_input"].get<double>(), 0.01);

  // keep: the input's normals unchanged, no estimation.
  r = run("normals " + path("inward.ply") + " " + path("kept.ply") + " --orient keep", dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const PointCloud kept = read_point_cloud(path("kept.ply")).cloud;
  ASSERT_EQ(kept.normals.size(), sphere.normals.size());
  for (std::size_t i = 0; i < kept.size(); ++i) EXPECT_EQ(kept.normals[i], sphere.normals[i]) << i;
  expect_failure("normals " + path("inward.ply") + " " + path("kept.ply") + " --orient keep --k 12", dir_, 1,
                 "k: ignored with orient keep (no estimation)");

  // input and keep need normals in the input.
  sphere.normals.clear();
  write_point_cloud(path("bare.ply"), sphere);
  expect_failure("normals " + path("bare.ply") + " " + path("o.ply") + " --orient keep", dir_, 1,
                 "orient keep: the input has no normals to keep (use mst, viewpoint or direction)");
  expect_failure("normals " + path("bare.ply") + " " + path("o.ply") + " --orient input", dir_, 1,
                 "orient input: the input has no normals to agree with");
}

TEST_F(Cli, CtrlCStopsTheStageLeavesNoOutputAndReportsCancelled) {
  // Screened Poisson of 200,000 sphere samples takes seconds: SIGINT arrives while it runs.
  write_point_cloud(path("sphere.ply"), test::sample_sphere(200000, 1.0, Vector3d::Zero(), 3));
  const test::InterruptedRun run = test::run_cli_interrupted(
      "reconstruct " + path("sphere.ply") + " " + path("mesh.ply") + " --method poisson --report " + path("r.json"), dir_, "[1/3]");
  ASSERT_TRUE(run.interrupted) << "the run ended before SIGINT: " << run.result.err;
  EXPECT_EQ(run.result.exit_code, 130) << run.result.err;
  EXPECT_TRUE(test::contains(run.result.err, "cancelled")) << run.result.err;
  const nlohmann::json report = nlohmann::json::parse(test::read_bytes(path("r.json")));
  EXPECT_EQ(report["status"], "cancelled");
  EXPECT_EQ(report["error"]["kind"], "cancelled");
  EXPECT_EQ(report["error"]["exit_code"], 130);
  for (const auto& entry : std::filesystem::directory_iterator(dir_))  // neither the mesh nor its temporary file
    EXPECT_FALSE(test::contains(entry.path().filename().string(), "mesh.ply")) << entry.path();
}

TEST_F(Cli, TooFewNeighboursIsAWarningWithTheShareAndAllPointsAnError) {
  // 2000 points on a unit square (spacing about 0.02) and 20 isolated points 1 apart, far away:
  // within radius 0.1 the square's points have neighbours, the isolated ones none.
  PointCloud cloud = test::sample_plane(2000, 0.5);
  cloud.normals.clear();
  for (int i = 0; i < 20; ++i) cloud.positions.emplace_back(10.0 + i, 10.0, 10.0);
  write_point_cloud(path("plane.ply"), cloud);
  RunResult r = run("normals " + path("plane.ply") + " " + path("o.ply") + " --radius 0.1", dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(test::contains(r.out + r.err, "(radius 0.1)")) << r.out << r.err;
  EXPECT_TRUE(test::contains(r.err, "20 points have (0.99 %) fewer than 3 neighbours within 0.1")) << r.err;

  // A valid radius that finds no neighbourhood is a failure of the computation (exit 3).
  expect_failure("normals " + path("plane.ply") + " " + path("o.ply") + " --radius 0.001", dir_, 3,
                 "radius: every one of the 2020 points has fewer than 3 neighbours within 0.001");
  // So is a radius outlier test that would remove every point (not an empty file and exit 0).
  expect_failure("clean " + path("plane.ply") + " " + path("none.ply") + " --method radius --radius 1e-9", dir_, 3,
                 "radius: every one of the 2020 points has fewer than 4 others within 1e-09");
  EXPECT_FALSE(std::filesystem::exists(path("none.ply")));

  // Later stages refuse all-zero normals and say what they skip when only some are zero.
  cloud.normals.assign(cloud.size(), Vector3d::Zero());
  write_point_cloud(path("zero.ply"), cloud);
  for (const char* stage : {"curvature", "clean --method bilateral", "clean --method trilateral", "features --normals input"})
    expect_failure(std::string(stage) + " " + path("zero.ply") + " " + path("z.ply"), dir_, 2, "all 2020 normals of the input are (0,0,0) or not finite");
  for (std::size_t i = 0; i < 2000; ++i) cloud.normals[i] = Vector3d::UnitZ();
  write_point_cloud(path("some.ply"), cloud);
  r = run("clean " + path("some.ply") + " " + path("s.ply") + " --method bilateral", dir_);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(test::contains(r.err, "20 points have (0.99 %) a zero or non-finite normal in the input: not moved")) << r.err;
}

TEST_F(Cli, ConvertKeepsGeoreferencedPrecisionThroughLasAndPly) {
  const std::string b9 = test::data_path("b9_training.ply").string();
  ASSERT_EQ(run("convert " + b9 + " " + path("b9.las") + " --quiet", dir_).exit_code, 0);
  ASSERT_EQ(run("convert " + path("b9.las") + " " + path("b9.ply") + " --quiet", dir_).exit_code, 0);
  const PointCloud a = read_point_cloud(b9).cloud;
  const PointCloud b = read_point_cloud(path("b9.ply")).cloud;
  ASSERT_EQ(a.size(), b.size());
  double worst = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) worst = std::max(worst, (a.positions[i] - b.positions[i]).cwiseAbs().maxCoeff());
  EXPECT_LT(worst, 1e-4);
  ASSERT_TRUE(b.has_colors());
  EXPECT_NEAR(a.colors[100].x(), b.colors[100].x(), 1e-3);
}

TEST_F(Cli, ConvertCarriesFacesAndWarnsWhereTheFormatCannotHoldThem) {
  TriangleMesh mesh;
  mesh.vertices.positions = {Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0), Vector3d(0, 0, 1)};
  mesh.triangles = {Triangle(0, 2, 1), Triangle(0, 1, 3), Triangle(0, 3, 2), Triangle(1, 2, 3)};
  write_mesh(path("tet.off"), mesh);
  ASSERT_EQ(run("convert " + path("tet.off") + " " + path("tet.ply") + " --quiet", dir_).exit_code, 0);
  EXPECT_EQ(read_mesh(path("tet.ply")).mesh.triangles, mesh.triangles);
  const RunResult r = run("convert " + path("tet.ply") + " " + path("tet.xyz") + " --report " + path("r.json"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("cannot hold: 4 faces"), std::string::npos) << r.err;
  const nlohmann::json report = nlohmann::json::parse(test::read_bytes(path("r.json")));
  EXPECT_EQ(report["stages"][1]["counts"]["faces"], 0);
  EXPECT_EQ(report["warnings"].size(), 1u);
}

TEST_F(Cli, FaceFieldsTravelThroughPlyAndAreNamedWhereAFormatDropsThem) {
  TriangleMesh mesh;
  mesh.vertices.positions = {Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0), Vector3d(0, 0, 1)};
  mesh.triangles = {Triangle(0, 2, 1), Triangle(0, 1, 3), Triangle(0, 3, 2), Triangle(1, 2, 3)};
  mesh.face_fields.add("region", 4, ScalarType::Int32).values = {0, 1, 1, 2};
  write_mesh(path("tet.ply"), mesh);
  RunResult r = run("convert " + path("tet.ply") + " " + path("copy.ply") + " --ascii", dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.err.find("cannot hold"), std::string::npos) << r.err;
  const TriangleMesh back = read_mesh(path("copy.ply")).mesh;
  ASSERT_NE(back.face_fields.find("region"), nullptr);
  EXPECT_EQ(back.face_fields.find("region")->values, (std::vector<double>{0, 1, 1, 2}));
  r = run("info " + path("copy.ply") + " --json", dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json info = nlohmann::json::parse(r.out);
  ASSERT_EQ(info["face_fields"].size(), 1u);
  EXPECT_EQ(info["face_fields"][0]["name"], "region");
  EXPECT_EQ(info["face_fields"][0]["type"], "int");
  EXPECT_EQ(info["face_fields"][0]["max"], 2.0);
  for (const std::string ext : {"obj", "off", "stl"}) {
    r = run("convert " + path("tet.ply") + " " + path("tet." + ext), dir_);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("the " + ext + " format cannot hold: face field 'region'"), std::string::npos) << r.err;
    EXPECT_EQ(read_mesh(path("tet." + ext)).mesh.triangle_count(), 4u);
  }
}

TEST_F(Cli, FloatOutputOfGeoreferencedCloudIsRefusedAndLeavesNothing) {
  const RunResult r = run("convert " + test::data_path("b9_training.ply").string() + " " + path("b9.ply") + " --float", dir_);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_FALSE(std::filesystem::exists(path("b9.ply")));
  for (const auto& entry : std::filesystem::directory_iterator(dir_))
    EXPECT_EQ(entry.path().filename().string().find(".tmp"), std::string::npos) << entry.path();
}

TEST_F(Cli, ThreadsOptionAndDirectionOrientation) {
  PointCloud plane = test::sample_plane(2000);
  plane.normals.clear();
  write_point_cloud(path("plane.xyz"), plane);
  const RunResult r = run("normals " + path("plane.xyz") + " " + path("plane.ply") + " --orient direction --direction 0,0,-1 --threads 1 --quiet", dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const PointCloud out = read_point_cloud(path("plane.ply")).cloud;
  for (const Vector3d& n : out.normals) EXPECT_LT(n.z(), -0.99);
}

// Two scans of a room from inside, written as E57 with their poses, 1e6 m from the origin. By
// default the normals face the scanner that recorded each point (inwards); MST's outward vote,
// asked for, turns the closed room's walls outwards: away from both scanners.
TEST_F(Cli, NormalsOfE57ScansFaceTheirScanners) {
  const Vector3d corner(1e6, 2e6, 100.0);  // the room is [0,10] x [0,8] x [0,3] from here
  std::vector<ScanPose> poses(2);
  poses[0].translation = corner + Vector3d(2.5, 4.0, 1.5);
  poses[0].rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Vector3d::UnitZ()));
  poses[1].translation = corner + Vector3d(7.5, 4.0, 1.5);
  poses[1].rotation = Eigen::Quaterniond(Eigen::AngleAxisd(-2.0, Vector3d::UnitZ()));
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  PointCloud scans;  // in each scan's own frame, as a scanner records them
  std::vector<double>& scan = scans.fields.add("scan", 0).values;
  std::vector<Vector3d> world;
  const Vector3d size(10, 8, 3);
  while (world.size() < 30000) {
    Vector3d p(u(rng) * size.x(), u(rng) * size.y(), u(rng) * size.z());
    const int axis = static_cast<int>(u(rng) * 3.0) % 3;  // a point on one of the six walls
    p[axis] = u(rng) < 0.5 ? 0.0 : size[axis];
    const int s = p.x() < 5.0 ? 0 : 1;
    world.push_back(corner + p);
    scans.positions.push_back(poses[std::size_t(s)].rotation.conjugate() * (corner + p - poses[std::size_t(s)].translation));
    scan.push_back(s);
  }
  WriteOptions options;
  options.scan_poses = poses;
  write_point_cloud(path("room.e57"), scans, options);

  const auto facing = [&](const std::string& file) {
    const PointCloud got = read_point_cloud(path(file)).cloud;
    std::size_t towards = 0;
    for (std::size_t i = 0; i < got.size(); ++i) {
      const std::size_t s = got.positions[i].x() - corner.x() < 5.0 ? 0 : 1;
      towards += got.normals[i].dot(poses[s].translation - got.positions[i]) > 0.0 ? 1 : 0;
    }
    return double(towards) / double(got.size());
  };
  RunResult r = run("normals " + path("room.e57") + " " + path("n.ply") + " --report " + path("n.json"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(test::contains(r.err, "oriented towards the 2 scanner positions")) << r.err;
  EXPECT_GT(facing("n.ply"), 0.999);
  const nlohmann::json report = nlohmann::json::parse(test::read_bytes(path("n.json")));
  EXPECT_EQ(report["stages"][1]["parameters"]["orient"], "scanners");
  r = run("normals " + path("room.e57") + " " + path("mst.ply") + " --orient mst", dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_LT(facing("mst.ply"), 0.01);
}

}  // namespace
}  // namespace pointsurf
