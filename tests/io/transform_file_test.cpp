// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/io/transform_file.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "support/files.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

RigidTransform some_motion() {
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  return RigidTransform::about(Eigen::Vector3d(4.0e6, 5.0e5, 120.0), r, Eigen::Vector3d(0.1, -0.2, 0.3));
}

TEST(TransformFile, RoundTripIsExact) {
  const auto dir = test::temp_dir("transform_file_round_trip");
  TransformFile f;
  f.transform = some_motion();
  f.members = {{"fitness", 0.93}, {"iterations", std::int64_t(14)}, {"converged", true}, {"descriptor", std::string("fpfh")},
               {"seconds", std::vector<double>{0.5, 1.25}}};
  write_transform_file(dir / "T.json", f);
  const std::string text = test::read_bytes(dir / "T.json");
  EXPECT_TRUE(test::contains(text, "\"matrix\": [")) << text;
  EXPECT_LT(text.find("matrix"), text.find("fitness"));  // matrix first
  const TransformFile back = read_transform_file(dir / "T.json");
  EXPECT_EQ(back.transform.matrix(), f.transform.matrix());
  ASSERT_EQ(back.members.size(), 5u);
  auto find = [&](const std::string& name) {
    for (const auto& [k, v] : back.members)
      if (k == name) return v;
    ADD_FAILURE() << name;
    return TransformFileValue{};
  };
  EXPECT_EQ(std::get<double>(find("fitness")), 0.93);
  EXPECT_EQ(std::get<std::int64_t>(find("iterations")), 14);
  EXPECT_EQ(std::get<bool>(find("converged")), true);
  EXPECT_EQ(std::get<std::string>(find("descriptor")), "fpfh");
  EXPECT_EQ(std::get<std::vector<double>>(find("seconds")), (std::vector<double>{0.5, 1.25}));
  // No temporary file is left beside it.
  std::size_t files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) files += e.is_regular_file();
  EXPECT_EQ(files, 1u);
}

TEST(TransformFile, ReadsSixteenNumbersAndProjectsShortDigits) {
  const auto dir = test::temp_dir("transform_file_flat");
  // A rotation of 45 degrees about z written with 6 digits, as people type it.
  test::write_bytes(dir / "T.json", R"({"matrix": [0.707107, -0.707107, 0, 1, 0.707107, 0.707107, 0, 2, 0, 0, 1, 3, 0, 0, 0, 1]})");
  const TransformFile f = read_transform_file(dir / "T.json");
  EXPECT_NEAR(f.transform.angle_degrees(), 45.0, 1e-4);
  EXPECT_LT((f.transform.rotation() * f.transform.rotation().transpose() - Eigen::Matrix3d::Identity()).norm(), 1e-14);
  EXPECT_EQ(f.transform.translation(), Eigen::Vector3d(1, 2, 3));
  EXPECT_TRUE(f.members.empty());
}

TEST(TransformFile, BadFilesAreNamed) {
  const auto dir = test::temp_dir("transform_file_bad");
  auto expect = [&](const std::string& name, const std::string& text, const std::string& part) {
    test::write_bytes(dir / name, text);
    test::expect_error<InputError>([&] { read_transform_file(dir / name); }, part);
  };
  expect("a.json", "{\"matrix\": [1, 0", "a.json: not JSON");
  expect("b.json", "[1, 2]", "b.json: expected a JSON object with a \"matrix\", got array");
  expect("c.json", "{\"fitness\": 1}", "c.json: no \"matrix\" member");
  expect("d.json", "{\"matrix\": [1, 0, 0]}", "d.json: \"matrix\": a list of 3 items");
  expect("e.json", "{\"matrix\": [[1,0,0,0],[0,1,0,0],[0,0,1,0]]}", "e.json: \"matrix\": a list of 3 items");
  expect("f.json", "{\"matrix\": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,\"x\",1]]}", "f.json: \"matrix\": row 4 holds \"x\"");
  expect("g.json", "{\"matrix\": [2,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]}", "g.json: \"matrix\": the 3x3 block is not a rotation");
  expect("h.json", "{\"matrix\": [-1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,0,1]}", "determinant -1");
  expect("i.json", "{\"matrix\": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0,0,1,1]}", "i.json: \"matrix\": the last row must be 0, 0, 0, 1");
  test::expect_error<InputError>([&] { read_transform_file(dir / "missing.json"); }, "missing.json");
  TransformFile f;
  f.members = {{"matrix", 1.0}};
  test::expect_error<UsageError>([&] { write_transform_file(dir / "out.json", f); }, "may not be named \"matrix\"");
  test::expect_error<Error>([&] { write_transform_file(dir / "no_such_dir" / "out.json", TransformFile{}); }, "does not exist");
}

}  // namespace
}  // namespace pointsurf
