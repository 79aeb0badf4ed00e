// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/io/io.h"
#include "pointsurf/normals/normals.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <random>
#include <string>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;

// The cloud's normals are the exact ones from the sampler; `exact` keeps them aside.
struct Shape {
  PointCloud cloud;
  std::vector<Vector3d> exact;
};

Shape make(PointCloud cloud) {
  Shape s;
  s.exact = std::move(cloud.normals);
  cloud.normals.clear();
  s.cloud = std::move(cloud);
  return s;
}

double angle_unoriented(const Vector3d& a, const Vector3d& b) { return std::acos(std::min(1.0, std::abs(a.dot(b)))); }

double mean_unoriented_error_deg(const std::vector<Vector3d>& normals, const std::vector<Vector3d>& exact) {
  double sum = 0.0;
  for (std::size_t i = 0; i < normals.size(); ++i) sum += angle_unoriented(normals[i], exact[i]);
  return sum / double(normals.size()) / kDegree;
}

// Number of points with a normal whose side disagrees with the exact outward normal.
std::size_t inward_count(const std::vector<Vector3d>& normals, const std::vector<Vector3d>& exact) {
  std::size_t bad = 0;
  for (std::size_t i = 0; i < normals.size(); ++i)
    if (normals[i].squaredNorm() > 0.0 && !(normals[i].dot(exact[i]) > 0.0)) ++bad;
  return bad;
}

Shape permuted(const Shape& s, std::vector<std::size_t>& perm, std::uint64_t seed = 5) {
  perm.resize(s.cloud.size());
  std::iota(perm.begin(), perm.end(), std::size_t(0));
  std::shuffle(perm.begin(), perm.end(), std::mt19937_64(seed));
  Shape out;
  out.cloud = s.cloud.select(perm);
  for (std::size_t i : perm) out.exact.push_back(s.exact[i]);
  return out;
}

Eigen::Isometry3d rigid_motion() {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.rotate(Eigen::AngleAxisd(0.7, Vector3d(1.0, -2.0, 0.5).normalized()));
  t.pretranslate(Vector3d(12.0, -3.5, 100.0));
  return t;
}

Shape moved(const Shape& s, const Eigen::Isometry3d& t) {
  Shape out = s;
  for (Vector3d& p : out.cloud.positions) p = t * p;
  for (Vector3d& n : out.exact) n = t.linear() * n;
  return out;
}

Shape shifted(const Shape& s, const Vector3d& offset) {
  Shape out = s;
  for (Vector3d& p : out.cloud.positions) p += offset;
  return out;
}

template <class F>
void expect_usage_error(F f, const std::string& message) {
  try {
    f();
    FAIL() << "expected UsageError: " << message;
  } catch (const UsageError& e) {
    EXPECT_EQ(std::string(e.what()), message);
  }
}

TEST(EstimateNormals, SphereNormalsAreAccurate) {
  Shape s = make(test::sample_sphere(20000, 2.0));
  const NormalResult r = estimate_normals(s.cloud, {.k = 30});
  EXPECT_EQ(r.degenerate, 0u);
  ASSERT_EQ(s.cloud.normals.size(), s.exact.size());
  EXPECT_LT(mean_unoriented_error_deg(s.cloud.normals, s.exact), 1.0);
  for (const Vector3d& n : s.cloud.normals) ASSERT_NEAR(n.norm(), 1.0, 1e-12);
  const ScalarField* variation = s.cloud.fields.find("variation");
  ASSERT_NE(variation, nullptr);
  EXPECT_EQ(variation->type, ScalarType::Float32);
  ASSERT_EQ(variation->values.size(), s.cloud.size());
  for (double v : variation->values) ASSERT_TRUE(v >= 0.0 && v <= 1.0 / 3.0) << v;
}

TEST(EstimateNormals, RadiusAndHybridNeighbourhoods) {
  Shape s = make(test::sample_sphere(20000));
  const double spacing = mean_spacing(s.cloud.positions);
  NormalResult r = estimate_normals(s.cloud, {.neighborhood = NeighborhoodKind::Radius});
  EXPECT_NEAR(r.radius_used, 3.0 * spacing, 1e-12);
  EXPECT_LT(mean_unoriented_error_deg(s.cloud.normals, s.exact), 2.0);
  r = estimate_normals(s.cloud, {.neighborhood = NeighborhoodKind::Hybrid, .k = 20, .radius = Length::cloud(0.08)});
  EXPECT_EQ(r.radius_used, 0.08);
  EXPECT_EQ(r.degenerate, 0u);
  EXPECT_LT(mean_unoriented_error_deg(s.cloud.normals, s.exact), 1.0);
}

