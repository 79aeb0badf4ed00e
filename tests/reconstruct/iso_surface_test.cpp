// SPDX-License-Identifier: GPL-3.0-or-later
#include "reconstruct/detail/iso_surface.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <tuple>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include "pointsurf/core/error.h"
#include "pointsurf/core/mesh_topology.h"

namespace pointsurf {
namespace {

using detail::extract_iso_surface;
using detail::IsoFunction;
using detail::IsoLattice;
using detail::IsoSurface;
using detail::IsoSurfaceParams;

using ScalarFunction = std::function<double(const Vector3d&)>;
using Refine = std::function<bool(int level, const Vector3d& centre, double half_size)>;

/// An analytic function (inside positive) with a numerical gradient, on an octree that `refine`
/// describes from each cell's centre and half size.
class AnalyticIso : public IsoFunction {
 public:
  AnalyticIso(ScalarFunction value, IsoLattice lattice, Refine refine)
      : value_(std::move(value)), lattice_(lattice), refine_(std::move(refine)) {}
  void corner_values(int level, const std::uint32_t* corners, std::size_t n, double* values) const override {
    for (std::size_t i = 0; i < n; ++i)
      values[i] = value_(lattice_.corner_position(level, {corners[3 * i], corners[3 * i + 1], corners[3 * i + 2]}));
  }
  double value(const Vector3d& p) const override { return value_(p); }
  Vector3d gradient(const Vector3d& p) const override {
    const double e = 1e-6 * lattice_.size;
    Vector3d g;
    for (int i = 0; i < 3; ++i) {
      Vector3d d = Vector3d::Zero();
      d[i] = e;
      g[i] = (value_(p + d) - value_(p - d)) / (2 * e);
    }
    return g;
  }
  bool refined(int level, const std::array<std::uint32_t, 3>& cell) const override {
    const double half = 0.5 * lattice_.size / double(std::uint64_t{1} << level);
    const Vector3d centre = lattice_.corner_position(level, cell) + Vector3d::Constant(half);
    return refine_(level, centre, half);
  }

