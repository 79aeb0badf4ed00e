// SPDX-License-Identifier: GPL-3.0-or-later
// The registration commands and stages end to end: `transform --file T.json`, `register`,
// `register-many`, and a pipeline that reads two scans by tag, registers and merges them.
#include <set>

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_run.h"
#include "pointsurf/io/io.h"
#include "pointsurf/io/transform_file.h"
#include "support/files.h"
#include "support/scan_views.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

class RegisterCli : public ::testing::Test {
public:
  void SetUp() override {
    dir_ = test::temp_dir(std::string("register_cli_") + ::testing::UnitTest::GetInstance()->current_test_info()->name());
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::filesystem::path dir_;
};


RigidTransform test_motion() {
  return RigidTransform(Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.2, 1.0, 0.3).normalized()).toRotationMatrix(), Eigen::Vector3d(0.3, -0.1, 0.2));
}

TEST_F(RegisterCli, TransformReadsTJsonAndInverts) {
  const PointCloud sphere = test::sample_sphere(500, 1.0, Vector3d(2, 0, 1));
  write_point_cloud(path("in.ply"), sphere);
  TransformFile t;
  t.transform = test_motion();
  t.members = {{"fitness", 1.0}};
  write_transform_file(path("T.json"), t);
  test::CliResult r = test::run_cli("transform " + path("in.ply") + " " + path("moved.ply") + " --file " + path("T.json"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const PointCloud moved = read_point_cloud(path("moved.ply")).cloud;
  ASSERT_EQ(moved.size(), sphere.size());
  for (std::size_t i = 0; i < sphere.size(); ++i) EXPECT_LT((moved.positions[i] - t.transform.apply(sphere.positions[i])).norm(), 1e-12);
  r = test::run_cli("transform " + path("moved.ply") + " " + path("back.ply") + " --file " + path("T.json") + " --invert", dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const PointCloud back = read_point_cloud(path("back.ply")).cloud;
  for (std::size_t i = 0; i < sphere.size(); ++i) EXPECT_LT((back.positions[i] - sphere.positions[i]).norm(), 1e-12);

  r = test::run_cli("transform " + path("in.ply") + " " + path("x.ply") + " --file " + path("T.json") + " --matrix 1,0,0,0,0,1,0,0,0,0,1,0,0,0,0,1",
                    dir_);
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_TRUE(test::contains(r.err, "give one of them, not both")) << r.err;
  test::write_bytes(dir_ / "bad.json", "{\"matrix\": [1, 2, 3]}");
  r = test::run_cli("transform " + path("in.ply") + " " + path("x.ply") + " --file " + path("bad.json"), dir_);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_TRUE(test::contains(r.err, "bad.json: \"matrix\": a list of 3 items")) << r.err;
  EXPECT_FALSE(std::filesystem::exists(path("x.ply")));
}


// Two views of the kitten 45 degrees apart in frames of their own, written as a.ply (scan 0)
// and b.ply (scan 1); returns the truth mapping b onto a.
RigidTransform write_two_views(const RegisterCli& t, bool normals = true) {
  test::ScanViews s = test::scan_views(2, 0.1, 11, 45.0);
  if (!normals)
    for (PointCloud& c : s.clouds) c.normals.clear();
  write_point_cloud(t.path("a.ply"), s.clouds[0]);
  write_point_cloud(t.path("b.ply"), s.clouds[1]);
  return s.truth[0].inverse() * s.truth[1];
}

TEST_F(RegisterCli, RegisterWritesTJsonAndTheMovedSource) {
  const RigidTransform truth = write_two_views(*this);
  test::CliResult r = test::run_cli("register " + path("b.ply") + " " + path("a.ply") + " --out " + path("T.json") + " --apply " + path("moved.ply") +
                                        " --report " + path("r.json"),
                                    dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(test::contains(r.err, "register: source onto target: rotation")) << r.err;
  const TransformFile t = read_transform_file(path("T.json"));
  const PointCloud b = read_point_cloud(path("b.ply")).cloud;
  EXPECT_LT(RigidTransform::rotation_error_degrees(t.transform, truth), 0.5);
  EXPECT_LT(RigidTransform::translation_error(t.transform, truth, b.positions[0]), 0.5 * test::kKittenSpacing);
  std::set<std::string> members;
  for (const auto& [name, value] : t.members) members.insert(name);
  for (const char* m : {"fitness", "inlier_rmse", "iterations", "converged", "descriptor", "seconds"}) EXPECT_TRUE(members.count(m)) << m;
  // --apply wrote the source moved by exactly that matrix: as `transform --file` does.
  r = test::run_cli("transform " + path("b.ply") + " " + path("moved2.ply") + " --file " + path("T.json"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const PointCloud moved = read_point_cloud(path("moved.ply")).cloud, moved2 = read_point_cloud(path("moved2.ply")).cloud;
  ASSERT_EQ(moved.size(), moved2.size());
  for (std::size_t i = 0; i < moved.size(); i += 97) EXPECT_LT((moved.positions[i] - moved2.positions[i]).norm(), 1e-12);
  // The report holds the transform and the per-step times.
  const nlohmann::json report = nlohmann::json::parse(test::read_bytes(path("r.json")));
  const nlohmann::json& m = report["stages"][2]["metrics"];
  EXPECT_EQ(m["transform"].size(), 16u);
  for (const char* key : {"fitness", "inlier_rmse", "iterations", "converged", "seconds_descriptors", "seconds_align", "seconds_icp"})
    EXPECT_TRUE(m.contains(key)) << key;
  EXPECT_EQ(report["stages"][2]["parameters"]["descriptor"], "fpfh");
}

TEST_F(RegisterCli, RegisterEstimatesMissingNormalsWithAWarning) {
  const RigidTransform truth = write_two_views(*this, false);
  const test::CliResult r =
      test::run_cli("register " + path("b.ply") + " " + path("a.ply") + " --out " + path("T.json") + " --descriptor pfh", dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(test::contains(r.err, "the source has no normals; estimated")) << r.err;
  EXPECT_TRUE(test::contains(r.err, "the target has no normals; estimated")) << r.err;
  const TransformFile t = read_transform_file(path("T.json"));
  EXPECT_LT(RigidTransform::rotation_error_degrees(t.transform, truth), 1.0);
}

TEST_F(RegisterCli, BadRegistrationsEndWithTheirExitCodes) {
  write_two_views(*this);
  write_point_cloud(path("far.ply"), test::sample_sphere(2000, 0.3, Vector3d(50, 0, 0), 9));
  PointCloud few;
  for (int i = 0; i < 6; ++i) few.positions.emplace_back(i, 0.5 * i, 0);
  write_point_cloud(path("few.ply"), few);
  struct Case {
    std::string args, message;
    int exit_code;
  };
  const std::vector<Case> cases = {
      {"register " + path("far.ply") + " " + path("a.ply") + " --out " + path("T.json") + " --ransac-iterations 2000", "no overlap found: fitness", 3},
      {"register " + path("few.ply") + " " + path("a.ply") + " --out " + path("T.json"), "source: 6 points; registration needs at least 10", 2},
      {"register " + path("b.ply") + " " + path("a.ply"), "nothing to write: give --out FILE, --apply OUT or both", 1},
      {"register " + path("b.ply") + " --out " + path("T.json"), "expected two input files source target, got 1 file name", 1},
      {"register " + path("b.ply") + " " + path("a.ply") + " --out " + path("T.json") + " --icp planes", "--icp: \"planes\" is not one of point or plane",
       1},
      {"register-many " + path("a.ply") + " " + path("far.ply") + " --out " + path("m.ply"), "scan 1 could not be registered to scan 0", 3},
  };
  for (const Case& c : cases) {
    const test::CliResult r = test::run_cli(c.args, dir_);
    EXPECT_EQ(r.exit_code, c.exit_code) << c.args << "\n" << r.err;
    EXPECT_TRUE(test::contains(r.err, c.message)) << c.args << "\n" << r.err;
    EXPECT_FALSE(std::filesystem::exists(path("T.json"))) << c.args;
    EXPECT_FALSE(std::filesystem::exists(path("m.ply"))) << c.args;
  }
}

TEST_F(RegisterCli, RegisterManyMergesWithAScanField) {
  const test::ScanViews s = test::scan_views(3, 0.1, 12, 50.0);
  std::string inputs;
  for (std::size_t i = 0; i < 3; ++i) {
    write_point_cloud(path(fmt::format("s{}.ply", i)), s.clouds[i]);
    inputs += " " + path(fmt::format("s{}.ply", i));
  }
  test::CliResult r = test::run_cli("register-many" + inputs + " --out " + path("merged.ply") + " --report " + path("r.json"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const PointCloud merged = read_point_cloud(path("merged.ply")).cloud;
  ASSERT_EQ(merged.size(), s.clouds[0].size() + s.clouds[1].size() + s.clouds[2].size());
  const ScalarField* scan = merged.fields.find("scan");
  ASSERT_NE(scan, nullptr);
  EXPECT_EQ(scan->values.back(), 2.0);
  // Each scan's points land where the truth puts them.
  const std::size_t first_of_2 = s.clouds[0].size() + s.clouds[1].size();
  EXPECT_LT((merged.positions[first_of_2] - s.truth[2].apply(s.clouds[2].positions[0])).norm(), test::kKittenSpacing);
  const nlohmann::json report = nlohmann::json::parse(test::read_bytes(path("r.json")));
  const nlohmann::json& m = report["stages"][3]["metrics"];
  EXPECT_EQ(m["pose_2"].size(), 16u);
  EXPECT_TRUE(m.contains("graph_cost"));
  // The positional form names the output last, as merge does.
  r = test::run_cli("register-many" + inputs + " " + path("merged2.ply") + " --mode first --no-refine --poses " + path("poses"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(test::contains(r.err, "register-many: 3 scans in one frame (first of them")) << r.err;
  // --poses: one T.json per scan, the pose that maps it into scan 0's frame; transform --file
  // with it puts scan 2's points where the merge put them.
  for (std::size_t i = 0; i < 3; ++i) {
    const TransformFile f = read_transform_file(path(fmt::format("poses/scan_{}_s{}.json", i, i)));
    if (i == 0) EXPECT_LT((f.transform.matrix() - Eigen::Matrix4d::Identity()).norm(), 1e-12);
  }
  r = test::run_cli("transform " + path("s2.ply") + " " + path("s2_moved.ply") + " --file " + path("poses/scan_2_s2.json"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const PointCloud moved = read_point_cloud(path("s2_moved.ply")).cloud;
  const PointCloud merged2 = read_point_cloud(path("merged2.ply")).cloud;
  EXPECT_LT((moved.positions[0] - merged2.positions[first_of_2]).norm(), 1e-9);
}

TEST_F(RegisterCli, PipelineReadsTwoScansByTagRegistersAndMerges) {
  const RigidTransform truth = write_two_views(*this);
  const std::string pipeline = R"([{"type": "read", "filename": ")" + path("a.ply") + R"(", "tag": "a"},
    {"type": "read", "filename": ")" + path("b.ply") + R"(", "tag": "b"},
    {"type": "register", "inputs": ["b", "a"], "tag": "b_on_a", "out": ")" + path("T.json") + R"("},
    {"type": "merge", "inputs": ["a", "b_on_a"]},
    ")" + path("merged.ply") + R"("])";
  test::write_bytes(dir_ / "p.json", pipeline);
  const test::CliResult r = test::run_cli("run " + path("p.json"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const PointCloud a = read_point_cloud(path("a.ply")).cloud, b = read_point_cloud(path("b.ply")).cloud;
  const PointCloud merged = read_point_cloud(path("merged.ply")).cloud;
  ASSERT_EQ(merged.size(), a.size() + b.size());
  EXPECT_LT((merged.positions[a.size()] - truth.apply(b.positions[0])).norm(), 0.5 * test::kKittenSpacing);
  EXPECT_TRUE(std::filesystem::exists(path("T.json")));
  // A register step needs its two inputs named.
  test::write_bytes(dir_ / "q.json", "[\"" + path("a.ply") + "\", {\"type\": \"register\"}, \"" + path("x.ply") + "\"]");
  const test::CliResult q = test::run_cli("run " + path("q.json"), dir_);
  EXPECT_EQ(q.exit_code, 1) << q.err;
  EXPECT_TRUE(test::contains(q.err, "stage 2 (register): takes 2 inputs, got 1")) << q.err;
}

// The keys of the previous release (x_in_spacings numbers) still work, with a warning, and
// give what the lengths in spacings give.
TEST_F(RegisterCli, OldInSpacingsKeysAreLengthsInSpacingsWithAWarning) {
  write_two_views(*this);
  const auto pipeline = [&](const std::string& params, const std::string& name) {
    return R"([{"type": "read", "filename": ")" + path("a.ply") + R"(", "tag": "a"},
      {"type": "read", "filename": ")" + path("b.ply") + R"(", "tag": "b"},
      {"type": "register", "inputs": ["b", "a"], "out": ")" + path(name + ".json") + R"(", )" + params + R"(}, ")" + path(name + ".ply") + "\"]";
  };
  test::write_bytes(dir_ / "old.json", pipeline(R"("voxel_in_spacings": 3, "icp_distance_in_spacings": 4, "radius_in_spacings": 8)", "T_old"));
  test::write_bytes(dir_ / "new.json", pipeline(R"("voxel": "3sp", "icp_distance": "4sp", "radius": "8sp")", "T_new"));
  test::CliResult r = test::run_cli("run " + path("old.json") + " --report " + path("old_report.json"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = test::run_cli("run " + path("new.json") + " --report " + path("new_report.json"), dir_);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(read_transform_file(path("T_old.json")).transform.matrix(), read_transform_file(path("T_new.json")).transform.matrix());
  const nlohmann::json old_report = nlohmann::json::parse(test::read_bytes(path("old_report.json")));
  const nlohmann::json new_report = nlohmann::json::parse(test::read_bytes(path("new_report.json")));
  std::string warnings;
  for (const auto& w : old_report["warnings"]) warnings += w.get<std::string>() + "\n";
  for (const char* key : {"voxel_in_spacings", "icp_distance_in_spacings", "radius_in_spacings"})
    EXPECT_TRUE(test::contains(warnings, fmt::format("key \"{}\" is deprecated", key))) << warnings;
  EXPECT_FALSE(test::contains(new_report["warnings"].dump(), "deprecated"));
  nlohmann::json params = old_report["stages"][2]["parameters"], new_params = new_report["stages"][2]["parameters"];
  EXPECT_EQ(params["voxel"], "3sp");
  EXPECT_EQ(params["icp_distance"], "4sp");
  EXPECT_FALSE(params.contains("voxel_in_spacings"));
  params.erase("out");
  new_params.erase("out");
  EXPECT_EQ(params, new_params);
}

}  // namespace
}  // namespace pointsurf