TEST(EstimateNormals, PlaneNormalsAreExactlyVertical) {
  Shape s = make(test::sample_plane(3000));
  const NormalResult r = estimate_normals(s.cloud, {.k = 12});
  EXPECT_EQ(r.degenerate, 0u);
  for (const Vector3d& n : s.cloud.normals) {
    ASSERT_NEAR(std::abs(n.z()), 1.0, 1e-12);
    ASSERT_NEAR(n.x(), 0.0, 1e-12);
    ASSERT_NEAR(n.y(), 0.0, 1e-12);
  }
  for (double v : s.cloud.fields.find("variation")->values) ASSERT_NEAR(v, 0.0, 1e-12);
}

TEST(EstimateNormals, CubeFacesAreExactAwayFromEdges) {
  Shape s = make(test::sample_cube(30000));
  const KdTree tree(s.cloud.positions);
  estimate_normals(s.cloud, {.k = 30}, &tree);
  // A point whose 30 neighbours all lie on its own face has a planar neighbourhood: its normal
  // is exact. Closer to an edge the neighbourhood bends round it and the normal blends.
  std::vector<Neighbor> neighbors;
  std::size_t interior = 0;
  for (std::size_t i = 0; i < s.cloud.size(); ++i) {
    const Vector3d& p = s.cloud.positions[i];
    tree.knn(p, 30, neighbors);
    const double reach = std::sqrt(neighbors.back().squared_distance);
    double to_edge = 1e300;
    for (int a = 0; a < 3; ++a)
      if (std::abs(s.exact[i][a]) == 0.0) to_edge = std::min(to_edge, 1.0 - std::abs(p[a]));
    if (to_edge <= reach) continue;
    ++interior;
    ASSERT_LT(angle_unoriented(s.cloud.normals[i], s.exact[i]), 1e-9) << "point " << i;
  }
  EXPECT_GT(interior, s.cloud.size() / 2);
}

TEST(EstimateNormals, InvariantUnderPermutationAndRigidMotion) {
  const Shape s = make(test::sample_torus(8000));
  PointCloud base = s.cloud;
  estimate_normals(base, {.k = 20});

  std::vector<std::size_t> perm;
  Shape p = permuted(s, perm);
  estimate_normals(p.cloud, {.k = 20});
  for (std::size_t i = 0; i < perm.size(); ++i)
    ASSERT_LT((p.cloud.normals[i] - base.normals[perm[i]]).norm(), 1e-9) << "point " << i;

  const Eigen::Isometry3d t = rigid_motion();
  Shape m = moved(s, t);
  estimate_normals(m.cloud, {.k = 20});
  for (std::size_t i = 0; i < s.cloud.size(); ++i)
    ASSERT_LT(angle_unoriented(m.cloud.normals[i], t.linear() * base.normals[i]), 1e-6) << "point " << i;
}

TEST(EstimateNormals, GeoreferencedCloudGivesTheSameNormals) {
  const Shape s = make(test::sample_sphere(5000, 10.0));
  PointCloud base = s.cloud;
  estimate_normals(base, {.k = 20});
  Shape far = shifted(s, Vector3d(6.5e6, -1e6, 6.5e6));
  estimate_normals(far.cloud, {.k = 20});
  for (std::size_t i = 0; i < s.cloud.size(); ++i)
    ASSERT_LT(angle_unoriented(far.cloud.normals[i], base.normals[i]), 1e-6) << "point " << i;
}

TEST(EstimateNormals, ExistingNormalsKeepTheirSide) {
  Shape s = make(test::sample_sphere(5000));
  s.cloud.normals = s.exact;
  estimate_normals(s.cloud, {.k = 20});
  EXPECT_EQ(inward_count(s.cloud.normals, s.exact), 0u);
  for (std::size_t i = 0; i < s.exact.size(); ++i) s.cloud.normals[i] = -s.exact[i];
  estimate_normals(s.cloud, {.k = 20});
  EXPECT_EQ(inward_count(s.cloud.normals, s.exact), s.exact.size());
}