 private:
  ScalarFunction value_;
  IsoLattice lattice_;
  Refine refine_;
};


IsoLattice unit_lattice(int depth) {
  IsoLattice l;
  l.origin = Vector3d::Constant(-1.0);
  l.size = 2.0;
  l.depth = depth;
  return l;
}

/// Refined where |f| at the cell centre is below the cell's half diagonal (f 1-Lipschitz).
Refine near_surface(const ScalarFunction& f, int depth) {
  return [f, depth](int level, const Vector3d& c, double half) {
    return level < depth && std::abs(f(c)) <= std::sqrt(3.0) * half * 1.01;
  };
}
Refine everywhere() {
  return [](int, const Vector3d&, double) { return true; };
}

TriangleMesh to_mesh(const IsoSurface& s) {
  TriangleMesh m;
  m.vertices.positions = s.vertices;
  m.vertices.normals = s.normals;
  for (const auto& t : s.triangles) m.triangles.emplace_back(int(t[0]), int(t[1]), int(t[2]));
  return m;
}

double signed_volume(const TriangleMesh& m) {
  double v = 0.0;
  for (const Triangle& t : m.triangles) v += m.vertices.positions[t[0]].dot(m.vertices.positions[t[1]].cross(m.vertices.positions[t[2]])) / 6.0;
  return v;
}

/// Checks every property the contract promises for a closed surface and returns the topology;
/// with `smooth` (a smooth function on a fine enough lattice), also that the gradient normals
/// agree with the triangles' orientation and that no two vertices coincide (they may where a
/// corner value equals the iso-value).
MeshTopology expect_closed_manifold(const IsoSurface& s, bool smooth = true) {
  const TriangleMesh m = to_mesh(s);
  m.validate();
  const MeshTopology topo = analyze_topology(m);
  EXPECT_GT(topo.triangles, 0u);
  EXPECT_EQ(topo.degenerate_triangles, 0u);
  EXPECT_EQ(topo.boundary_edges, 0u);
  EXPECT_EQ(topo.non_manifold_edges, 0u);
  EXPECT_EQ(topo.non_manifold_vertices, 0u);
  EXPECT_EQ(topo.inconsistent_edges, 0u);
  EXPECT_EQ(topo.isolated_vertices, 0u);
  EXPECT_TRUE(topo.watertight());
  EXPECT_GT(signed_volume(m), 0.0);
  // Unit normals that agree with the triangles' orientation.
  std::size_t against = 0;
  for (const Triangle& t : m.triangles) {
    const Vector3d n = (m.vertices.positions[t[1]] - m.vertices.positions[t[0]]).cross(m.vertices.positions[t[2]] - m.vertices.positions[t[0]]);
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(m.vertices.normals[t[k]].norm(), 1.0, 1e-9);
      if (n.dot(m.vertices.normals[t[k]]) < 0.0) ++against;
    }
  }
  if (!smooth) return topo;
  EXPECT_LE(against, m.triangles.size() / 50);
  // No vertex repeated by position (one vertex per crossed edge).
  std::vector<std::array<double, 3>> keys;
  for (const Vector3d& v : m.vertices.positions) keys.push_back({v.x(), v.y(), v.z()});
  std::sort(keys.begin(), keys.end());
  EXPECT_EQ(std::adjacent_find(keys.begin(), keys.end()), keys.end());
  return topo;
}

double max_abs(const IsoSurface& s, const ScalarFunction& distance) {
  double worst = 0.0;
  for (const Vector3d& v : s.vertices) worst = std::max(worst, std::abs(distance(v)));
  return worst;
}

ScalarFunction sphere(const Vector3d& c, double r) {
  return [c, r](const Vector3d& p) { return r - (p - c).norm(); };
}
ScalarFunction torus(double R, double r) {
  return [R, r](const Vector3d& p) { return r - std::hypot(std::hypot(p.x(), p.y()) - R, p.z()); };
}

TEST(IsoSurface, SphereNearSurfaceOctreeIsClosedGenusZeroAndOnTheSurface) {
  const ScalarFunction f = sphere(Vector3d(0.05, -0.02, 0.03), 0.7);
  const IsoLattice lattice = unit_lattice(6);
  const AnalyticIso iso(f, lattice, near_surface(f, 6));
  const double h = lattice.size / 64;
  const IsoSurface s = extract_iso_surface(iso, lattice, {});
  const MeshTopology topo = expect_closed_manifold(s);
  EXPECT_EQ(topo.components, 1u);
  EXPECT_EQ(topo.genus(), 0);
  EXPECT_LE(max_abs(s, f), 0.02 * h);
  IsoSurfaceParams refined;
  refined.root_refinement_steps = 8;
  EXPECT_LE(max_abs(extract_iso_surface(iso, lattice, refined), f), 1e-9);
  // Normals point away from the centre.
  for (std::size_t i = 0; i < s.vertices.size(); ++i)
    EXPECT_GT(s.normals[i].dot((s.vertices[i] - Vector3d(0.05, -0.02, 0.03)).normalized()), 0.999);
}

TEST(IsoSurface, UniformAndNearSurfaceOctreesGiveTheSameMesh) {
  const ScalarFunction f = sphere(Vector3d(0.1, 0.0, -0.1), 0.6);
  const IsoLattice lattice = unit_lattice(5);
  const IsoSurface a = extract_iso_surface(AnalyticIso(f, lattice, near_surface(f, 5)), lattice, {});
  const IsoSurface b = extract_iso_surface(AnalyticIso(f, lattice, everywhere()), lattice, {});
  EXPECT_EQ(a.vertices, b.vertices);
  EXPECT_EQ(a.triangles, b.triangles);
}

TEST(IsoSurface, TorusIsClosedGenusOne) {
  const ScalarFunction f = torus(0.55, 0.22);
  const IsoLattice lattice = unit_lattice(6);
  const IsoSurface s = extract_iso_surface(AnalyticIso(f, lattice, near_surface(f, 6)), lattice, {});
  const MeshTopology topo = expect_closed_manifold(s);
  EXPECT_EQ(topo.components, 1u);
  EXPECT_EQ(topo.genus(), 1);
  EXPECT_LE(max_abs(s, f), 0.05 * lattice.size / 64);
}

TEST(IsoSurface, TwoNearbySpheresStayTwoSpheres) {
  // Gap of 1.3 finest cells between them.
  const double h = 2.0 / 64;
  const ScalarFunction a = sphere(Vector3d(-0.4 - 0.65 * h, 0, 0), 0.4), b = sphere(Vector3d(0.4 + 0.65 * h, 0, 0), 0.4);
  const ScalarFunction f = [a, b](const Vector3d& p) { return std::max(a(p), b(p)); };
  const IsoLattice lattice = unit_lattice(6);
  const IsoSurface s = extract_iso_surface(AnalyticIso(f, lattice, near_surface(f, 6)), lattice, {});
  const MeshTopology topo = expect_closed_manifold(s);
  EXPECT_EQ(topo.components, 2u);
  EXPECT_EQ(topo.euler_characteristic, 4);  // two spheres
}

TEST(IsoSurface, ThinPlateIsOneClosedBox) {
  // A 1.5-cell thick plate: most cells see both of its faces.
  const double h = 2.0 / 64;
  const ScalarFunction f = [h](const Vector3d& p) {
    return std::min({0.75 * h - std::abs(p.z() - 0.3 * h), 0.6 - std::abs(p.x()), 0.6 - std::abs(p.y())});
  };
  const IsoLattice lattice = unit_lattice(6);
  const IsoSurface s = extract_iso_surface(AnalyticIso(f, lattice, near_surface(f, 6)), lattice, {});
  const MeshTopology topo = expect_closed_manifold(s);
  EXPECT_EQ(topo.components, 1u);
  EXPECT_EQ(topo.genus(), 0);
  EXPECT_LE(max_abs(s, f), h);
}

TEST(IsoSurface, LevelJumpsAcrossTheSurfaceStayCrackFree) {
  // Refined to depth 7 for x < 0.2, to depth 3 elsewhere: the surface crosses leaves four levels
  // apart, and most of it lies in coarse leaves.
  const ScalarFunction f = torus(0.5, 0.3);
  const IsoLattice lattice = unit_lattice(7);
  const Refine refine = [f](int level, const Vector3d& c, double half) {
    const int limit = c.x() - half < 0.2 ? 7 : 3;
    return level < limit && std::abs(f(c)) <= std::sqrt(3.0) * half * 1.01;
  };
  const IsoSurface s = extract_iso_surface(AnalyticIso(f, lattice, refine), lattice, {});
  const MeshTopology topo = expect_closed_manifold(s);
  EXPECT_EQ(topo.components, 1u);
  EXPECT_EQ(topo.genus(), 1);
  EXPECT_LE(max_abs(s, f), 0.05 * lattice.size / 128);
}

TEST(IsoSurface, OctreeShallowerThanTheLatticeIsMeshedAtItsDeepestLevel) {
  // Leaves stop at level 5 in a depth-7 lattice: the mesh is the depth-5 one.
  const ScalarFunction f = torus(0.5, 0.23);
  const IsoLattice deep = unit_lattice(7), shallow = unit_lattice(5);
  const IsoSurface a = extract_iso_surface(AnalyticIso(f, deep, near_surface(f, 5)), deep, {});
  const IsoSurface b = extract_iso_surface(AnalyticIso(f, shallow, near_surface(f, 5)), shallow, {});
  EXPECT_EQ(a.triangles, b.triangles);
  EXPECT_EQ(a.vertices, b.vertices);
  EXPECT_EQ(expect_closed_manifold(a).genus(), 1);
}

TEST(IsoSurface, CoarseOnlyOctreeIsSeededFromCoarseEdges) {
  // No finest leaf near the sphere: refined to level 2 everywhere, to 5 only along the face x = 1.
  const ScalarFunction f = sphere(Vector3d(0.02, 0.01, 0.0), 0.55);
  const IsoLattice lattice = unit_lattice(5);
  const Refine refine = [](int level, const Vector3d& c, double half) { return level < 2 || (level < 5 && c.x() + half > 0.99); };
  const IsoSurface s = extract_iso_surface(AnalyticIso(f, lattice, refine), lattice, {});
  const MeshTopology topo = expect_closed_manifold(s);
  EXPECT_EQ(topo.components, 1u);
  EXPECT_EQ(topo.genus(), 0);
  const IsoSurface uniform = extract_iso_surface(AnalyticIso(f, lattice, everywhere()), lattice, {});
  EXPECT_EQ(s.triangles, uniform.triangles);
}

/// Trilinear interpolation of given lattice values: every face ambiguity is exercised.
class LatticeIso : public IsoFunction {
 public:
  LatticeIso(std::vector<double> values, int n) : v_(std::move(values)), n_(n) {}
  double at(std::uint32_t x, std::uint32_t y, std::uint32_t z) const { return v_[(std::size_t(z) * (n_ + 1) + y) * (n_ + 1) + x]; }
  void corner_values(int, const std::uint32_t* c, std::size_t n, double* out) const override {
    for (std::size_t i = 0; i < n; ++i) out[i] = at(c[3 * i], c[3 * i + 1], c[3 * i + 2]);
  }
  double value(const Vector3d& p) const override {
    const Vector3d q = p.cwiseMax(0.0).cwiseMin(double(n_) - 1e-12);
    const auto x = std::uint32_t(q.x()), y = std::uint32_t(q.y()), z = std::uint32_t(q.z());
    const double u = q.x() - x, v = q.y() - y, w = q.z() - z;
    double r = 0.0;
    for (int k = 0; k < 8; ++k)
      r += at(x + (k & 1), y + ((k >> 1) & 1), z + (k >> 2)) * ((k & 1) ? u : 1 - u) * ((k & 2) ? v : 1 - v) * ((k & 4) ? w : 1 - w);
    return r;
  }
  Vector3d gradient(const Vector3d& p) const override {
    Vector3d g;
    for (int i = 0; i < 3; ++i) {
      Vector3d d = Vector3d::Zero();
      d[i] = 1e-5;
      g[i] = (value(p + d) - value(p - d)) / 2e-5;
    }
    return g;
  }
  bool refined(int, const std::array<std::uint32_t, 3>&) const override { return true; }

