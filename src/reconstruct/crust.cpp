// SPDX-License-Identifier: GPL-3.0-or-later
// Crust via the cocone test (Amenta, Bern, Kamvysselis 1998; Amenta, Choi, Dey, Leekha 2000).
// This is the only file of pointsurf that includes CGAL for the crust: the Delaunay
// triangulation is copied into plain arrays right after it is built, and every later pass works
// on those arrays (in parallel where it is a per-point or per-cell pass).
#include "pointsurf/reconstruct/crust.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <utility>
#include <vector>

// CGAL's parallel Delaunay triangulation (oneTBB) is built when POINTSURF_PARALLEL_DELAUNAY is
// defined. It needs libtbbmalloc at link time (CGAL's concurrent containers use
// tbb::scalable_allocator), which the pointsurf target does not link by default. crust.cpp is the
// only translation unit that includes CGAL, so defining CGAL_LINKED_WITH_TBB here affects no other.
#if defined(POINTSURF_PARALLEL_DELAUNAY) && !defined(CGAL_LINKED_WITH_TBB)
#define CGAL_LINKED_WITH_TBB
#endif
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Delaunay_triangulation_cell_base_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_cell_base_with_info_3.h>
#include <CGAL/Triangulation_data_structure_3.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "core/detail/progress_reporter.h"
#include "pointsurf/core/error.h"
#include "pointsurf/core/mesh_topology.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_with_info_3<int, K>;
using Cb = CGAL::Triangulation_cell_base_with_info_3<int, K, CGAL::Delaunay_triangulation_cell_base_3<K>>;
// The triangulation itself does not depend on the insertion order (CGAL's symbolic perturbation
// settles cospherical points by a fixed rule); its cells are renumbered by their vertices below,
// so every later pass is deterministic with parallel insertion too.
#ifdef POINTSURF_PARALLEL_DELAUNAY
using Tds = CGAL::Triangulation_data_structure_3<Vb, Cb, CGAL::Parallel_tag>;
#else
using Tds = CGAL::Triangulation_data_structure_3<Vb, Cb>;
#endif
using Delaunay = CGAL::Delaunay_triangulation_3<K, Tds>;

constexpr double kPi = 3.14159265358979323846;
constexpr int kInfinite = -1;
constexpr std::size_t kAxisNeighbours = 10;  // samples in the plane fit that gives hull samples their axis

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

/// The Delaunay triangulation as plain arrays. Cell c has vertices cell_vertex[c] (kInfinite for
/// the point at infinity) and cell_neighbor[c][i] across the facet opposite vertex i. For a finite
/// cell, `center` is its circumcenter (local coordinates; NaN for a flat cell); for an infinite
/// cell, the unit outward normal of its hull facet.
struct Cells {
  std::vector<std::array<int, 4>> vertex;
  std::vector<std::array<int, 4>> neighbor;
  std::vector<Vector3d> center;
  std::vector<char> infinite;
  std::size_t size() const { return vertex.size(); }
};

Vector3d circumcenter(const Vector3d& a, const Vector3d& b0, const Vector3d& c0, const Vector3d& d0) {
  const Vector3d b = b0 - a, c = c0 - a, d = d0 - a;
  const double det = 2.0 * b.dot(c.cross(d));
  const Vector3d num = b.squaredNorm() * c.cross(d) + c.squaredNorm() * d.cross(b) + d.squaredNorm() * b.cross(c);
  if (det == 0.0) return Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  return a + num / det;
}

/// Where a Voronoi edge end lies relative to the double cone of half-angle 90 - theta around the
/// pole vector at p: +1 inside the upper cone, -1 inside the lower cone, 0 in the cocone.
int cone_side(const Vector3d& direction, const Vector3d& pole, double sin_theta) {
  const double len = direction.norm();
  if (!(len > 0.0) || !std::isfinite(len)) return 0;
  const double c = direction.dot(pole) / len;
  if (c > sin_theta) return 1;
  if (c < -sin_theta) return -1;
  return 0;
}

std::uint64_t edge_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
}

/// Candidate triangles with their edge incidences (CSR: edge e has triangles
/// edge_tris[edge_start[e] .. edge_start[e+1])).
struct Complex {
  std::vector<std::array<int, 3>> tris;
  std::vector<std::array<int, 3>> tri_edges;  // edge id of (tris[t][k], tris[t][k + 1])
  std::vector<std::array<int, 2>> edge_verts;
  std::vector<std::size_t> edge_start;
  std::vector<int> edge_tris;
};

Complex build_complex(std::vector<std::array<int, 3>> tris) {
  Complex cx;
  cx.tris = std::move(tris);
  const std::size_t nt = cx.tris.size();
  std::vector<std::pair<std::uint64_t, std::uint32_t>> entries(3 * nt);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t t = r.begin(); t != r.end(); ++t)
      for (int k = 0; k < 3; ++k)
        entries[3 * t + k] = {edge_key(cx.tris[t][k], cx.tris[t][(k + 1) % 3]), std::uint32_t(3 * t + k)};
  });
  tbb::parallel_sort(entries.begin(), entries.end());
  cx.tri_edges.resize(nt);
  cx.edge_tris.resize(3 * nt);
  cx.edge_start.reserve(3 * nt / 2 + 2);
  for (std::size_t i = 0; i < entries.size(); ++i) {
    if (i == 0 || entries[i].first != entries[i - 1].first) {
      cx.edge_start.push_back(i);
      cx.edge_verts.push_back({int(entries[i].first >> 32), int(entries[i].first & 0xffffffffu)});
    }
    const std::uint32_t slot = entries[i].second;
    cx.edge_tris[i] = int(slot / 3);
    cx.tri_edges[slot / 3][slot % 3] = int(cx.edge_verts.size() - 1);
  }
  cx.edge_start.push_back(entries.size());
  return cx;
}