TEST(EstimateNormals, CollinearNeighbourhoodsAreDegenerate) {
  PointCloud line;
  for (int i = 0; i < 200; ++i) line.positions.emplace_back(0.1 * i, 0.2 * i - 3.0, 0.05 * i);
  NormalResult r = estimate_normals(line, {.k = 10});
  EXPECT_EQ(r.degenerate, 200u);
  for (const Vector3d& n : line.normals) EXPECT_EQ(n, Vector3d::Zero());
  const OrientResult o = orient_normals(line);
  EXPECT_EQ(o.flipped, 0u);

  // A plane with a line far from it: only the line's points are degenerate; so are the points
  // of a cloud that all coincide.
  Shape s = make(test::sample_plane(2000));
  for (int i = 0; i < 50; ++i) s.cloud.positions.emplace_back(10.0 + 0.01 * i, 10.0, 10.0);
  r = estimate_normals(s.cloud, {.k = 10});
  EXPECT_EQ(r.degenerate, 50u);
  PointCloud same;
  same.positions.assign(20, Vector3d(1, 2, 3));
  r = estimate_normals(same, {.neighborhood = NeighborhoodKind::Hybrid});
  EXPECT_EQ(r.degenerate, 20u);
  EXPECT_EQ(r.radius_used, 0.0);
}

TEST(EstimateNormals, BadParametersThrowUsageError) {
  Shape s = make(test::sample_sphere(100));
  expect_usage_error([&] { estimate_normals(s.cloud, {.k = 2}); }, "estimate_normals: k must be >= 3, got 2");
  expect_usage_error([&] { estimate_normals(s.cloud, {.neighborhood = NeighborhoodKind::Radius, .radius = Length::cloud(-1.0)}); },
                     "estimate_normals: radius must be > 0, got -1");
  expect_usage_error(
      [&] { estimate_normals(s.cloud, {.neighborhood = NeighborhoodKind::Hybrid, .radius = Length::spacings(0.0)}); },
      "estimate_normals: radius must be > 0, got 0sp");
  PointCloud two;
  two.positions = {Vector3d::Zero(), Vector3d::UnitX()};
  expect_usage_error([&] { estimate_normals(two); }, "estimate_normals: needs at least 3 points, got 2");
  const KdTree other(two.positions);
  expect_usage_error([&] { estimate_normals(s.cloud, {}, &other); },
                     "estimate_normals: the kd-tree holds 2 points but the cloud has 100");
  EXPECT_TRUE(s.cloud.normals.empty());
}

TEST(EstimateNormals, ProgressIsReportedAndCanCancel) {
  Shape s = make(test::sample_sphere(20000));
  std::vector<double> fractions;
  estimate_normals(s.cloud, {}, nullptr, [&](double f) {
    fractions.push_back(f);
    return true;
  });
  ASSERT_FALSE(fractions.empty());
  EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
  EXPECT_EQ(fractions.back(), 1.0);

  PointCloud fresh = make(test::sample_sphere(20000)).cloud;
  EXPECT_THROW(estimate_normals(fresh, {}, nullptr, [](double f) { return f < 0.3; }), CancelledError);
  EXPECT_TRUE(fresh.normals.empty());  // a cancelled run leaves the cloud as it was
  EXPECT_FALSE(fresh.fields.contains("variation"));
}

