// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/features/boundary_points.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <vector>

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/detail/local_pca.h"
#include "pointsurf/core/error.h"

namespace pointsurf {

const FieldTable<BoundaryParams>& BoundaryParams::fields() {
  static const FieldTable<BoundaryParams> table = [] {
    using P = BoundaryParams;
    FieldTable<P> t;
    t.integer("k", &P::k, "Neighbours per point of the angular-gap test").at_least(4).unit("points");
    t.number("min_gap_deg", &P::min_gap_deg, "A point is on the boundary when its neighbours leave a wider gap").unit("degrees").range(0.0, 360.0, true, true);
    return t;
  }();
  return table;
}

void BoundaryParams::validate() const {
  if (k < 4) throw UsageError(fmt::format("boundary points: k = {}, expected at least 4", k));
  if (!(min_gap_deg > 0.0 && min_gap_deg < 360.0))
    throw UsageError(fmt::format("boundary points: min_gap_deg = {}, expected a value in (0, 360)", min_gap_deg));
  fields().validate(*this, "detect_boundary_points");
}

BoundaryResult detect_boundary_points(const PointCloud& cloud, const BoundaryParams& params, const KdTree* tree) {
  params.validate();
  cloud.validate();
  const std::size_t n = cloud.size();
  BoundaryResult out;
  out.boundary.assign(n, 0);
  out.gap_deg.assign(n, 360.0);
  if (n == 0) return out;
  std::optional<KdTree> own;
  if (!tree) tree = &own.emplace(cloud.positions);
  const bool has_normals = cloud.has_normals();
  const auto order = tree->spatial_order();
  const double min_gap = params.min_gap_deg * std::numbers::pi / 180.0;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<Neighbor> near;
    std::vector<double> angle;
    for (std::size_t o = r.begin(); o != r.end(); ++o) {
      const std::uint32_t i = order[o];
      const Vector3d& x = cloud.positions[i];
      tree->knn(x, std::size_t(params.k) + 1, near);
      Vector3d normal = has_normals ? cloud.normals[i] : Vector3d::Zero();
      if (!(normal.squaredNorm() > 0.0)) {
        const detail::LocalPca pca = detail::local_pca([&](std::size_t j) { return Vector3d(cloud.positions[near[j].index] - x); }, near.size());
        if (!pca.valid) continue;  // collinear or single: no plane, no verdict
        normal = pca.normal();
      }
      normal.normalize();
      const Vector3d e1 = normal.unitOrthogonal(), e2 = normal.cross(e1);
      angle.clear();
      for (const Neighbor& nb : near) {
        if (!(nb.squared_distance > 0.0)) continue;  // the point itself and exact copies
        const Vector3d d = cloud.positions[nb.index] - x;
        const double u = d.dot(e1), v = d.dot(e2);
        if (u == 0.0 && v == 0.0) continue;
        angle.push_back(std::atan2(v, u));
      }
      if (angle.size() < 2) {
        out.boundary[i] = 1;
        continue;
      }
      std::sort(angle.begin(), angle.end());
      double gap = angle.front() + 2.0 * std::numbers::pi - angle.back();
      for (std::size_t j = 1; j < angle.size(); ++j) gap = std::max(gap, angle[j] - angle[j - 1]);
      out.gap_deg[i] = gap * 180.0 / std::numbers::pi;
      out.boundary[i] = gap > min_gap ? 1 : 0;
    }
  });
  out.count = std::size_t(std::count(out.boundary.begin(), out.boundary.end(), std::uint8_t{1}));
  return out;
}

const ResultTable<BoundaryResult>& BoundaryResult::results() {
  static const ResultTable<BoundaryResult> table = [] {
    ResultTable<BoundaryResult> t;
    t.count("boundary", &BoundaryResult::count, "Boundary points (field boundary)").as_count();
    return t;
  }();
  return table;
}

}  // namespace pointsurf
