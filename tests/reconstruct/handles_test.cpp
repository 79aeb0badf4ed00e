// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/reconstruct/handles.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <set>

#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "pointsurf/core/mesh_topology.h"
#include "reconstruct/detail/iso_surface.h"

namespace pointsurf {
namespace {

using ScalarFunction = std::function<double(const Vector3d&)>;

// An analytic inside-positive function, contoured on the octree refined near its zero set.
class Analytic : public detail::IsoFunction {
 public:
  Analytic(ScalarFunction f, detail::IsoLattice lattice) : f_(std::move(f)), lattice_(lattice) {}
  void corner_values(int level, const std::uint32_t* corners, std::size_t n, double* values) const override {
    for (std::size_t i = 0; i < n; ++i)
      values[i] = f_(lattice_.corner_position(level, {corners[3 * i], corners[3 * i + 1], corners[3 * i + 2]}));
  }
  double value(const Vector3d& p) const override { return f_(p); }
  Vector3d gradient(const Vector3d& p) const override {
    const double e = 1e-6;
    Vector3d g;
    for (int i = 0; i < 3; ++i) {
      Vector3d d = Vector3d::Zero();
      d[i] = e;
      g[i] = (f_(p + d) - f_(p - d)) / (2 * e);
    }
    return g;
  }
  bool refined(int level, const std::array<std::uint32_t, 3>& cell) const override {
    const double half = 0.5 * lattice_.size / double(std::uint64_t{1} << level);
    const Vector3d centre = lattice_.corner_position(level, cell) + Vector3d::Constant(half);
    return level < lattice_.depth && std::abs(f_(centre)) <= std::sqrt(3.0) * half * 1.01;
  }

