// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/reconstruct/crust.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "pointsurf/reconstruct/cocone.h"
#include "support/crust_sampling.h"
#include "support/mesh_compare.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

using test::spaced;

TEST(Crust, SphereIsWatertightGenusZeroOutwardAndClose) {
  const PointCloud cloud = spaced(test::sample_sphere(30000, 1.0, Vector3d::Zero(), 11), 0.06);
  CrustStats stats;
  const ReconstructionResult r = reconstruct_crust(cloud, {}, {}, &stats);
  EXPECT_TRUE(r.topology.watertight());
  EXPECT_EQ(r.topology.genus(), 0);
  EXPECT_EQ(r.topology.components, 1u);
  EXPECT_EQ(r.unused_points, 0u);
  EXPECT_EQ(test::inward_faces(r.mesh, Vector3d::Zero()), 0u);
  const auto [to_truth, from_truth] = test::hausdorff_to_surface(r.mesh, test::sample_sphere(20000, 1.0, Vector3d::Zero(), 5).positions,
                                                                 [](const Vector3d& x) { return std::abs(x.norm() - 1.0); });
  EXPECT_LE(to_truth, 0.25 * r.mean_spacing);
  EXPECT_LE(from_truth, 1.0 * r.mean_spacing);
  // Every sample of a sphere is on the hull: one finite pole each (p-, near the centre).
  EXPECT_EQ(stats.hull_points, cloud.size());
  EXPECT_GT(stats.poles, 0u);
  EXPECT_LE(stats.poles, cloud.size());
  EXPECT_EQ(stats.second_delaunay_vertices, cloud.size() + stats.poles);
  EXPECT_GT(stats.second_delaunay_cells, stats.delaunay_cells);
  EXPECT_GE(stats.candidate_triangles, r.mesh.triangles.size());
}

TEST(Crust, TorusIsWatertightGenusOneAndClose) {
  const PointCloud cloud = spaced(test::sample_torus(60000, 1.0, 0.4, 12), 0.05);
  CrustStats stats;
  const ReconstructionResult r = reconstruct_crust(cloud, {}, {}, &stats);
  EXPECT_TRUE(r.topology.watertight());
  EXPECT_EQ(r.topology.genus(), 1);
  EXPECT_EQ(r.unused_points, 0u);
  const auto [to_truth, from_truth] =
      test::hausdorff_to_surface(r.mesh, test::sample_torus(20000, 1.0, 0.4, 5).positions, [](const Vector3d& x) {
        return std::abs(std::hypot(std::hypot(x.x(), x.y()) - 1.0, x.z()) - 0.4);
      });
  EXPECT_LE(to_truth, 0.25 * r.mean_spacing);
  EXPECT_LE(from_truth, 1.0 * r.mean_spacing);
  // Inner-ring samples have bounded Voronoi cells: both poles.
  EXPECT_GT(stats.poles, cloud.size());
}

// The two methods choose their candidates by different rules (empty of poles against crossing
// the cocones): on coarse random samples of a thin torus they keep different triangles, and
// both stay edge-manifold and oriented.
TEST(Crust, DiffersFromTheCoconeOnCoarseRandomSamples) {
  PointCloud cloud = test::sample_torus(2500, 1.0, 0.25, 21);
  cloud.normals.clear();
  CrustStats crust_stats;
  CoconeStats cocone_stats;
  const ReconstructionResult crust = reconstruct_crust(cloud, {}, {}, &crust_stats);
  const ReconstructionResult cocone = reconstruct_cocone(cloud, {}, {}, &cocone_stats);
  for (const ReconstructionResult* r : {&crust, &cocone}) {
    EXPECT_EQ(r->topology.non_manifold_edges, 0u);
    EXPECT_EQ(r->topology.inconsistent_edges, 0u);
    EXPECT_GT(r->topology.triangles, cloud.size());
  }
  const auto a = test::oriented_triangle_set(crust.mesh), b = test::oriented_triangle_set(cocone.mesh);
  std::vector<std::array<int, 3>> only_crust;
  std::set_difference(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(only_crust));
  EXPECT_GT(only_crust.size(), a.size() / 100) << "crust " << a.size() << " cocone " << b.size();
  EXPECT_NE(crust_stats.candidate_triangles, cocone_stats.candidate_triangles);
}

TEST(Crust, InvariantUnderPermutationRigidMotionAndLargeShift) {
  const PointCloud cloud = spaced(test::sample_torus(20000, 1.0, 0.4, 25), 0.08);
  const ReconstructionResult base = reconstruct_crust(cloud);
  ASSERT_TRUE(base.topology.watertight());
  const auto base_set = test::oriented_triangle_set(base.mesh);
  std::vector<std::size_t> perm(cloud.size());
  std::iota(perm.begin(), perm.end(), std::size_t{0});
  std::shuffle(perm.begin(), perm.end(), std::mt19937_64(5));
  const ReconstructionResult rp = reconstruct_crust(cloud.select(perm));
  EXPECT_EQ(test::oriented_triangle_set(rp.mesh, std::vector<int>(perm.begin(), perm.end())), base_set);
  const Eigen::Matrix3d rot = Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Vector3d offset(1e6, 2e6, 300.0);
  PointCloud moved = cloud;
  for (auto& x : moved.positions) x = rot * x + offset;
  const ReconstructionResult rm = reconstruct_crust(moved);
  EXPECT_EQ(rm.topology.genus(), 1);
  EXPECT_EQ(test::oriented_triangle_set(rm.mesh), base_set);
}

TEST(Crust, RejectsBadParametersAndDegenerateInput) {
  const PointCloud cloud = spaced(test::sample_sphere(5000, 1.0, Vector3d::Zero(), 30), 0.15);
  CrustParams p;
  p.sharp_edge_angle_deg = 90.0;
  try {
    reconstruct_crust(cloud, p);
    FAIL() << "no error";
  } catch (const UsageError& e) {
    EXPECT_NE(std::string(e.what()).find("crust: sharp_edge_angle_deg = 90"), std::string::npos) << e.what();
  }
  PointCloud flat;
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) flat.positions.emplace_back(i, j, 0.0);
  try {
    reconstruct_crust(flat);
    FAIL() << "no error";
  } catch (const ComputeError& e) {
    EXPECT_NE(std::string(e.what()).find("crust: all 36 points are coplanar"), std::string::npos) << e.what();
  }
  PointCloud few;
  few.positions = {Vector3d(0, 0, 0), Vector3d(1, 0, 0), Vector3d(0, 1, 0)};
  EXPECT_THROW(reconstruct_crust(few), UsageError);
}

}  // namespace
}  // namespace pointsurf
