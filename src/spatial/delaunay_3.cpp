// SPDX-License-Identifier: GPL-3.0-or-later
// The 3D Delaunay triangulation copied into plain arrays (spatial/detail/delaunay_3.h). The only
// file of pointsurf that includes CGAL's Delaunay_triangulation_3.
#include "spatial/detail/delaunay_3.h"

#include <algorithm>
#include <limits>
#include <utility>

// CGAL's parallel Delaunay triangulation (oneTBB) is built when POINTSURF_PARALLEL_DELAUNAY is
// defined. It needs libtbbmalloc at link time (CGAL's concurrent containers use
// tbb::scalable_allocator), which the pointsurf target does not link by default. This is the
// only translation unit that includes CGAL's triangulation, so defining CGAL_LINKED_WITH_TBB here
// affects no other.
#if defined(POINTSURF_PARALLEL_DELAUNAY) && !defined(CGAL_LINKED_WITH_TBB)
#define CGAL_LINKED_WITH_TBB
#endif
#include <Eigen/Geometry>
#include <CGAL/Delaunay_triangulation_3.h>
#include <CGAL/Delaunay_triangulation_cell_base_3.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_cell_base_with_info_3.h>
#include <CGAL/Triangulation_data_structure_3.h>
#include <CGAL/Triangulation_vertex_base_with_info_3.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "pointsurf/core/point_cloud.h"

namespace pointsurf::detail {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_with_info_3<int, K>;
using Cb = CGAL::Triangulation_cell_base_with_info_3<int, K, CGAL::Delaunay_triangulation_cell_base_3<K>>;
// The triangulation itself does not depend on the insertion order (CGAL's symbolic perturbation
// settles cospherical points by a fixed rule); its cells are renumbered by their vertices below.
#ifdef POINTSURF_PARALLEL_DELAUNAY
using Tds = CGAL::Triangulation_data_structure_3<Vb, Cb, CGAL::Parallel_tag>;
#else
using Tds = CGAL::Triangulation_data_structure_3<Vb, Cb>;
#endif
using Delaunay = CGAL::Delaunay_triangulation_3<K, Tds>;

Vector3d circumcenter(const Vector3d& a, const Vector3d& b0, const Vector3d& c0, const Vector3d& d0) {
  const Vector3d b = b0 - a, c = c0 - a, d = d0 - a;
  const double det = 2.0 * b.dot(c.cross(d));
  const Vector3d num = b.squaredNorm() * c.cross(d) + c.squaredNorm() * d.cross(b) + d.squaredNorm() * b.cross(c);
  if (det == 0.0) return Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  return a + num / det;
}

K::Point_3 point_of(const Vector3d& v) { return K::Point_3(v.x(), v.y(), v.z()); }

}  // namespace

DelaunayCells delaunay_cells(const std::vector<Vector3d>& p) {
  const std::size_t n = p.size();
  DelaunayCells cells;
  cells.representative.assign(n, -1);
  {
    std::vector<std::pair<K::Point_3, int>> input(n);
    for (std::size_t i = 0; i < n; ++i) input[i] = {point_of(p[i]), int(i)};
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
    cells.dimension = dt.dimension();
    if (dt.dimension() < 3) return cells;
    cells.duplicates = n - dt.number_of_vertices();
    std::vector<int>& rep = cells.representative;
    if (cells.duplicates > 0) {
      // Which copy of a duplicate the triangulation keeps depends on the insertion order: keep
      // the one of smallest index instead (the later copies are the unused ones).
      std::vector<char> present(n, 0);
      for (auto v = dt.finite_vertices_begin(); v != dt.finite_vertices_end(); ++v) present[v->info()] = 1;
      for (std::size_t i = 0; i < n; ++i)
        if (!present[i]) {
          const auto v = dt.nearest_vertex(point_of(p[i]));
          if (int(i) < v->info()) v->info() = int(i);
        }
    }
    for (auto v = dt.finite_vertices_begin(); v != dt.finite_vertices_end(); ++v) rep[v->info()] = v->info();
    if (cells.duplicates > 0) {
      for (std::size_t i = 0; i < n; ++i)
        if (rep[i] < 0) rep[i] = dt.nearest_vertex(point_of(p[i]))->info();
    }
    const std::size_t nc = dt.tds().number_of_cells();
    cells.vertex.resize(nc);
    cells.neighbor.resize(nc);
    cells.center.resize(nc);
    cells.infinite.resize(nc);
    {
      std::vector<std::pair<std::array<int, 4>, Delaunay::Cell_handle>> order_cells;
      order_cells.reserve(nc);
      for (auto c = dt.all_cells_begin(); c != dt.all_cells_end(); ++c) {
        std::array<int, 4> key;
        for (int i = 0; i < 4; ++i) key[i] = dt.is_infinite(c->vertex(i)) ? kInfiniteVertex : c->vertex(i)->info();
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
        cells.vertex[ci][i] = dt.is_infinite(v) ? kInfiniteVertex : v->info();
        cells.neighbor[ci][i] = c->neighbor(i)->info();
      }
      cells.infinite[ci] = dt.is_infinite(c) ? 1 : 0;
    }
    cells.finite_cells = dt.number_of_finite_cells();
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
      while (v[k] != kInfiniteVertex) ++k;
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
  return cells;
}

}  // namespace pointsurf::detail