 private:
  ScalarFunction f_;
  detail::IsoLattice lattice_;
};

// The zero set of f in [-1, 1]^3 at 128 cells a side (edges about 0.01), shifted by `offset`.
TriangleMesh contour(const ScalarFunction& f, const Vector3d& offset = Vector3d::Zero()) {
  detail::IsoLattice lattice;
  lattice.origin = Vector3d::Constant(-1.0);
  lattice.size = 2.0;
  lattice.depth = 7;
  const detail::IsoSurface s = detail::extract_iso_surface(Analytic(f, lattice), lattice, {});
  TriangleMesh mesh;
  for (const Vector3d& v : s.vertices) mesh.vertices.positions.push_back(v + offset);
  for (const auto& t : s.triangles) mesh.triangles.emplace_back(int(t[0]), int(t[1]), int(t[2]));
  return mesh;
}

ScalarFunction sphere(const Vector3d& c, double r) {
  return [c, r](const Vector3d& p) { return r - (p - c).norm(); };
}
// A torus of major radius R and minor r around the axis `axis` (0 x, 1 y, 2 z) through c.
ScalarFunction torus(const Vector3d& c, double R, double r, int axis) {
  return [c, R, r, axis](const Vector3d& p) {
    const Vector3d q = p - c;
    const double along = q[axis];
    const double across = std::sqrt(std::max(0.0, q.squaredNorm() - along * along));
    return r - std::hypot(across - R, along);
  };
}
ScalarFunction capsule(const Vector3d& a, const Vector3d& b, double r) {
  return [a, b, r](const Vector3d& p) {
    const double t = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
    return r - (p - (a + t * (b - a))).norm();
  };
}
ScalarFunction join(ScalarFunction f, ScalarFunction g) {
  return [f, g](const Vector3d& p) { return std::max(f(p), g(p)); };
}

// A sphere of radius 0.6 with a small ring (minor radius 0.05, meridian 0.31) half sunk into it
// at +x: genus 1, whose shortest loop is short.
ScalarFunction sphere_with_small_handle() {
  return join(sphere(Vector3d::Zero(), 0.6), torus(Vector3d(0.6, 0, 0), 0.15, 0.05, 1));
}

HandleParams spacing(double s) {
  HandleParams p;
  p.spacing = s;  // limit 10 x 0.04 = 0.4: the small ring's meridian (0.31) is under it
  return p;
}

TEST(Handles, TheSmallRingOfASphereIsCutAndBothSidesClosed) {
  TriangleMesh mesh = contour(sphere_with_small_handle());
  const MeshTopology before = analyze_topology(mesh);
  ASSERT_TRUE(before.watertight());
  ASSERT_EQ(before.genus(), 1);
  const std::vector<Vector3d> positions = mesh.vertices.positions;
  const std::vector<Triangle> triangles = mesh.triangles;

  const HandleResult r = remove_short_handles(mesh, spacing(0.04));
  EXPECT_EQ(r.handles_before, 1);
  EXPECT_EQ(r.short_handles, 1u);
  EXPECT_EQ(r.handles_removed, 1u);
  EXPECT_EQ(r.handles_after, 0);
  EXPECT_DOUBLE_EQ(r.max_loop_length, 0.4);
  ASSERT_EQ(r.loops.size(), 1u);
  EXPECT_GT(r.shortest_loop, 0.0);
  EXPECT_LE(r.shortest_loop, 0.4);
  const MeshTopology after = analyze_topology(mesh);
  EXPECT_TRUE(after.watertight());
  EXPECT_EQ(after.genus(), 0);
  EXPECT_EQ(after.components, 1u);
  // No vertex moved or added; every triangle that changed lies on the ring (within 0.25 of its centre).
  EXPECT_EQ(mesh.vertices.positions, positions);
  const auto key = [](const Triangle& t) {
    std::array<int, 3> k{t[0], t[1], t[2]};
    std::rotate(k.begin(), std::min_element(k.begin(), k.end()), k.end());
    return k;
  };
  std::set<std::array<int, 3>> old_set, new_set;
  for (const Triangle& t : triangles) old_set.insert(key(t));
  for (const Triangle& t : mesh.triangles) new_set.insert(key(t));
  std::size_t changed = 0;
  for (const auto& t : new_set)
    if (!old_set.count(t)) {
      ++changed;
      for (int v : t) EXPECT_LT((positions[std::size_t(v)] - Vector3d(0.6, 0, 0)).norm(), 0.25);
    }
  for (const auto& t : old_set) {
    if (new_set.count(t)) continue;
    for (int v : t) EXPECT_LT((positions[std::size_t(v)] - Vector3d(0.6, 0, 0)).norm(), 0.25);
  }
  EXPECT_GT(changed, 0u);
  // The loop cut is a loop of the mesh around the ring's tube: near the ring's core circle.
  for (int v : r.loops.front().vertices) {
    const Vector3d q = positions[std::size_t(v)] - Vector3d(0.6, 0, 0);
    EXPECT_NEAR(std::hypot(std::hypot(q.x(), q.z()) - 0.15, q.y()), 0.05, 0.03);
  }
}

TEST(Handles, HolesElsewhereDoNotHideTheRing) {
  // The sphere with its small ring, open where z > 0.45 (a cap cut off) and around (0, -0.6, 0):
  // the searches on either side of a loop pass through the holes.
  TriangleMesh mesh = contour(sphere_with_small_handle());
  std::erase_if(mesh.triangles, [&](const Triangle& t) {
    const Vector3d c = (mesh.vertices.positions[std::size_t(t[0])] + mesh.vertices.positions[std::size_t(t[1])] +
                        mesh.vertices.positions[std::size_t(t[2])]) / 3.0;
    return c.z() > 0.45 || (c - Vector3d(0, -0.6, 0)).norm() < 0.1;
  });
  const MeshTopology before = analyze_topology(mesh);
  ASSERT_EQ(before.boundary_loops.size(), 2u);
  ASSERT_EQ(before.genus(), 1);
  const HandleResult r = remove_short_handles(mesh, spacing(0.04));
  EXPECT_EQ(r.handles_removed, 1u);
  const MeshTopology after = analyze_topology(mesh);
  EXPECT_EQ(after.genus(), 0);
  EXPECT_EQ(after.boundary_loops.size(), 2u);
  EXPECT_EQ(after.boundary_edges, before.boundary_edges);
}

TEST(Handles, RealHandlesAndThinLimbsAreLeftAlone) {
  // A torus (meridian 1.26) with a thin finger (a separating loop of 0.31 around it).
  TriangleMesh mesh = contour(join(torus(Vector3d::Zero(), 0.5, 0.2, 2), capsule(Vector3d(0.65, 0, 0), Vector3d(0.95, 0, 0), 0.05)));
  ASSERT_EQ(analyze_topology(mesh).genus(), 1);
  const std::vector<Triangle> triangles = mesh.triangles;
  const HandleResult r = remove_short_handles(mesh, spacing(0.04));
  EXPECT_EQ(r.handles_before, 1);
  EXPECT_EQ(r.short_handles, 0u);
  EXPECT_EQ(r.handles_removed, 0u);
  EXPECT_EQ(r.handles_after, 1);
  EXPECT_EQ(r.shortest_loop, 0.0);
  EXPECT_EQ(mesh.triangles, triangles);
  // With a limit above the torus' meridian, the torus is a short handle too.
  HandleParams wide = spacing(0.04);
  wide.max_loop_in_spacings = 40;  // 1.6 > 1.26
  EXPECT_EQ(find_short_handles(mesh, wide).short_handles, 1u);
}

TEST(Handles, CountingLeavesTheMeshAsItIs) {
  TriangleMesh mesh = contour(sphere_with_small_handle());
  const std::vector<Triangle> triangles = mesh.triangles;
  HandleParams count = spacing(0.04);
  count.remove = false;
  const HandleResult r = remove_short_handles(mesh, count);
  EXPECT_EQ(r.short_handles, 1u);
  EXPECT_EQ(r.handles_removed, 0u);
  EXPECT_EQ(r.handles_after, 1);
  EXPECT_EQ(mesh.triangles, triangles);
  const HandleResult found = find_short_handles(mesh, spacing(0.04));
  EXPECT_EQ(found.short_handles, 1u);
  EXPECT_EQ(found.loops.size(), 1u);
}

TEST(Handles, SeveralSmallRingsAndAFarOffsetGiveTheSameCut) {
  // Two small rings on opposite sides, two components (a second sphere with one ring); at the
  // origin and shifted by 1e6 m.
  const ScalarFunction f = join(join(sphere(Vector3d(-0.3, 0, 0), 0.45), torus(Vector3d(0.15, 0, 0), 0.12, 0.045, 1)),
                                join(torus(Vector3d(-0.75, 0, 0), 0.12, 0.045, 2), join(sphere(Vector3d(0.55, 0.45, 0.3), 0.25),
                                                                                      torus(Vector3d(0.55, 0.45, 0.55), 0.1, 0.04, 0))));
  TriangleMesh near = contour(f), far = contour(f, Vector3d(1e6, 2e6, 50));
  ASSERT_EQ(analyze_topology(near).handles(), 3);
  ASSERT_EQ(analyze_topology(near).components, 2u);
  const HandleResult a = remove_short_handles(near, spacing(0.04)), b = remove_short_handles(far, spacing(0.04));
  EXPECT_EQ(a.handles_before, 3);
  EXPECT_EQ(a.handles_removed, 3u);
  EXPECT_EQ(a.handles_after, 0);
  EXPECT_EQ(analyze_topology(near).components, 2u);
  EXPECT_TRUE(analyze_topology(near).watertight());
  // Far away the lengths differ in their last bits, which may pick another loop of equal length
  // around the same ring: the same cuts, not the same triangles.
  EXPECT_EQ(b.handles_removed, a.handles_removed);
  EXPECT_EQ(b.handles_after, 0);
  EXPECT_TRUE(analyze_topology(far).watertight());
  EXPECT_NEAR(b.shortest_loop, a.shortest_loop, 0.05 * a.shortest_loop);
  EXPECT_NEAR(double(far.triangles.size()), double(near.triangles.size()), 0.01 * double(near.triangles.size()));
}

// Progress grows through the searches and changes nothing; a false answer cancels.
TEST(Handles, ReportsProgressAndCanBeCancelled) {
  const TriangleMesh original = contour(sphere_with_small_handle());
  TriangleMesh heard = original, plain = original;
  std::vector<double> fractions;
  const HandleResult a = remove_short_handles(heard, spacing(0.04), [&](double f) {
    fractions.push_back(f);
    return true;
  });
  const HandleResult b = remove_short_handles(plain, spacing(0.04));
  ASSERT_GE(fractions.size(), 2u);
  EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
  EXPECT_GE(fractions.back(), 0.9);
  EXPECT_LE(fractions.back(), 1.0);
  EXPECT_EQ(a.handles_removed, b.handles_removed);
  EXPECT_EQ(heard.triangles, plain.triangles);
  TriangleMesh cancelled = original;
  EXPECT_THROW(remove_short_handles(cancelled, spacing(0.04), [](double f) { return f < 0.3; }), CancelledError);
}

TEST(Handles, DefaultSpacingIsTheMeanEdgeLength) {
  TriangleMesh mesh = contour(sphere_with_small_handle());
  const HandleResult r = find_short_handles(mesh, {});
  EXPECT_GT(r.max_loop_length, 0.05);  // 10 edges of about 0.01
  EXPECT_LT(r.max_loop_length, 0.2);
  EXPECT_EQ(r.short_handles, 0u);  // the ring's meridian (0.31) is longer
}

TEST(Handles, ParametersOutOfRangeAreRefused) {
  TriangleMesh mesh = contour(sphere(Vector3d::Zero(), 0.5));
  HandleParams p;
  p.max_loop_in_spacings = -1;
  EXPECT_THROW(remove_short_handles(mesh, p), UsageError);
  p = HandleParams{};
  p.spacing = std::nan("");
  EXPECT_THROW(remove_short_handles(mesh, p), UsageError);
  // Genus 0: nothing to look for.
  const HandleResult r = remove_short_handles(mesh, {});
  EXPECT_EQ(r.handles_before, 0);
  EXPECT_EQ(r.short_handles, 0u);
}

}  // namespace
}  // namespace pointsurf