// MST orientation turns every normal outward on closed shapes, whatever the point order,
// placement and far offset. On the sphere and the torus every estimated normal is within a
// few degrees of the exact one, so outward means a positive dot product with it. At the
// cube's corners a PCA normal can lean past 90 degrees from its face's normal while pointing
// out of the cube, so there outward means pointing away from the centre (the cube is convex)
// and, wherever the estimate is within 60 degrees of the face normal, agreeing with it.
class OrientMst : public ::testing::TestWithParam<const char*> {
protected:
  bool is_cube() const { return std::string(GetParam()) == "cube"; }
  Shape shape() const {
    const std::string name = GetParam();
    if (name == "sphere") return make(test::sample_sphere(20000, 1.5, Vector3d(0.3, -0.2, 0.1)));
    if (name == "torus") return make(test::sample_torus(20000, 1.0, 0.3));
    return make(test::sample_cube(20000, 1.0, 4));  // a seed with corner normals leaning past 90 degrees
  }
  // `center` is where the cube's centre went.
  void expect_outward(Shape s, const Vector3d& center = Vector3d::Zero()) const {
    const NormalResult r = estimate_normals(s.cloud, {.k = 30});
    EXPECT_EQ(r.degenerate, 0u);
    const OrientResult o = orient_normals(s.cloud);
    EXPECT_EQ(o.components, 1u);
    std::size_t inward = 0;
    for (std::size_t i = 0; i < s.cloud.size(); ++i) {
      const Vector3d& n = s.cloud.normals[i];
      const double along_exact = n.dot(s.exact[i]);
      if (!is_cube()) {
        inward += !(along_exact > 0.0);
      } else {
        inward += !(n.dot(s.cloud.positions[i] - center) > 0.0) || along_exact < -0.5;
      }
    }
    EXPECT_EQ(inward, 0u);
  }
};

TEST_P(OrientMst, AllNormalsOutward) { expect_outward(shape()); }

TEST_P(OrientMst, AllNormalsOutwardAfterPermutation) {
  std::vector<std::size_t> perm;
  expect_outward(permuted(shape(), perm));
}

TEST_P(OrientMst, AllNormalsOutwardAfterRigidMotion) {
  const Eigen::Isometry3d t = rigid_motion();
  expect_outward(moved(shape(), t), t.translation());
}

TEST_P(OrientMst, AllNormalsOutwardFarFromTheOrigin) {
  const Vector3d offset(1e6, -1e6, 1e6);
  expect_outward(shifted(shape(), offset), offset);
}

INSTANTIATE_TEST_SUITE_P(Shapes, OrientMst, ::testing::Values("sphere", "torus", "cube"));

TEST(OrientNormals, NoisyTorusIsOutward) {
  Shape s = make(test::sample_torus(20000, 1.0, 0.3, 2));
  test::add_noise(s.cloud, 0.01);
  estimate_normals(s.cloud, {.k = 30});
  orient_normals(s.cloud);
  EXPECT_EQ(inward_count(s.cloud.normals, s.exact), 0u);
}

// An open terrain-like height field has no inside: the vote falls back on "up" (+z), whatever
// the PCA signs were, even far from the origin like a georeferenced tile.
TEST(OrientNormals, OpenHeightFieldPointsUp) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-50.0, 50.0);
  PointCloud cloud;
  for (int i = 0; i < 20000; ++i) {
    const double x = u(rng), y = u(rng);
    cloud.positions.emplace_back(596000.0 + x, 243000.0 + y, 80.0 + 3.0 * std::sin(0.1 * x) * std::cos(0.07 * y));
  }
  estimate_normals(cloud, {.k = 20});
  std::mt19937_64 flips(3);
  for (Vector3d& n : cloud.normals)
    if (flips() & 1) n = -n;
  orient_normals(cloud);
  std::size_t down = 0;
  for (const Vector3d& n : cloud.normals) down += n.z() <= 0.0;
  EXPECT_EQ(down, 0u);
}

// A single view of a convex object seen from the side (an open cap of a sphere facing -x) is
// oriented outward. (Mostly horizontal open sheets follow the survey convention instead: up.)
TEST(OrientNormals, SideViewOfSphereIsOutward) {
  const PointCloud sphere = test::sample_sphere(30000, 2.0, Vector3d(0, 0, 0), 5);
  PointCloud cap;
  for (std::size_t i = 0; i < sphere.size(); ++i)
    if (sphere.positions[i].x() < -0.8) {
      cap.positions.push_back(sphere.positions[i]);
      cap.normals.push_back(sphere.normals[i]);
    }
  const std::vector<Vector3d> exact = cap.normals;
  cap.normals.clear();
  estimate_normals(cap, {.k = 20});
  orient_normals(cap);
  EXPECT_EQ(inward_count(cap.normals, exact), 0u);
}