int third_vertex(const std::array<int, 3>& t, int a, int b) {
  for (int v : t)
    if (v != a && v != b) return v;
  return t[0];
}

/// Angles (radians, [0, 2 pi)) of the half-planes of `tris` around the edge a -> b, measured from
/// `reference` (a direction perpendicular-ish to the edge) towards axis x reference.
void edge_angles(const std::vector<Vector3d>& p, int a, int b, const Vector3d& reference, const int* tris,
                 std::size_t count, const Complex& cx, double* out) {
  const Vector3d axis = (p[b] - p[a]).normalized();
  Vector3d e1 = reference - reference.dot(axis) * axis;
  e1.normalize();
  const Vector3d e2 = axis.cross(e1);
  for (std::size_t i = 0; i < count; ++i) {
    const Vector3d w = p[third_vertex(cx.tris[tris[i]], a, b)] - p[a];
    double ang = std::atan2(w.dot(e2), w.dot(e1));
    if (ang < 0) ang += 2 * kPi;
    out[i] = ang;
  }
}

/// Repeatedly removes the triangles at sharp edges (see CrustParams::sharp_edge_angle_deg); when
/// `rim_is_sharp`, an edge with a single triangle is sharp too. Returns the number removed.
std::size_t prune_sharp(const Complex& cx, const std::vector<Vector3d>& p, std::vector<char>& alive,
                        double max_gap_rad, bool rim_is_sharp) {
  const std::size_t ne = cx.edge_verts.size();
  std::vector<int> queue(ne);
  std::iota(queue.begin(), queue.end(), 0);
  std::vector<char> queued(ne, 1);
  std::vector<int> live;
  std::vector<double> ang;
  std::size_t removed = 0;
  // FIFO over a growing vector: deterministic, each edge re-queued only when a triangle of it dies.
  for (std::size_t head = 0; head < queue.size(); ++head) {
    const int e = queue[head];
    queued[e] = 0;
    live.clear();
    for (std::size_t i = cx.edge_start[e]; i < cx.edge_start[e + 1]; ++i)
      if (alive[cx.edge_tris[i]]) live.push_back(cx.edge_tris[i]);
    if (live.empty()) continue;
    bool sharp = false;
    if (live.size() == 1) {
      sharp = rim_is_sharp;
    } else if (max_gap_rad < 2 * kPi) {
      const int a = cx.edge_verts[e][0], b = cx.edge_verts[e][1];
      const Vector3d ref = p[third_vertex(cx.tris[live[0]], a, b)] - p[a];
      ang.resize(live.size());
      edge_angles(p, a, b, ref, live.data(), live.size(), cx, ang.data());
      std::sort(ang.begin(), ang.end());
      double gap = 2 * kPi - (ang.back() - ang.front());
      for (std::size_t i = 1; i < ang.size(); ++i) gap = std::max(gap, ang[i] - ang[i - 1]);
      sharp = gap > max_gap_rad;
    }
    if (!sharp) continue;
    for (int t : live) {
      alive[t] = 0;
      ++removed;
      for (int k = 0; k < 3; ++k) {
        const int f = cx.tri_edges[t][k];
        if (!queued[f]) {
          queued[f] = 1;
          queue.push_back(f);
        }
      }
    }
  }
  return removed;
}

/// Connected components of the alive triangles (sharing an edge); -1 for dead triangles.
/// Components are numbered in the order of their smallest triangle index.
std::vector<int> components(const Complex& cx, const std::vector<char>& alive, int& count) {
  const std::size_t nt = cx.tris.size();
  std::vector<int> comp(nt, -1);
  std::vector<int> stack;
  count = 0;
  for (std::size_t s = 0; s < nt; ++s) {
    if (!alive[s] || comp[s] >= 0) continue;
    comp[s] = count;
    stack.push_back(int(s));
    while (!stack.empty()) {
      const int t = stack.back();
      stack.pop_back();
      for (int k = 0; k < 3; ++k) {
        const int e = cx.tri_edges[t][k];
        for (std::size_t i = cx.edge_start[e]; i < cx.edge_start[e + 1]; ++i) {
          const int u = cx.edge_tris[i];
          if (alive[u] && comp[u] < 0) {
            comp[u] = count;
            stack.push_back(u);
          }
        }
      }
    }
    ++count;
  }
  return comp;
}

}  // namespace

void CrustParams::validate() const {
  const CrustParams& params = *this;
  if (!(params.cocone_angle_deg > 0.0 && params.cocone_angle_deg < 90.0))
    throw UsageError(fmt::format("crust: cocone_angle_deg = {}, expected a value in (0, 90)", params.cocone_angle_deg));
  if (!(params.normal_filter_angle_deg > 0.0 && params.normal_filter_angle_deg <= 90.0))
    throw UsageError(fmt::format("crust: normal_filter_angle_deg = {}, expected a value in (0, 90]",
                                 params.normal_filter_angle_deg));
  if (!(params.sharp_edge_angle_deg >= 180.0 && params.sharp_edge_angle_deg <= 360.0))
    throw UsageError(fmt::format("crust: sharp_edge_angle_deg = {}, expected a value in [180, 360]",
                                 params.sharp_edge_angle_deg));
  if (!(params.max_boundary_edge_in_spacings >= 0.0) || !std::isfinite(params.max_boundary_edge_in_spacings))
    throw UsageError(fmt::format("crust: max_boundary_edge_in_spacings = {}, expected a finite value >= 0 (0: off)",
                                 params.max_boundary_edge_in_spacings));
  if (params.max_hole_edges < 0)
    throw UsageError(fmt::format("crust: max_hole_edges = {}, expected a value >= 0 (0: off)", params.max_hole_edges));
}

