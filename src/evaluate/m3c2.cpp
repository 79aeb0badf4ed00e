// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/evaluate/m3c2.h"

#include <cmath>
#include <limits>
#include <optional>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "pointsurf/core/error.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf {
namespace {

struct AxisStats {
  std::uint32_t count = 0;
  double mean = 0.0, variance = 0.0;  // of the positions along the axis (sample variance)
};

// Points of `tree` in the cylinder of radius r and half-length h about `p` along `n`.
AxisStats cylinder_stats(const KdTree& tree, const Vector3d& p, const Vector3d& n, double r, double h, std::vector<Neighbor>& buffer) {
  tree.radius(p, std::sqrt(r * r + h * h), buffer);
  AxisStats s;
  double sum = 0.0, sum_sq = 0.0;
  for (const Neighbor& nb : buffer) {
    const Vector3d d = tree.point(nb.index) - p;
    const double along = d.dot(n);
    if (std::abs(along) > h || (d - along * n).squaredNorm() > r * r) continue;
    ++s.count;
    sum += along;
    sum_sq += along * along;
  }
  if (s.count > 0) s.mean = sum / s.count;
  if (s.count > 1) s.variance = std::max(0.0, (sum_sq - s.count * s.mean * s.mean) / (s.count - 1));
  return s;
}

}  // namespace

M3c2Result m3c2_distances(const PointCloud& cloud1, const PointCloud& cloud2, std::span<const Vector3d> core_points, const M3c2Params& params,
                          const KdTree* tree1, const KdTree* tree2) {
  if (cloud1.empty() || cloud2.empty()) throw InputError(fmt::format("m3c2: cloud {} is empty", cloud1.empty() ? 1 : 2));
  for (const double v : {params.normal_scale, params.normal_scale_in_spacings, params.projection_scale, params.projection_scale_in_spacings,
                         params.max_depth, params.max_depth_in_spacings, params.registration_error})
    if (!(v >= 0.0)) throw UsageError(fmt::format("m3c2: scales and the registration error must be >= 0, got {}", v));
  if (params.min_points < 2) throw UsageError(fmt::format("m3c2: min_points {} must be at least 2 (a spread needs two)", params.min_points));
  std::optional<KdTree> own1, own2;
  if (tree1 == nullptr) tree1 = &own1.emplace(cloud1.positions);
  if (tree2 == nullptr) tree2 = &own2.emplace(cloud2.positions);
  if (core_points.empty()) core_points = cloud1.positions;

  M3c2Result r;
  const bool derived = params.normal_scale == 0.0 || params.projection_scale == 0.0 || params.max_depth == 0.0;
  const double spacing = derived ? mean_spacing(*tree1) : 0.0;
  r.normal_scale = params.normal_scale > 0.0 ? params.normal_scale : params.normal_scale_in_spacings * spacing;
  r.projection_scale = params.projection_scale > 0.0 ? params.projection_scale : params.projection_scale_in_spacings * spacing;
  r.max_depth = params.max_depth > 0.0 ? params.max_depth : params.max_depth_in_spacings * spacing;
  if (!(r.normal_scale > 0.0 && r.projection_scale > 0.0 && r.max_depth > 0.0))
    throw InputError("m3c2: the points of cloud 1 coincide: no scale can be derived from their spacing");

  const std::size_t n = core_points.size();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  r.distance.assign(n, nan);
  r.lod95.assign(n, nan);
  r.significant.assign(n, 0);
  r.normals.assign(n, Vector3d::UnitZ());
  r.count1.assign(n, 0);
  r.count2.assign(n, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256), [&](const tbb::blocked_range<std::size_t>& range) {
    std::vector<Neighbor> buffer;
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      const Vector3d& p = core_points[i];
      // The normal: PCA of cloud 1 within D/2, about the core point.
      tree1->radius(p, 0.5 * r.normal_scale, buffer);
      if (buffer.size() < 3) continue;
      Vector3d mean = Vector3d::Zero();
      for (const Neighbor& nb : buffer) mean += tree1->point(nb.index) - p;
      mean /= static_cast<double>(buffer.size());
      Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
      for (const Neighbor& nb : buffer) {
        const Vector3d d = tree1->point(nb.index) - p - mean;
        cov += d * d.transpose();
      }
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
      Vector3d normal = eig.eigenvectors().col(0);
      Vector3d towards = Vector3d::UnitZ();
      if (cloud1.has_normals()) {
        tree1->knn(p, 1, buffer);
        towards = cloud1.normals[buffer.front().index];
      }
      if (normal.dot(towards) < 0.0) normal = -normal;
      r.normals[i] = normal;
      const double radius = 0.5 * r.projection_scale;
      const AxisStats a = cylinder_stats(*tree1, p, normal, radius, r.max_depth, buffer);
      const AxisStats b = cylinder_stats(*tree2, p, normal, radius, r.max_depth, buffer);
      r.count1[i] = a.count;
      r.count2[i] = b.count;
      if (a.count < params.min_points || b.count < params.min_points) continue;
      r.distance[i] = b.mean - a.mean;
      r.lod95[i] = 1.96 * std::sqrt(a.variance / a.count + b.variance / b.count) + params.registration_error;
      r.significant[i] = std::abs(r.distance[i]) > r.lod95[i] ? 1 : 0;
    }
  });
  for (std::size_t i = 0; i < n; ++i) {
    r.valid += std::isfinite(r.distance[i]) ? 1 : 0;
    r.significant_count += r.significant[i] ? 1 : 0;
  }
  return r;
}

}  // namespace pointsurf