// Terrain with a building: ground and a flat roof 15 m higher, joined only through the walls.
// Propagation has to cross the 90-degree creases; every horizontal surface must still face up.
TEST(OrientNormals, RoofAndGroundOfTerrainBothFaceUp) {
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  PointCloud cloud;
  const Vector3d offset(596000.0, 243000.0, 70.0);
  auto inside_building = [](double x, double y) { return x > 30 && x < 50 && y > 30 && y < 50; };
  for (int i = 0; i < 40000; ++i) {  // ground around the building, 80 m x 80 m
    const double x = 80 * u(rng), y = 80 * u(rng);
    if (!inside_building(x, y)) cloud.positions.push_back(offset + Vector3d(x, y, 0.02 * std::sin(x)));
  }
  for (int i = 0; i < 2500; ++i) {  // roof
    const double x = 30 + 20 * u(rng), y = 30 + 20 * u(rng);
    cloud.positions.push_back(offset + Vector3d(x, y, 15.0));
  }
  for (int i = 0; i < 6000; ++i) {  // four walls
    const double t = 20 * u(rng), z = 15 * u(rng);
    switch (i % 4) {
      case 0: cloud.positions.push_back(offset + Vector3d(30 + t, 30, z)); break;
      case 1: cloud.positions.push_back(offset + Vector3d(30 + t, 50, z)); break;
      case 2: cloud.positions.push_back(offset + Vector3d(30, 30 + t, z)); break;
      default: cloud.positions.push_back(offset + Vector3d(50, 30 + t, z)); break;
    }
  }
  estimate_normals(cloud, {.k = 20});
  orient_normals(cloud);
  std::size_t horizontal = 0, down = 0;
  for (const Vector3d& n : cloud.normals) {
    if (std::abs(n.z()) < 0.9) continue;
    ++horizontal;
    down += n.z() < 0.0;
  }
  EXPECT_GT(horizontal, 30000u);
  EXPECT_EQ(down, 0u);
}

// The shipped aerial LiDAR tile (ground, trees, a building whose roof is joined to the
// ground only through sparse walls): horizontal surfaces must face up. Before the crease
// regions of step 7, the roof came out upside down (89 % of horizontal points up).
TEST(OrientNormals, AerialTileHorizontalSurfacesFaceUp) {
  PointCloud cloud = read_point_cloud(test::data_path("b9_training.ply")).cloud;
  estimate_normals(cloud, {.k = 30});
  orient_normals(cloud);
  std::size_t horizontal = 0, up = 0;
  for (const Vector3d& n : cloud.normals) {
    if (std::abs(n.z()) < 0.9) continue;
    ++horizontal;
    up += n.z() > 0.0;
  }
  ASSERT_GT(horizontal, 10000u);
  EXPECT_GT(double(up) / double(horizontal), 0.95);
}

TEST(OrientNormals, CountsFlipsAndComponents) {
  // Two spheres far apart, exact normals with a third of them reversed.
  Shape a = make(test::sample_sphere(3000, 1.0, Vector3d::Zero(), 1));
  Shape b = make(test::sample_sphere(3000, 1.0, Vector3d(10, 0, 0), 2));
  PointCloud both = a.cloud;
  both.append(b.cloud);
  std::vector<Vector3d> exact = a.exact;
  exact.insert(exact.end(), b.exact.begin(), b.exact.end());
  both.normals = exact;
  for (std::size_t i = 0; i < exact.size(); i += 3) both.normals[i] = -exact[i];
  const OrientResult o = orient_normals(both, {.k = 8});
  EXPECT_EQ(o.components, 2u);
  EXPECT_EQ(o.flipped, 2000u);
  EXPECT_EQ(inward_count(both.normals, exact), 0u);
}

TEST(OrientNormals, ASamplingGapIsJoinedButSeparateObjectsAreNot) {
  // A sphere without its equatorial band (|z| < 0.1, about 4 spacings wide): the kNN graph
  // falls into two caps, which the shortest connecting edge joins into one component.
  Shape full = make(test::sample_sphere(6000, 1.0, Vector3d::Zero(), 4));
  Shape s;
  for (std::size_t i = 0; i < full.cloud.size(); ++i) {
    if (std::abs(full.cloud.positions[i].z()) < 0.1) continue;
    s.cloud.positions.push_back(full.cloud.positions[i]);
    s.exact.push_back(full.exact[i]);
  }
  s.cloud.normals = s.exact;
  for (std::size_t i = 0; i < s.exact.size(); i += 3) s.cloud.normals[i] = -s.exact[i];
  const OrientResult o = orient_normals(s.cloud, {.k = 8});
  EXPECT_EQ(o.components, 1u);
  EXPECT_EQ(inward_count(s.cloud.normals, s.exact), 0u);
}