 private:
  std::vector<double> v_;
  int n_;
};

std::vector<double> random_values(int n, unsigned seed, bool integers) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> real(-1.0, 1.0);
  std::uniform_int_distribution<int> ints(-1, 1);
  std::vector<double> v(std::size_t(n + 1) * (n + 1) * (n + 1));
  for (int z = 0; z <= n; ++z)
    for (int y = 0; y <= n; ++y)
      for (int x = 0; x <= n; ++x) {
        const bool border = x == 0 || y == 0 || z == 0 || x == n || y == n || z == n;
        v[(std::size_t(z) * (n + 1) + y) * (n + 1) + x] = border ? -1.0 : integers ? ints(rng) : real(rng);
      }
  return v;
}

TEST(IsoSurface, RandomCornerValuesGiveClosedManifoldSurfaces) {
  // Random signs: a third of the faces are ambiguous; values exactly at the iso-value (the
  // integer case) count as outside.
  IsoLattice lattice;
  lattice.size = 16.0;
  lattice.depth = 4;
  for (unsigned seed = 1; seed <= 6; ++seed)
    for (bool integers : {false, true}) {
      SCOPED_TRACE(testing::Message() << "seed " << seed << (integers ? " integers" : " reals"));
      const LatticeIso iso(random_values(16, seed, integers), 16);
      const IsoSurface s = extract_iso_surface(iso, lattice, {});
      EXPECT_GT(expect_closed_manifold(s, false).triangles, 100u);
      // Every vertex is a crossing on a lattice edge (or a loop centre inside a cell).
      for (std::size_t i = 0; i < s.vertices.size(); ++i) EXPECT_NEAR(iso.value(s.vertices[i]), 0.0, 0.6);
    }
}

