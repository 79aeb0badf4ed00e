// SPDX-License-Identifier: GPL-3.0-or-later
// Voronoi poles from the Delaunay cells (spatial/detail/delaunay_3.h): no CGAL here.
#include "pointsurf/spatial/voronoi_poles.h"

#include <algorithm>
#include <cstdint>
#include <limits>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "pointsurf/core/error.h"
#include "pointsurf/spatial/kd_tree.h"
#include "spatial/detail/delaunay_3.h"

namespace pointsurf {
namespace detail {
namespace {

constexpr std::size_t kAxisNeighbours = 10;  // samples in the plane fit that gives hull samples their axis
const Vector3d kNoPole = Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());

}  // namespace

PoleSet voronoi_poles(const DelaunayCells& cells, const std::vector<Vector3d>& p, const KdTree& tree) {
  const std::size_t n = p.size(), nc = cells.size();
  // Vertex -> incident cells (CSR).
  std::vector<std::size_t> vc_start(n + 1, 0);
  for (std::size_t c = 0; c < nc; ++c)
    for (int v : cells.vertex[c])
      if (v != kInfiniteVertex) ++vc_start[std::size_t(v) + 1];
  for (std::size_t i = 0; i < n; ++i) vc_start[i + 1] += vc_start[i];
  std::vector<int> vc(vc_start[n]);
  {
    std::vector<std::size_t> fill(vc_start.begin(), vc_start.end() - 1);
    for (std::size_t c = 0; c < nc; ++c)
      for (int v : cells.vertex[c])
        if (v != kInfiniteVertex) vc[fill[std::size_t(v)]++] = int(c);
  }
  PoleSet poles;
  poles.axis.assign(n, Vector3d::Zero());
  poles.positive.assign(n, kNoPole);
  poles.negative.assign(n, kNoPole);
  poles.hull_normal.assign(n, Vector3d::Zero());
  poles.on_hull.assign(n, 0);
  poles.finite_pole.assign(n, 0);
  const auto order = tree.spatial_order();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<Neighbor> near;  // one per chunk, reused by its points
    for (std::size_t o = r.begin(); o != r.end(); ++o) {
      const std::uint32_t i = order[o];
      if (cells.representative[i] != int(i)) continue;
      Vector3d hull = Vector3d::Zero(), far = Vector3d::Zero();
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
      poles.on_hull[i] = hull_point ? 1 : 0;
      Vector3d axis = Vector3d::Zero();
      if (hull_point) {
        // The Voronoi cell is unbounded, so p+ is at infinity. Its direction, the mean outward
        // normal of the hull facets, is the surface normal on a closed surface but lies sideways
        // at the rim of an open one (where it would let vertical "curtain" triangles through).
        // The axis is therefore the normal of the plane fitted to the nearest samples, signed by
        // the hull normal, which still serves to orient pieces.
        const double h = hull.norm();
        if (h > 1e-6) poles.hull_normal[i] = hull / h;
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
        Vector3d fitted = eig.eigenvectors().col(0);
        if (eig.eigenvalues()(1) > 0.0 && fitted.allFinite()) {
          if (fitted.dot(poles.hull_normal[i]) < 0.0) fitted = -fitted;
          axis = fitted.normalized();
        } else {
          axis = poles.hull_normal[i];
        }
      } else if (far2 > 0.0) {
        axis = far.normalized();
        poles.positive[i] = p[i] + far;
        poles.finite_pole[i] = 1;
      }
      poles.axis[i] = axis;
      // p-: the farthest Voronoi vertex against the axis.
      double neg2 = -1.0;
      for (std::size_t j = vc_start[i]; j < vc_start[i + 1]; ++j) {
        const int c = vc[j];
        if (cells.infinite[c] || !cells.center[c].allFinite()) continue;
        const Vector3d d = cells.center[c] - p[i];
        if (!(d.dot(axis) < 0.0)) continue;
        const double d2 = d.squaredNorm();
        if (d2 > neg2) {
          neg2 = d2;
          poles.negative[i] = cells.center[c];
        }
      }
    }
  });
  poles.hull_points = std::size_t(std::count(poles.on_hull.begin(), poles.on_hull.end(), char(1)));
  return poles;
}

}  // namespace detail

VoronoiPoles voronoi_poles(std::span<const Vector3d> points) {
  const std::size_t n = points.size();
  if (n < 4) throw UsageError(fmt::format("voronoi_poles: {} points given, expected at least 4", n));
  for (std::size_t i = 0; i < n; ++i)
    if (!points[i].allFinite())
      throw InputError(fmt::format("voronoi_poles: point {} has a non-finite coordinate, expected finite x, y, z", i));
  const Vector3d origin = bounding_box(points).center();
  std::vector<Vector3d> p(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) p[i] = points[i] - origin;
  });
  const detail::DelaunayCells cells = detail::delaunay_cells(p);
  if (cells.dimension < 3)
    throw ComputeError(fmt::format("voronoi_poles: all {} points are {}, expected points spread in 3D", n,
                                   cells.dimension == 2 ? "coplanar" : cells.dimension == 1 ? "collinear" : "equal"));
  const KdTree tree(p);
  detail::PoleSet set = detail::voronoi_poles(cells, p, tree);
  VoronoiPoles out;
  out.positive = std::move(set.positive);
  out.negative = std::move(set.negative);
  out.axis = std::move(set.axis);
  out.on_hull = std::move(set.on_hull);
  for (Vector3d& v : out.positive) v += origin;  // NaN stays NaN
  for (Vector3d& v : out.negative) v += origin;
  out.hull_points = set.hull_points;
  out.duplicate_points = cells.duplicates;
  out.delaunay_cells = cells.finite_cells;
  return out;
}

}  // namespace pointsurf