TEST(OrientNormals, ZeroNormalsAreSkipped) {
  Shape s = make(test::sample_sphere(5000));
  s.cloud.normals = s.exact;
  for (std::size_t i = 0; i < s.exact.size(); i += 4) s.cloud.normals[i] = -s.exact[i];
  for (std::size_t i = 1; i < s.exact.size(); i += 10) s.cloud.normals[i] = Vector3d::Zero();
  orient_normals(s.cloud);
  EXPECT_EQ(inward_count(s.cloud.normals, s.exact), 0u);
  for (std::size_t i = 1; i < s.exact.size(); i += 10) EXPECT_EQ(s.cloud.normals[i], Vector3d::Zero());
}

TEST(OrientNormals, ViewpointAndDirection) {
  Shape s = make(test::sample_sphere(2000, 1.0, Vector3d(5, 5, 5)));
  s.cloud.normals = s.exact;
  // Seen from the centre every outward normal turns inward.
  OrientResult o = orient_normals(s.cloud, {.method = Orientation::Viewpoint, .viewpoint = Vector3d(5, 5, 5)});
  EXPECT_EQ(o.flipped, 2000u);
  EXPECT_EQ(inward_count(s.cloud.normals, s.exact), 2000u);
  o = orient_normals(s.cloud, {.method = Orientation::Viewpoint, .viewpoint = Vector3d(5, 5, 5)});
  EXPECT_EQ(o.flipped, 0u);

  Shape plane = make(test::sample_plane(500));
  plane.cloud.normals = plane.exact;
  o = orient_normals(plane.cloud, {.method = Orientation::Direction, .direction = Vector3d(0.1, 0, -3)});
  EXPECT_EQ(o.flipped, 500u);
  for (const Vector3d& n : plane.cloud.normals) EXPECT_EQ(n, Vector3d(0, 0, -1));
  o = orient_normals(plane.cloud, {.method = Orientation::None});
  EXPECT_EQ(o.flipped, 0u);
}

TEST(OrientNormals, BadParametersThrowUsageError) {
  Shape s = make(test::sample_sphere(100));
  expect_usage_error([&] { orient_normals(s.cloud); }, "orient_normals: the cloud has no normals (estimate them first)");
  s.cloud.normals = s.exact;
  expect_usage_error([&] { orient_normals(s.cloud, {.k = 0}); }, "orient_normals: orient_k must be >= 1, got 0");
  expect_usage_error([&] { orient_normals(s.cloud, {.method = Orientation::Direction, .direction = Vector3d::Zero()}); },
                     "orient_normals: the direction must be a finite non-zero vector, got (0, 0, 0)");
  s.cloud.normals.pop_back();
  expect_usage_error([&] { orient_normals(s.cloud); }, "orient_normals: the cloud has 99 normals for 100 points");
}

TEST(OrientToReference, SphereFlippedAtRandomAgreesWithTheInputEverywhere) {
  // The exact outward normals are the input; the new ones are flipped at random (seeded): after
  // orient_to_reference they all agree with the input, and compare_normals says 100 %.
  Shape s = make(test::sample_sphere(4000));
  s.cloud.normals = s.exact;
  std::mt19937_64 rng(11);
  std::size_t reversed = 0;
  for (Vector3d& n : s.cloud.normals)
    if (rng() % 2 == 0) {
      n = -n;
      ++reversed;
    }
  const NormalAgreement before = compare_normals(s.exact, s.cloud.normals);
  EXPECT_EQ(before.compared, 4000u);
  EXPECT_EQ(before.agreeing, 4000u - reversed);
  const OrientResult r = orient_to_reference(s.cloud, s.exact);
  EXPECT_EQ(r.flipped, reversed);
  EXPECT_EQ(inward_count(s.cloud.normals, s.exact), 0u);
  const NormalAgreement after = compare_normals(s.exact, s.cloud.normals);
  EXPECT_EQ(after.agreeing, 4000u);
  EXPECT_DOUBLE_EQ(after.share, 1.0);
  EXPECT_NEAR(after.mean_angle_deg, 0.0, 1e-6);
}

