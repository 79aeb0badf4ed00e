// SPDX-License-Identifier: GPL-3.0-or-later
#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>

#include <fmt/format.h>

#include "core/detail/local_pca.h"
#include "core/detail/progress_reporter.h"
#include "pointsurf/core/error.h"
#include "pointsurf/segment/segment.h"

namespace pointsurf {

const FieldTable<RegionGrowingParams>& RegionGrowingParams::fields() {
  static const FieldTable<RegionGrowingParams> table = [] {
    using P = RegionGrowingParams;
    FieldTable<P> t;
    t.integer("k", &P::k, "Neighbours per point (the graph's edges)").at_least(3).unit("points");
    t.number("max_angle_deg", &P::max_angle_deg, "Largest angle between neighbouring normals in one segment").unit("degrees").range(0.0, 90.0, true, false);
    t.number("max_variation", &P::max_variation, "Points of higher surface variation join a segment but do not extend it").range(0.0, 1.0 / 3.0);
    t.boolean("use_features", &P::use_features, "Feature points (field \"feature\" non-zero) do not extend a segment");
    t.integer("min_points", &P::min_points, "Fewest points of a segment; smaller ones are unassigned").at_least(1).unit("points");
    return t;
  }();
  return table;
}

void RegionGrowingParams::validate() const {
  constexpr std::string_view fn = "segment_region_growing";
  if (k < 3) throw UsageError(fmt::format("{}: k must be >= 3, got {}", fn, k));
  if (!(max_angle_deg > 0.0 && max_angle_deg <= 90.0))
    throw UsageError(fmt::format("{}: max_angle_deg must be in (0, 90] degrees, got {}", fn, max_angle_deg));
  if (!(max_variation >= 0.0 && max_variation <= 1.0 / 3.0))
    throw UsageError(fmt::format("{}: max_variation must be in [0, 1/3], got {}", fn, max_variation));
  fields().validate(*this, fn);
}

SegmentResult segment_region_growing(const PointCloud& cloud, const RegionGrowingParams& params, const KdTree* tree,
                                     const ProgressCallback& progress) {
  constexpr std::string_view fn = "segment_region_growing";
  params.validate();
  const std::size_t n = cloud.size();
  if (n == 0) return {};
  if (!cloud.has_normals()) throw UsageError(fmt::format("{}: the cloud has no normals (estimate them first: pointsurf normals)", fn));
  if (tree != nullptr && tree->size() != n)
    throw UsageError(fmt::format("{}: the kd-tree holds {} points but the cloud has {}", fn, tree->size(), n));
  std::optional<KdTree> own;
  const KdTree& t = tree != nullptr ? *tree : own.emplace(cloud.positions);
  const NeighborLists graph = t.knn_all({}, std::size_t(params.k) + 1);

  // Surface variation per point from its neighbourhood (row i of the graph: point i's).
  std::vector<double> variation(n, 1.0);
  for (std::size_t i = 0; i < n; ++i) {
    const std::span<const Neighbor> nb = graph[i];
    const Eigen::Vector3d& p = cloud.positions[i];
    const detail::LocalPca pca = detail::local_pca([&](std::size_t j) { return Eigen::Vector3d(cloud.positions[nb[j].index] - p); }, nb.size());
    if (pca.valid) variation[i] = pca.variation();
  }
  const ScalarField* features = params.use_features ? cloud.fields.find("feature") : nullptr;
  std::vector<Eigen::Vector3d> normal(n);
  std::vector<std::uint8_t> usable(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double l = cloud.normals[i].norm();
    usable[i] = std::isfinite(l) && l > 0.0;
    normal[i] = usable[i] ? Eigen::Vector3d(cloud.normals[i] / l) : Eigen::Vector3d::Zero();
  }
  // Seeds flattest first, ties by position, so that the order of the points does not matter.
  std::vector<std::uint32_t> seeds(n);
  std::iota(seeds.begin(), seeds.end(), 0u);
  std::sort(seeds.begin(), seeds.end(), [&](std::uint32_t a, std::uint32_t b) {
    if (variation[a] != variation[b]) return variation[a] < variation[b];
    const Eigen::Vector3d &pa = cloud.positions[a], &pb = cloud.positions[b];
    return std::lexicographical_compare(pa.data(), pa.data() + 3, pb.data(), pb.data() + 3);
  });
  const double cos_max = std::cos(params.max_angle_deg * M_PI / 180.0);
  std::vector<std::int64_t> region(n, -1);
  std::vector<std::uint32_t> front;
  detail::ProgressReporter reporter(progress, 0.0, 1.0, n);
  std::int64_t next = 0;
  for (std::uint32_t seed : seeds) {
    if (region[seed] >= 0 || !usable[seed]) continue;
    if (reporter.cancelled()) break;
    region[seed] = next;
    front.assign(1, seed);
    std::size_t grown = 1;
    while (!front.empty()) {
      const std::uint32_t i = front.back();
      front.pop_back();
      const bool extends = variation[i] <= params.max_variation && (features == nullptr || features->values[i] == 0.0);
      if (!extends && i != seed) continue;
      for (const Neighbor& nb : graph[i]) {
        const std::uint32_t j = nb.index;
        if (region[j] >= 0 || !usable[j] || std::abs(normal[i].dot(normal[j])) < cos_max) continue;
        region[j] = next;
        ++grown;
        front.push_back(j);
      }
    }
    reporter.advance(grown);
    ++next;
  }
  reporter.throw_if_cancelled();
  return number_segments(cloud.positions, region, params.min_points);
}

}  // namespace pointsurf
