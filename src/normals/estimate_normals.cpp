// SPDX-License-Identifier: GPL-3.0-or-later
#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>
#include <utility>
#include <vector>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "core/detail/local_pca.h"
#include "core/detail/progress_reporter.h"
#include "pointsurf/core/error.h"
#include "pointsurf/normals/normals.h"
#include "pointsurf/spatial/voxel_grid.h"

namespace pointsurf {
namespace {

struct PointNormal {
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // zero when degenerate
  double variation = 0.0;
  bool degenerate = true;
};

// PCA of the neighbourhood of `center`, in offsets from it (see detail::local_pca).
PointNormal fit_normal(std::span<const Eigen::Vector3d> positions, const Eigen::Vector3d& center,
                       std::span<const Neighbor> neighbors) {
  PointNormal out;
  const detail::LocalPca pca = detail::local_pca(
      [&](std::size_t j) { return Eigen::Vector3d(positions[neighbors[j].index] - center); }, neighbors.size());
  if (!pca.valid) return out;
  out.normal = pca.normal();
  out.variation = pca.variation();
  out.degenerate = false;
  return out;
}

// Points whose progress is reported at once (an atomic add per point would contend).
constexpr std::size_t kProgressBatch = 1024;

}  // namespace

const FieldTable<NormalParams>& NormalParams::fields() {
  static const FieldTable<NormalParams> table = [] {
    using P = NormalParams;
    FieldTable<P> t;
    t.choice("neighborhood", &P::neighborhood, neighborhood_kind_names(),
             "Neighbourhood: knn (k nearest), radius (all within r) or hybrid (at most k within r); default: radius when only "
             "radius is given, hybrid when k is given too");
    t.integer("k", &P::k, "Neighbours per point (knn; hybrid: at most k within r)")
        .at_least(3)
        .unit("points")
        .when([](const P& p) { return p.neighborhood != NeighborhoodKind::Radius; });
    t.length("radius", &P::radius, "Neighbourhood radius (radius, hybrid)")
        .positive()
        .when([](const P& p) { return p.neighborhood != NeighborhoodKind::Knn; })
        .was("radius_in_spacings");
    t.boolean("keep_variation", &P::keep_variation, "Add the field variation = l0 / (l0 + l1 + l2)").internal();
    t.boolean("keep_mean_distance", &P::keep_mean_distance, "Add the field mean_distance (mean distance to the neighbours)").internal();
    return t;
  }();
  return table;
}

void NormalParams::validate() const {
  fields().validate(*this, "estimate_normals");
  neighborhood_settings().validate("estimate_normals", 3);
}

NormalResult estimate_normals(PointCloud& cloud, const NormalParams& params, const KdTree* tree,
                              const ProgressCallback& progress) {
  const std::size_t n = cloud.size();
  const Neighborhood settings = params.neighborhood_settings();
  params.validate();
  if (n < 3) throw UsageError(fmt::format("estimate_normals: needs at least 3 points, got {}", n));
  if (cloud.has_normals() && cloud.normals.size() != n)
    throw UsageError(fmt::format("estimate_normals: the cloud has {} normals for {} points", cloud.normals.size(), n));
  if (tree != nullptr && tree->size() != n)
    throw UsageError(
        fmt::format("estimate_normals: the kd-tree holds {} points but the cloud has {}", tree->size(), n));

  // kNN (the default) runs over a voxel grid: every point's neighbours from the short list of
  // its block of cells, the same lists as the kd-tree's. Radius and hybrid use the tree.
  const bool bulk_knn = settings.kind == NeighborhoodKind::Knn;
  std::optional<KdTree> own_tree;
  if (tree == nullptr && !bulk_knn) tree = &own_tree.emplace(cloud.positions);

  NormalResult result;
  if (!bulk_knn) result.radius_used = settings.resolve_radius(*tree);

  // Results go to fresh arrays, committed at the end, so a cancelled run leaves the cloud as
  // it was. Existing normals keep their side: each new normal is flipped to agree with the old.
  const bool had_normals = cloud.has_normals();
  std::vector<Eigen::Vector3d> normals(n);
  std::vector<double> variation(params.keep_variation ? n : 0);
  std::vector<double> mean_distance(params.keep_mean_distance ? n : 0);

  detail::ProgressReporter reporter(progress, 0.0, 1.0, n);
  tbb::enumerable_thread_specific<std::size_t> degenerate(0), pending(0);
  const std::size_t k = static_cast<std::size_t>(params.k);
  const auto fit_one = [&](std::uint32_t i, std::span<const Neighbor> neighbors) {
    const Eigen::Vector3d& p = cloud.positions[i];
    PointNormal fit = fit_normal(cloud.positions, p, neighbors);
    if (fit.degenerate) ++degenerate.local();
    if (had_normals && fit.normal.dot(cloud.normals[i]) < 0.0) fit.normal = -fit.normal;
    normals[i] = fit.normal;
    if (params.keep_variation) variation[i] = fit.variation;
    if (params.keep_mean_distance) {
      double sum = 0.0;  // nearest first, as remove_statistical_outliers sums them
      for (const Neighbor& nb : neighbors) sum += std::sqrt(nb.squared_distance);
      mean_distance[i] = neighbors.empty() ? 0.0 : sum / double(neighbors.size());
    }
  };
  if (bulk_knn) {
    const VoxelGrid grid(cloud.positions, VoxelGrid::knn_cell_size(cloud.positions, k), tree);
    // The PCA needs the neighbours as a set; the mean distance sums them nearest first.
    grid.for_each_knn(
        k,
        [&](std::uint32_t i, std::span<const Neighbor> neighbors) {
          if (reporter.cancelled()) return;
          fit_one(i, neighbors);
          std::size_t& done = pending.local();
          if (++done == kProgressBatch) {
            reporter.advance(done);
            done = 0;
          }
        },
        params.keep_mean_distance);
  } else {
    const std::span<const std::uint32_t> order = tree->spatial_order();
    tbb::enumerable_thread_specific<std::vector<Neighbor>> buffers;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256), [&](const tbb::blocked_range<std::size_t>& r) {
      if (reporter.cancelled()) return;
      std::vector<Neighbor>& neighbors = buffers.local();
      for (std::size_t pos = r.begin(); pos != r.end(); ++pos) {
        const std::uint32_t i = order[pos];
        settings.query(*tree, cloud.positions[i], k, result.radius_used, neighbors);
        fit_one(i, neighbors);
      }
      reporter.advance(r.size());
    });
  }
  reporter.throw_if_cancelled();
  reporter.report(1.0);
  reporter.throw_if_cancelled();
  result.degenerate = degenerate.combine(std::plus<>());
  cloud.normals = std::move(normals);
  if (params.keep_variation) {
    // Count 0: the values are moved in next. A "variation" field already there keeps its old
    // type through add(), hence the explicit type.
    ScalarField& field = cloud.fields.add("variation", 0, ScalarType::Float32);
    field.type = ScalarType::Float32;
    field.values = std::move(variation);
  }
  if (params.keep_mean_distance) {
    ScalarField& field = cloud.fields.add("mean_distance", 0, ScalarType::Float64);
    field.type = ScalarType::Float64;
    field.values = std::move(mean_distance);
  }
  return result;
}

const ResultTable<NormalResult>& NormalResult::results() {
  static const ResultTable<NormalResult> table = [] {
    ResultTable<NormalResult> t;
    t.count("degenerate", &NormalResult::degenerate, "Points with too few neighbours or a degenerate neighbourhood: normal (0,0,0)")
        .lower_is_better()
        .as_count();
    return t;
  }();
  return table;
}

}  // namespace pointsurf