TEST(OrientToReference, ZeroNormalsAreLeftOutAndSizesChecked) {
  Shape s = make(test::sample_sphere(100));
  s.cloud.normals = s.exact;
  std::vector<Vector3d> reference = s.exact;
  for (std::size_t i = 0; i < 100; i += 2) reference[i] = -reference[i];
  reference[1] = Vector3d::Zero();
  s.cloud.normals[3] = Vector3d::Zero();
  const NormalAgreement a = compare_normals(reference, s.cloud.normals);
  EXPECT_EQ(a.compared, 98u);
  EXPECT_EQ(a.agreeing, 48u);
  EXPECT_EQ(orient_to_reference(s.cloud, reference).flipped, 50u);
  EXPECT_EQ(s.cloud.normals[3], Vector3d::Zero());
  EXPECT_EQ(s.cloud.normals[1], s.exact[1]);
  EXPECT_EQ(compare_normals({}, s.cloud.normals).compared, 0u);
  reference.pop_back();
  expect_usage_error([&] { orient_to_reference(s.cloud, reference); },
                     "orient_to_reference: 100 normals and 99 reference normals for 100 points");
  s.cloud.normals.clear();
  expect_usage_error([&] { orient_to_reference(s.cloud, s.exact); }, "orient_to_reference: the cloud has no normals (estimate them first)");
}

// A sphere seen from two scanners inside it, one per half: every normal faces its own scanner
// (inwards), whatever side PCA gave it; indices out of range are refused.
TEST(OrientToScanners, EachNormalFacesTheScannerOfItsPoint) {
  const Vector3d centre(3e6, -1e6, 50.0);
  Shape s = make(test::sample_sphere(2000, 1.0, centre));
  s.cloud.normals = s.exact;  // outward
  for (std::size_t i = 0; i < 2000; i += 3) s.cloud.normals[i] = -s.cloud.normals[i];
  const std::vector<Vector3d> scanners = {centre + Vector3d(-0.3, 0, 0), centre + Vector3d(0.3, 0, 0)};
  std::vector<double> scan(2000);
  for (std::size_t i = 0; i < 2000; ++i) scan[i] = s.cloud.positions[i].x() < centre.x() ? 0.0 : 1.0;
  orient_to_scanners(s.cloud, scanners, scan);
  for (std::size_t i = 0; i < 2000; ++i) EXPECT_GT(s.cloud.normals[i].dot(scanners[std::size_t(scan[i])] - s.cloud.positions[i]), 0.0) << i;
  for (std::size_t i = 0; i < 2000; ++i) EXPECT_LT((s.cloud.normals[i] + s.exact[i]).norm(), 1e-12) << i;  // inwards
  scan[7] = 2.0;
  EXPECT_THROW(orient_to_scanners(s.cloud, scanners, scan), InputError);
  scan.pop_back();
  EXPECT_THROW(orient_to_scanners(s.cloud, scanners, scan), UsageError);
  EXPECT_THROW(orient_to_scanners(s.cloud, {}), UsageError);
}

TEST(OrientNormals, ProgressCanCancel) {
  Shape s = make(test::sample_sphere(20000));
  s.cloud.normals = s.exact;
  std::vector<double> fractions;
  orient_normals(s.cloud, {}, nullptr, [&](double f) {
    fractions.push_back(f);
    return true;
  });
  ASSERT_FALSE(fractions.empty());
  EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
  EXPECT_EQ(fractions.back(), 1.0);
  for (std::size_t i = 0; i < s.exact.size(); i += 2) s.cloud.normals[i] = -s.exact[i];
  const std::vector<Vector3d> before = s.cloud.normals;
  EXPECT_THROW(orient_normals(s.cloud, {}, nullptr, [](double f) { return f < 0.5; }), CancelledError);
  EXPECT_THROW(orient_normals(s.cloud, {}, nullptr, [](double f) { return f < 1.0; }), CancelledError);
  EXPECT_EQ(s.cloud.normals, before);  // a cancelled run leaves the normals as they were
}

}  // namespace
}  // namespace pointsurf