TEST(IsoSurface, AmbiguousFaceFollowsTheAsymptoticDecider) {
  // On a 4^3 lattice at -1, two inside corners (a) diagonal on the face z = 1 of cell (1, 1, 0)
  // and the face's other two corners at -b: the bilinear saddle is inside when a^2 > b^2, so one
  // surface joins them; otherwise they are two separate spheres.
  for (const auto& [a, b, components] : {std::tuple{1.0, 0.5, 1u}, std::tuple{0.5, 1.0, 2u}}) {
    std::vector<double> v(125, -1.0);
    auto at = [&](int x, int y, int z) -> double& { return v[std::size_t((z * 5 + y) * 5 + x)]; };
    at(1, 1, 1) = a, at(2, 2, 1) = a, at(2, 1, 1) = -b, at(1, 2, 1) = -b;
    IsoLattice lattice;
    lattice.size = 4.0;
    lattice.depth = 2;
    const IsoSurface s = extract_iso_surface(LatticeIso(v, 4), lattice, {});
    const MeshTopology topo = expect_closed_manifold(s, false);
    EXPECT_EQ(topo.components, components) << "a " << a << " b " << b;
  }
}

TEST(IsoSurface, RandomSmoothFieldIsClosedAndManifold) {
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  std::vector<std::pair<Vector3d, double>> waves;
  for (int i = 0; i < 12; ++i) waves.emplace_back(Vector3d(normal(rng), normal(rng), normal(rng)) * 9.0, 6.28 * std::uniform_real_distribution<double>()(rng));
  const ScalarFunction f = [waves](const Vector3d& p) {
    double s = 0.0;
    for (const auto& [k, phase] : waves) s += std::sin(k.dot(p) + phase);
    // |noise| <= 0.3 sqrt(12) < 1.1: negative on the lattice's faces, so the surface is closed.
    return 0.3 * s / std::sqrt(double(waves.size())) + 2.0 * (0.45 - p.squaredNorm());
  };
  for (int depth : {4, 5}) {  // 3 and 6 cells per wavelength
    const IsoLattice lattice = unit_lattice(depth);
    const IsoSurface s = extract_iso_surface(AnalyticIso(f, lattice, everywhere()), lattice, {});
    const MeshTopology topo = expect_closed_manifold(s, depth == 5);
    EXPECT_GT(topo.triangles, 500u);
  }
}