namespace {

}  // namespace

ReconstructionResult reconstruct_crust(const PointCloud& cloud, const CrustParams& params,
                                       const ProgressCallback& progress, CrustStats* stats_out) {
  const auto t_start = Clock::now();
  params.validate();
  cloud.validate();
  const std::size_t n = cloud.size();
  if (n < 4) throw UsageError(fmt::format("crust: the cloud has {} points, expected at least 4", n));
  if (n > std::size_t(std::numeric_limits<int>::max() / 4))
    throw UsageError(fmt::format("crust: the cloud has {} points, expected at most {}", n,
                                 std::numeric_limits<int>::max() / 4));
  for (std::size_t i = 0; i < n; ++i)
    if (!cloud.positions[i].allFinite())
      throw InputError(fmt::format("crust: point {} has a non-finite coordinate, expected finite x, y, z", i));

  CrustStats stats;
  stats.input_points = n;
  detail::ProgressReporter reporter(progress, 0.0, 1.0, 1);
  reporter.report(0.0);
  reporter.throw_if_cancelled();

  // Local origin: the bounding-box centre, so that georeferenced coordinates keep their precision.
  const BoundingBox box = bounding_box(cloud.positions);
  const Vector3d origin = box.center();
  std::vector<Vector3d> p(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) p[i] = cloud.positions[i] - origin;
  });

  const KdTree tree(p);
  const double spacing = mean_spacing(tree);
  const auto order = tree.spatial_order();

  // 1. Delaunay triangulation (CGAL spatially sorts the points before inserting them).
  Cells cells;
  std::vector<int> rep(n, -1);  // input index -> vertex present in the triangulation (itself unless a duplicate)
  {
    const auto t0 = Clock::now();
    std::vector<std::pair<K::Point_3, int>> input(n);
    for (std::size_t i = 0; i < n; ++i) input[i] = {K::Point_3(p[i].x(), p[i].y(), p[i].z()), int(i)};
#ifdef POINTSURF_PARALLEL_DELAUNAY
    const BoundingBox local = bounding_box(p);
    const Vector3d pad = Vector3d::Constant(1e-6 * std::max(local.diagonal(), 1e-300));
    Delaunay::Lock_data_structure locks(CGAL::Bbox_3(local.min.x() - pad.x(), local.min.y() - pad.y(),
                                                      local.min.z() - pad.z(), local.max.x() + pad.x(),
                                                      local.max.y() + pad.y(), local.max.z() + pad.z()),
                                        50);
    Delaunay dt(input.begin(), input.end(), &locks);
#else
    Delaunay dt(input.begin(), input.end());  // spatially sorted range insertion
#endif
    input = {};
    stats.seconds_delaunay = seconds_since(t0);
    reporter.report(0.45);
    reporter.throw_if_cancelled();
    if (dt.dimension() < 3) {
      const char* what = dt.dimension() == 2 ? "coplanar" : dt.dimension() == 1 ? "collinear" : "identical";
      throw ComputeError(fmt::format(
          "crust: all {} points are {} (Delaunay dimension {}), expected points spread in 3D; use ball pivoting "
          "for a planar patch",
          n, what, dt.dimension()));
    }
    stats.duplicate_points = n - dt.number_of_vertices();
    if (stats.duplicate_points > 0) {
      // Which copy of a duplicate the triangulation keeps depends on the insertion order: keep
      // the one of smallest index instead (the later copies are the unused ones).
      std::vector<char> present(n, 0);
      for (auto v = dt.finite_vertices_begin(); v != dt.finite_vertices_end(); ++v) present[v->info()] = 1;
      for (std::size_t i = 0; i < n; ++i)
        if (!present[i]) {
          const auto v = dt.nearest_vertex(K::Point_3(p[i].x(), p[i].y(), p[i].z()));
          if (int(i) < v->info()) v->info() = int(i);
        }
    }
    for (auto v = dt.finite_vertices_begin(); v != dt.finite_vertices_end(); ++v) rep[v->info()] = v->info();
    if (stats.duplicate_points > 0) {
      for (std::size_t i = 0; i < n; ++i)
        if (rep[i] < 0) {
          const auto v = dt.nearest_vertex(K::Point_3(p[i].x(), p[i].y(), p[i].z()));
          rep[i] = v->info();
        }
    }
    const std::size_t nc = dt.tds().number_of_cells();
    cells.vertex.resize(nc);
    cells.neighbor.resize(nc);
    cells.center.resize(nc);
    cells.infinite.resize(nc);
    // Number the cells in the order of their sorted vertex indices, whatever order the (parallel)
    // insertion left them in.
    {
      std::vector<std::pair<std::array<int, 4>, Delaunay::Cell_handle>> order_cells;
      order_cells.reserve(nc);
      for (auto c = dt.all_cells_begin(); c != dt.all_cells_end(); ++c) {
        std::array<int, 4> key;
        for (int i = 0; i < 4; ++i) key[i] = dt.is_infinite(c->vertex(i)) ? kInfinite : c->vertex(i)->info();
        std::sort(key.begin(), key.end());
        order_cells.emplace_back(key, c);
      }
      tbb::parallel_sort(order_cells.begin(), order_cells.end(),
                         [](const auto& x, const auto& y) { return x.first < y.first; });
      for (std::size_t i = 0; i < nc; ++i) order_cells[i].second->info() = int(i);
    }
    for (auto c = dt.all_cells_begin(); c != dt.all_cells_end(); ++c) {
      const int ci = c->info();
      for (int i = 0; i < 4; ++i) {
        const auto v = c->vertex(i);
        cells.vertex[ci][i] = dt.is_infinite(v) ? kInfinite : v->info();
        cells.neighbor[ci][i] = c->neighbor(i)->info();
      }
      cells.infinite[ci] = dt.is_infinite(c) ? 1 : 0;
    }
    stats.delaunay_cells = dt.number_of_finite_cells();
  }  // the CGAL triangulation is freed here
  const std::size_t nc = cells.size();

  // Circumcenters of finite cells; outward hull normals of infinite cells.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nc), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t c = r.begin(); c != r.end(); ++c) {
      const auto& v = cells.vertex[c];
      if (!cells.infinite[c]) {
        std::array<int, 4> s = v;  // sorted, so that rounding does not depend on the vertex order
        std::sort(s.begin(), s.end());
        cells.center[c] = circumcenter(p[s[0]], p[s[1]], p[s[2]], p[s[3]]);
        continue;
      }
      int k = 0;
      while (v[k] != kInfinite) ++k;
      std::array<int, 3> f{v[(k + 1) % 4], v[(k + 2) % 4], v[(k + 3) % 4]};
      std::sort(f.begin(), f.end());
      const Vector3d& a = p[f[0]];
      const Vector3d& b = p[f[1]];
      const Vector3d& d = p[f[2]];
      Vector3d normal = (b - a).cross(d - a);
      const auto& inner = cells.vertex[cells.neighbor[c][k]];
      int opposite = inner[0];
      for (int w : inner)
        if (w != v[(k + 1) % 4] && w != v[(k + 2) % 4] && w != v[(k + 3) % 4]) opposite = w;
      if (normal.dot(p[opposite] - a) > 0) normal = -normal;
      const double len = normal.norm();
      cells.center[c] = len > 0 ? Vector3d(normal / len) : Vector3d::Zero();
    }
  });
  reporter.report(0.5);
  reporter.throw_if_cancelled();

  // 2. Poles. Vertex -> incident cells (CSR), then per point in the tree's spatial order.
  std::vector<std::size_t> vc_start(n + 1, 0);
  for (std::size_t c = 0; c < nc; ++c)
    for (int v : cells.vertex[c])
      if (v != kInfinite) ++vc_start[v + 1];
  for (std::size_t i = 0; i < n; ++i) vc_start[i + 1] += vc_start[i];
  std::vector<int> vc(vc_start[n]);
  {
    std::vector<std::size_t> fill(vc_start.begin(), vc_start.end() - 1);
    for (std::size_t c = 0; c < nc; ++c)
      for (int v : cells.vertex[c])
        if (v != kInfinite) vc[fill[v]++] = int(c);
  }
  std::vector<Vector3d> pole(n, Vector3d::Zero());        // unit normal axis (zero: none)
  std::vector<Vector3d> hull_normal(n, Vector3d::Zero());  // unit mean outward hull normal (hull samples)
  std::vector<char> on_hull(n, 0), finite_pole(n, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<Neighbor> near;  // one per chunk, reused by its points
    for (std::size_t o = r.begin(); o != r.end(); ++o) {
      const std::uint32_t i = order[o];
      if (rep[i] != int(i)) continue;
      Vector3d hull = Vector3d::Zero();
      Vector3d far = Vector3d::Zero();
      double far2 = -1.0;
      bool hull_point = false;
      for (std::size_t j = vc_start[i]; j < vc_start[i + 1]; ++j) {
        const int c = vc[j];
        if (cells.infinite[c]) {
          hull += cells.center[c];
          hull_point = true;
        } else if (cells.center[c].allFinite()) {
          const Vector3d d = cells.center[c] - p[i];
          const double d2 = d.squaredNorm();
          if (d2 > far2) {
            far2 = d2;
            far = d;
          }
        }
      }
      on_hull[i] = hull_point ? 1 : 0;
      if (hull_point) {
        // The Voronoi cell is unbounded, so the pole is at infinity. Its direction, the mean
        // outward normal of the hull facets, is the surface normal on a closed surface but lies
        // sideways at the rim of an open one (where it would let vertical "curtain" triangles
        // through). The axis is therefore the normal of the plane fitted to the nearest samples,
        // signed by the hull normal, which still serves to orient pieces.
        const double h = hull.norm();
        if (h > 1e-6) hull_normal[i] = hull / h;
        tree.knn(p[i], kAxisNeighbours, near);
        Vector3d mean = Vector3d::Zero();
        for (const Neighbor& nb : near) mean += p[nb.index];
        mean /= double(near.size());
        Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
        for (const Neighbor& nb : near) {
          const Vector3d d = p[nb.index] - mean;
          cov += d * d.transpose();
        }
        const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
        Vector3d axis = eig.eigenvectors().col(0);
        if (eig.eigenvalues()(1) > 0.0 && axis.allFinite()) {
          if (axis.dot(hull_normal[i]) < 0.0) axis = -axis;
          pole[i] = axis.normalized();
        } else {
          pole[i] = hull_normal[i];
        }
      } else if (far2 > 0.0) {
        pole[i] = far.normalized();
        finite_pole[i] = 1;
      }
    }
  });
  stats.hull_points = std::size_t(std::count(on_hull.begin(), on_hull.end(), char(1)));
  reporter.report(0.55);
  reporter.throw_if_cancelled();

  // 3. Cocone test and normal filter, per Delaunay facet (visited from its lower-numbered cell).
  const double sin_theta = std::sin(params.cocone_angle_deg * kPi / 180.0);
  const double cos_filter = std::cos(params.normal_filter_angle_deg * kPi / 180.0);
  std::vector<std::uint8_t> facet_flags(nc, 0);  // bit i: facet i kept; bit 4+i: removed by normal filter
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nc), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t c = r.begin(); c != r.end(); ++c) {
      const auto& v = cells.vertex[c];
      std::uint8_t flags = 0;
      for (int i = 0; i < 4; ++i) {
        const std::size_t other = std::size_t(cells.neighbor[c][i]);
        if (other < c) continue;
        if (cells.infinite[c] && cells.infinite[other]) continue;
        const int a = v[(i + 1) % 4], b = v[(i + 2) % 4], d = v[(i + 3) % 4];
        if (a == kInfinite || b == kInfinite || d == kInfinite) continue;
        bool keep = true;
        for (int q : {a, b, d}) {
          int side[2];
          const std::size_t ends[2] = {c, other};
          for (int e = 0; e < 2; ++e) {
            const std::size_t cell = ends[e];
            // a finite end is a circumcenter; an infinite end is the far end of a ray along the
            // hull normal, seen from p in that direction.
            const Vector3d dir = cells.infinite[cell] ? cells.center[cell] : Vector3d(cells.center[cell] - p[q]);
            side[e] = cone_side(dir, pole[q], sin_theta);
          }
          if (side[0] != 0 && side[1] != 0 && side[0] == side[1]) {
            keep = false;
            break;
          }
        }
        if (!keep) continue;
        Vector3d normal = (p[b] - p[a]).cross(p[d] - p[a]);
        const double len = normal.norm();
        bool filtered = !(len > 0.0);
        if (!filtered && cos_filter > 0.0) {
          normal /= len;
          for (int q : {a, b, d})
            if (pole[q] != Vector3d::Zero() && std::abs(normal.dot(pole[q])) < cos_filter) filtered = true;
        }
        flags |= std::uint8_t(filtered ? (16u << i) : (1u << i));
      }
      facet_flags[c] = flags;
    }
  });
  std::vector<std::array<int, 3>> candidates;
  for (std::size_t c = 0; c < nc; ++c) {
    const std::uint8_t f = facet_flags[c];
    if (f == 0) continue;
    for (int i = 0; i < 4; ++i) {
      if (f & (16u << i)) ++stats.cocone_triangles, ++stats.normal_filtered;
      if (f & (1u << i)) {
        ++stats.cocone_triangles;
        const auto& v = cells.vertex[c];
        std::array<int, 3> tri{v[(i + 1) % 4], v[(i + 2) % 4], v[(i + 3) % 4]};
        std::sort(tri.begin(), tri.end());
        candidates.push_back(tri);
      }
    }
  }
  cells = {};
  vc = {};
  vc_start = {};
  facet_flags = {};
  reporter.report(0.7);
  reporter.throw_if_cancelled();

  // 4a. Sharp-edge pruning.
  const Complex cx = build_complex(std::move(candidates));
  const std::size_t nt = cx.tris.size();
  const double max_gap = params.sharp_edge_angle_deg * kPi / 180.0;
  std::vector<char> alive(nt, 1);
  if (params.boundary == CrustBoundary::Closed) {
    stats.pruned = prune_sharp(cx, p, alive, max_gap, true);
  } else {
    stats.pruned = prune_sharp(cx, p, alive, max_gap, false);
    if (params.boundary == CrustBoundary::Auto) {
      std::vector<char> closed = alive;
      prune_sharp(cx, p, closed, max_gap, true);
      int count = 0;
      const std::vector<int> comp = components(cx, alive, count);
      std::vector<std::size_t> open_count(count, 0), closed_count(count, 0);
      for (std::size_t t = 0; t < nt; ++t)
        if (alive[t]) {
          ++open_count[comp[t]];
          if (closed[t]) ++closed_count[comp[t]];
        }
      std::vector<char> use_closed(count, 0);
      for (int k = 0; k < count; ++k) {
        use_closed[k] = 2 * closed_count[k] >= open_count[k] ? 1 : 0;
        ++(use_closed[k] ? stats.closed_pieces : stats.open_pieces);
      }
      for (std::size_t t = 0; t < nt; ++t)
        if (alive[t] && use_closed[comp[t]] && !closed[t]) {
          alive[t] = 0;
          ++stats.pruned;
        }
    }
  }
  reporter.report(0.8);
  reporter.throw_if_cancelled();

  // 4b. Manifold walk over each connected piece, from a seed on its outer side.
  int piece_count = 0;
  const std::vector<int> piece = components(cx, alive, piece_count);
  if (params.boundary == CrustBoundary::Closed) stats.closed_pieces = std::size_t(piece_count);
  if (params.boundary == CrustBoundary::Open) stats.open_pieces = std::size_t(piece_count);
  std::vector<std::size_t> piece_start(std::size_t(piece_count) + 1, 0);
  for (std::size_t t = 0; t < nt; ++t)
    if (piece[t] >= 0) ++piece_start[piece[t] + 1];
  for (int k = 0; k < piece_count; ++k) piece_start[k + 1] += piece_start[k];
  std::vector<int> piece_tris(piece_start[piece_count]);
  {
    std::vector<std::size_t> fill(piece_start.begin(), piece_start.end() - 1);
    for (std::size_t t = 0; t < nt; ++t)
      if (piece[t] >= 0) piece_tris[fill[piece[t]]++] = int(t);
  }

  const std::size_t ne = cx.edge_verts.size();
  std::vector<std::array<int, 2>> edge_used(ne, {-1, -1});  // accepted triangles per edge
  std::vector<std::array<int, 3>> oriented(nt);
  std::vector<std::int8_t> state(nt, 0);  // 0 untried, 1 accepted, -1 rejected
  std::vector<int> bfs;
  std::vector<double> ang;
  std::vector<int> live;
  std::vector<std::size_t> rank;
  std::vector<Triangle> out_tris;
  std::vector<int> out_piece;
  std::vector<int> out_src;  // candidate triangle of each output triangle

  // Accepts `tri` (oriented) if each of its edges has a free slot and, when already used once, is
  // traversed the other way by that triangle.
  auto directed = [&](int t, int a, int b) {
    const auto& o = oriented[t];
    for (int k = 0; k < 3; ++k)
      if (o[k] == a && o[(k + 1) % 3] == b) return true;
    return false;
  };
  auto try_accept = [&](int t, const std::array<int, 3>& o) {
    oriented[t] = o;
    for (int k = 0; k < 3; ++k) {
      const int a = o[k], b = o[(k + 1) % 3];
      int e = -1;
      for (int j = 0; j < 3; ++j)
        if (cx.edge_verts[cx.tri_edges[t][j]] == std::array<int, 2>{std::min(a, b), std::max(a, b)}) e = cx.tri_edges[t][j];
      const auto& used = edge_used[e];
      if (used[1] >= 0) return false;
      if (used[0] >= 0 && directed(used[0], a, b)) return false;
    }
    for (int j = 0; j < 3; ++j) {
      auto& used = edge_used[cx.tri_edges[t][j]];
      (used[0] < 0 ? used[0] : used[1]) = t;
    }
    state[t] = 1;
    return true;
  };

  for (int k = 0; k < piece_count; ++k) {
    // Seed: at the piece's vertex of largest x, its triangle most facing +x, turned towards +x.
    int top = -1;
    for (std::size_t j = piece_start[k]; j < piece_start[k + 1]; ++j)
      for (int v : cx.tris[piece_tris[j]])
        if (top < 0 || p[v].x() > p[top].x() || (p[v].x() == p[top].x() && v < top)) top = v;
    int seed = -1;
    double best = -1.0;
    for (std::size_t j = piece_start[k]; j < piece_start[k + 1]; ++j) {
      const auto& t = cx.tris[piece_tris[j]];
      if (t[0] != top && t[1] != top && t[2] != top) continue;
      const Vector3d nrm = (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]);
      const double score = std::abs(nrm.x()) / std::max(nrm.norm(), 1e-300);
      if (score > best) best = score, seed = piece_tris[j];
    }
    std::array<int, 3> o = cx.tris[seed];
    if ((p[o[1]] - p[o[0]]).cross(p[o[2]] - p[o[0]]).x() < 0) std::swap(o[1], o[2]);
    if (!try_accept(seed, o)) continue;
    bfs.assign(1, seed);
    for (std::size_t head = 0; head < bfs.size(); ++head) {
      const int t = bfs[head];
      const std::array<int, 3> ot = oriented[t];
      out_tris.emplace_back(ot[0], ot[1], ot[2]);
      out_piece.push_back(k);
      out_src.push_back(t);
      for (int j = 0; j < 3; ++j) {
        const int a = ot[j], b = ot[(j + 1) % 3];
        int e = -1;
        for (int m = 0; m < 3; ++m)
          if (cx.edge_verts[cx.tri_edges[t][m]] == std::array<int, 2>{std::min(a, b), std::max(a, b)})
            e = cx.tri_edges[t][m];
        if (edge_used[e][1] >= 0) continue;
        live.clear();
        for (std::size_t i = cx.edge_start[e]; i < cx.edge_start[e + 1]; ++i) {
          const int u = cx.edge_tris[i];
          if (u != t && alive[u]) live.push_back(u);
        }
        if (live.empty()) continue;
        // The first triangle met turning around a -> b from t towards t's outer (normal) side:
        // with e1 along t's half-plane and e2 = axis x e1 = the normal side, the smallest angle.
        ang.resize(live.size());
        edge_angles(p, a, b, p[ot[(j + 2) % 3]] - p[a], live.data(), live.size(), cx, ang.data());
        // edge_angles measures towards axis x e1; t's normal is along (b - a) x (c - a), the
        // same side, so the smallest angle is the outer neighbour.
        // If the outer neighbour cannot join (one of its other edges is taken, or it would be
        // traversed the wrong way), the next ones in angular order are tried, so that a conflict
        // far away does not leave a hole here; try_accept keeps the result edge-manifold and
        // oriented whichever one joins.
        rank.resize(live.size());
        std::iota(rank.begin(), rank.end(), std::size_t{0});
        std::sort(rank.begin(), rank.end(), [&](std::size_t x, std::size_t y) {
          return ang[x] < ang[y] || (ang[x] == ang[y] && live[x] < live[y]);
        });
        for (std::size_t i : rank) {
          const int s = live[i];
          if (state[s] == 1) break;
          if (state[s] == -1) continue;
          const int d = third_vertex(cx.tris[s], a, b);
          if (try_accept(s, {b, a, d})) {
            bfs.push_back(s);
            break;
          }
          state[s] = -1;
        }
      }
    }
  }
  stats.walk_dropped = 0;
  for (std::size_t t = 0; t < nt; ++t)
    if (alive[t] && state[t] != 1) ++stats.walk_dropped;

  // 4c. Rim peeling. Where an open surface's rim is concave, the Delaunay triangulation fills it
  // with long thin triangles that pass the cocone test (they lie in the surface); they are peeled
  // from the boundary inward while their boundary edge is too long. Closed pieces have no boundary
  // edge and are untouched.
  if (params.max_boundary_edge_in_spacings > 0.0 && !out_tris.empty()) {
    const double max_len2 = std::pow(params.max_boundary_edge_in_spacings * spacing, 2);
    std::vector<int> out_of(nt, -1);  // candidate -> output triangle
    for (std::size_t j = 0; j < out_src.size(); ++j) out_of[out_src[j]] = int(j);
    std::vector<char> keep(out_tris.size(), 1);
    auto edge_len2 = [&](int e) { return (p[cx.edge_verts[e][0]] - p[cx.edge_verts[e][1]]).squaredNorm(); };
    auto other_on = [&](int e, int t) { return edge_used[e][0] == t ? edge_used[e][1] : edge_used[e][0]; };
    std::vector<int> peel;
    for (std::size_t j = 0; j < out_src.size(); ++j)
      for (int e : cx.tri_edges[out_src[j]])
        if (edge_used[e][1] < 0 && edge_len2(e) > max_len2) {
          peel.push_back(int(j));
          break;
        }
    while (!peel.empty()) {
      const int j = peel.back();
      peel.pop_back();
      if (!keep[j]) continue;
      keep[j] = 0;
      ++stats.rim_peeled;
      const int t = out_src[j];
      for (int e : cx.tri_edges[t]) {
        const int u = other_on(e, t);
        edge_used[e] = {u, -1};
        if (u >= 0 && keep[out_of[u]] && edge_len2(e) > max_len2) peel.push_back(out_of[u]);
      }
    }
    std::size_t w = 0;
    for (std::size_t j = 0; j < out_tris.size(); ++j)
      if (keep[j]) {
        out_tris[w] = out_tris[j];
        out_piece[w] = out_piece[j];
        out_src[w] = out_src[j];
        ++w;
      }
    out_tris.resize(w);
    out_piece.resize(w);
    out_src.resize(w);
  }
  reporter.report(0.9);
  reporter.throw_if_cancelled();

  // 5. Orientation of each piece, then vertex normals.
  const bool has_normals = cloud.has_normals();
  std::vector<std::size_t> start(std::size_t(piece_count) + 1, 0);
  for (int k : out_piece) ++start[k + 1];
  for (int k = 0; k < piece_count; ++k) start[k + 1] += start[k];
  // out_tris is grouped by piece (pieces are walked one after another).
  std::vector<char> flip(std::size_t(piece_count), 0);
  tbb::parallel_for(0, piece_count, [&](int k) {
    if (start[k] == start[k + 1]) return;
    double score = 0.0;
    if (has_normals) {
      for (std::size_t j = start[k]; j < start[k + 1]; ++j) {
        const Triangle& t = out_tris[j];
        const Vector3d nrm = (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]);
        score += nrm.dot(cloud.normals[t[0]] + cloud.normals[t[1]] + cloud.normals[t[2]]);
      }
    } else {
      // Closed: signed volume. Open: agreement with the hull pole vectors (outward by
      // construction) when they decide, else facing away from the piece's centroid.
      bool closed = true;
      Vector3d centroid = Vector3d::Zero();
      for (std::size_t j = start[k]; j < start[k + 1]; ++j) {
        const Triangle& t = out_tris[j];
        centroid += (p[t[0]] + p[t[1]] + p[t[2]]) / 3.0;
        for (int e : cx.tri_edges[out_src[j]])
          if (edge_used[e][1] < 0) closed = false;
      }
      centroid /= double(start[k + 1] - start[k]);
      double volume = 0.0, hull_score = 0.0, hull_abs = 0.0, centroid_score = 0.0;
      for (std::size_t j = start[k]; j < start[k + 1]; ++j) {
        const Triangle& t = out_tris[j];
        const Vector3d a = p[t[0]] - centroid, b = p[t[1]] - centroid, c = p[t[2]] - centroid;
        const Vector3d nrm = (b - a).cross(c - a);
        volume += a.dot(b.cross(c));
        centroid_score += nrm.dot(a + b + c);
        for (int m = 0; m < 3; ++m)
          if (on_hull[t[m]]) {
            hull_score += nrm.dot(hull_normal[t[m]]);
            hull_abs += std::abs(nrm.dot(hull_normal[t[m]]));
          }
      }
      if (closed)
        score = volume;
      else if (std::abs(hull_score) > 0.2 * hull_abs)
        score = hull_score;
      else
        score = centroid_score;
    }
    flip[k] = score < 0.0 ? 1 : 0;
  });
  for (std::size_t j = 0; j < out_tris.size(); ++j)
    if (flip[out_piece[j]]) std::swap(out_tris[j][1], out_tris[j][2]);
  stats.flipped_pieces = std::size_t(std::count(flip.begin(), flip.end(), char(1)));

  // 6. Small holes. Undersampled spots (random samples, thin parts) leave holes of a few edges
  // where the cocone test missed a triangle or the walk met a conflict; each boundary loop of at
  // most `max_hole_edges` edges is closed by ear clipping (shortest new edge first) with triangles
  // of existing samples, as long as no new edge already exists in the mesh. Loops through a
  // vertex with several boundary edges, and loops of small pieces (which would fold shut), are
  // left open.
  if (params.max_hole_edges >= 3 && !out_tris.empty()) {
    auto directed_key = [](int a, int b) { return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b); };
    std::vector<std::uint64_t> half(3 * out_tris.size());
    for (std::size_t j = 0; j < out_tris.size(); ++j)
      for (int k = 0; k < 3; ++k) half[3 * j + k] = directed_key(out_tris[j][k], out_tris[j][(k + 1) % 3]);
    tbb::parallel_sort(half.begin(), half.end());
    std::vector<std::uint64_t> added;  // directed edges of fill triangles (few), kept sorted
    auto has_half = [&](int a, int b) {
      const std::uint64_t key = directed_key(a, b);
      return std::binary_search(half.begin(), half.end(), key) || std::binary_search(added.begin(), added.end(), key);
    };
    auto has_edge = [&](int a, int b) { return has_half(a, b) || has_half(b, a); };
    // Boundary half-edges a -> b (no b -> a), and the number leaving each vertex.
    std::vector<std::pair<int, int>> rim;
    for (std::uint64_t key : half) {
      const int a = int(key >> 32), b = int(key & 0xffffffffu);
      if (!std::binary_search(half.begin(), half.end(), directed_key(b, a))) rim.emplace_back(a, b);
    }
    std::sort(rim.begin(), rim.end());
    std::vector<std::size_t> piece_size(std::size_t(piece_count), 0);
    std::vector<int> piece_of_vertex(n, -1);
    for (std::size_t j = 0; j < out_tris.size(); ++j) {
      ++piece_size[out_piece[j]];
      for (int k = 0; k < 3; ++k) piece_of_vertex[out_tris[j][k]] = out_piece[j];
    }
    const std::size_t min_piece = 8 * std::size_t(params.max_hole_edges);
    std::vector<char> rim_done(rim.size(), 0);
    std::vector<int> loop, poly;
    auto next_rim = [&](int a) -> long {  // the one boundary half-edge leaving a, or -1
      const auto lo = std::lower_bound(rim.begin(), rim.end(), std::make_pair(a, std::numeric_limits<int>::min()));
      if (lo == rim.end() || lo->first != a) return -1;
      if (lo + 1 != rim.end() && (lo + 1)->first == a) return -1;
      return long(lo - rim.begin());
    };
    for (std::size_t start = 0; start < rim.size(); ++start) {
      if (rim_done[start]) continue;
      loop.clear();
      bool ok = true;
      long h = long(start);
      while (true) {
        if (rim_done[h]) {
          ok = h == long(start) && loop.size() >= 3;
          break;
        }
        rim_done[h] = 1;
        loop.push_back(rim[h].first);
        h = next_rim(rim[h].second);
        if (h < 0 || loop.size() > std::size_t(params.max_hole_edges)) {
          ok = false;
          break;
        }
      }
      if (!ok) continue;
      const int owner = piece_of_vertex[loop[0]];
      if (owner < 0 || piece_size[owner] < min_piece) continue;
      // The fill runs against the loop: polygon = loop reversed, clipped ear by ear.
      poly.assign(loop.rbegin(), loop.rend());
      std::vector<Triangle> fill_tris;
      while (poly.size() > 3) {
        std::size_t best = poly.size();
        double best_len = std::numeric_limits<double>::infinity();
        for (std::size_t j = 0; j < poly.size(); ++j) {
          const int a = poly[(j + poly.size() - 1) % poly.size()], c = poly[(j + 1) % poly.size()];
          if (has_edge(a, c)) continue;
          const double len = (p[a] - p[c]).squaredNorm();
          if (len < best_len) best_len = len, best = j;
        }
        if (best == poly.size()) break;
        const std::size_t m = poly.size();
        const int a = poly[(best + m - 1) % m], b = poly[best], c = poly[(best + 1) % m];
        fill_tris.emplace_back(a, b, c);
        added.insert(std::upper_bound(added.begin(), added.end(), directed_key(c, a)), directed_key(c, a));
        added.insert(std::upper_bound(added.begin(), added.end(), directed_key(a, c)), directed_key(a, c));
        poly.erase(poly.begin() + std::ptrdiff_t(best));
      }
      if (poly.size() != 3) continue;  // (the diagonals added above only block later fills)
      fill_tris.emplace_back(poly[0], poly[1], poly[2]);
      ++stats.holes_filled;
      for (const Triangle& t : fill_tris) {
        out_tris.push_back(t);
        out_piece.push_back(owner);
      }
    }
  }

  ReconstructionResult result;
  result.mean_spacing = spacing;
  if (!has_normals) {
    // Area-weighted face normals per vertex decide the sign of each pole vector; samples without
    // a finite pole (hull samples) take the face normal itself when they have triangles.
    std::vector<Vector3d> face_sum(n, Vector3d::Zero());
    for (const Triangle& t : out_tris) {
      const Vector3d nrm = (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]);
      for (int m = 0; m < 3; ++m) face_sum[t[m]] += nrm;
    }
    std::vector<Vector3d> normals(n, Vector3d::Zero());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) {
        const int v = rep[i];
        Vector3d nrm = pole[v];
        const double f = face_sum[v].norm();
        if (!finite_pole[v] && f > 0.0)
          nrm = face_sum[v] / f;
        else if (f > 0.0 && nrm.dot(face_sum[v]) < 0.0)
          nrm = -nrm;
        normals[i] = nrm;
      }
    });
    PointCloud copy = cloud;
    copy.normals = std::move(normals);
    result.mesh = TriangleMesh::from_cloud(std::move(copy), std::move(out_tris));
  } else {
    result.mesh = TriangleMesh::from_cloud(cloud, std::move(out_tris));
  }
  result.topology = analyze_topology(result.mesh);
  result.unused_points = result.topology.isolated_vertices;
  reporter.report(1.0);
  reporter.throw_if_cancelled();
  stats.seconds_total = seconds_since(t_start);
  if (stats_out) *stats_out = stats;
  return result;
}

}  // namespace pointsurf