TEST(IsoSurface, SameMeshUnderAnyThreadCount) {
  const ScalarFunction f = torus(0.5, 0.25);
  const IsoLattice lattice = unit_lattice(6);
  const AnalyticIso iso(f, lattice, near_surface(f, 6));
  IsoSurfaceParams params;
  params.root_refinement_steps = 3;
  IsoSurface one, many;
  tbb::task_arena(1).execute([&] { one = extract_iso_surface(iso, lattice, params); });
  tbb::task_arena(8).execute([&] { many = extract_iso_surface(iso, lattice, params); });
  EXPECT_EQ(one.vertices, many.vertices);
  EXPECT_EQ(one.normals, many.normals);
  EXPECT_EQ(one.triangles, many.triangles);
}

TEST(IsoSurface, SurfaceLeavingTheLatticeIsOpenOnlyAtItsFaces) {
  const ScalarFunction f = sphere(Vector3d(0.9, 0.0, 0.0), 0.5);
  const IsoLattice lattice = unit_lattice(5);
  const IsoSurface s = extract_iso_surface(AnalyticIso(f, lattice, near_surface(f, 5)), lattice, {});
  const MeshTopology topo = analyze_topology(to_mesh(s));
  EXPECT_GT(topo.boundary_edges, 0u);
  EXPECT_EQ(topo.non_manifold_edges, 0u);
  EXPECT_EQ(topo.non_manifold_vertices, 0u);
  EXPECT_EQ(topo.boundary_loops.size(), 1u);
  for (int v : topo.boundary_loops.at(0).vertices) EXPECT_NEAR(s.vertices[v].x(), 1.0, 1e-12);
}

TEST(IsoSurface, CancelsAndRejectsBadLattices) {
  const ScalarFunction f = sphere(Vector3d::Zero(), 0.5);
  IsoLattice lattice = unit_lattice(4);
  const AnalyticIso iso(f, lattice, everywhere());
  EXPECT_THROW(extract_iso_surface(iso, lattice, {}, [](double) { return false; }), CancelledError);
  lattice.depth = 25;
  EXPECT_THROW(extract_iso_surface(iso, lattice, {}), UsageError);
}

}  // namespace
}  // namespace pointsurf
