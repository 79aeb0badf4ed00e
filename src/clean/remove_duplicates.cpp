// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/clean/remove_duplicates.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <vector>

#include <fmt/format.h>

#include "clean/detail/clean_common.h"
#include "pointsurf/clean/remove_outliers.h"
#include "core/detail/progress_reporter.h"
#include "pointsurf/core/error.h"

namespace pointsurf {

const FieldTable<DuplicateParams>& DuplicateParams::fields() {
  static const FieldTable<DuplicateParams> table = [] {
    using P = DuplicateParams;
    FieldTable<P> t;
    t.boolean("exact", &P::exact, "Merge only points with identical coordinates");
    t.length("distance", &P::distance, "Merge distance")
        .positive()
        .when([](const P& p) { return !p.exact; })
        .was("distance_in_spacings");
    return t;
  }();
  return table;
}

void DuplicateParams::validate() const { fields().validate(*this, "find_duplicates"); }

DuplicateResult find_duplicates(const PointCloud& cloud, const DuplicateParams& params, const KdTree* tree,
                                const ProgressCallback& progress) {
  constexpr std::string_view fn = "find_duplicates";
  params.validate();
  detail::check_cloud(fn, cloud, 1, tree);
  std::optional<KdTree> own;
  const KdTree& t = detail::tree_for(cloud, tree, own);
  const std::size_t n = cloud.size();

  DuplicateResult result;
  if (!params.exact) result.distance_used = n < 2 ? params.distance.resolve(0.0) : detail::resolve_length(params.distance, t);
  detail::ProgressReporter reporter(progress, 0.0, 1.0, 2);
  // Radius 0 finds the points with identical coordinates: the tree subtracts the same centre
  // from equal coordinates, so their squared distance is exactly 0.
  const NeighborLists lists = t.radius_all({}, result.distance_used);
  reporter.advance(1);
  reporter.throw_if_cancelled();

  constexpr std::uint32_t kUnset = std::numeric_limits<std::uint32_t>::max();
  result.representative.assign(n, kUnset);
  double max_squared = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    if (result.representative[i] != kUnset) continue;
    result.representative[i] = static_cast<std::uint32_t>(i);
    result.kept.push_back(static_cast<std::uint32_t>(i));
    for (const Neighbor& nb : lists[i]) {
      if (nb.index > i && result.representative[nb.index] == kUnset) {
        result.representative[nb.index] = static_cast<std::uint32_t>(i);
        max_squared = std::max(max_squared, nb.squared_distance);
      }
    }
  }
  result.removed = n - result.kept.size();
  result.max_distance = std::sqrt(max_squared);
  reporter.report(1.0);
  reporter.throw_if_cancelled();
  return result;
}

PointCloud merge_duplicates(const PointCloud& cloud, const DuplicateResult& found) {
  if (found.representative.size() != cloud.size())
    throw UsageError(fmt::format("merge_duplicates: the result covers {} points but the cloud has {}", found.representative.size(),
                                 cloud.size()));
  PointCloud out = keep_points(cloud, found.kept);
  if (found.removed == 0) return out;
  std::vector<std::uint32_t> slot(cloud.size(), 0);
  for (std::size_t s = 0; s < found.kept.size(); ++s) slot[found.kept[s]] = static_cast<std::uint32_t>(s);
  std::vector<std::uint32_t> count(found.kept.size(), 1);
  std::vector<Vector3d> normal_sum = out.normals;
  std::vector<Vector3d> color_sum(out.colors.size());
  for (std::size_t s = 0; s < out.colors.size(); ++s) color_sum[s] = out.colors[s].cast<double>();
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const std::uint32_t rep = found.representative[i];
    if (rep == i) continue;
    const std::uint32_t s = slot[rep];
    ++count[s];
    if (cloud.has_normals()) {
      const Vector3d& n = cloud.normals[i];
      normal_sum[s] += n.dot(cloud.normals[rep]) < 0.0 ? Vector3d(-n) : n;
    }
    if (cloud.has_colors()) color_sum[s] += cloud.colors[i].cast<double>();
  }
  for (std::size_t s = 0; s < found.kept.size(); ++s) {
    if (count[s] == 1) continue;
    if (out.has_normals()) {
      const double length = normal_sum[s].norm();
      if (length > 0.0) out.normals[s] = normal_sum[s] / length;
    }
    if (out.has_colors()) out.colors[s] = (color_sum[s] / double(count[s])).cast<float>();
  }
  return out;
}

DuplicateResult remove_duplicates(PointCloud& cloud, const DuplicateParams& params, const KdTree* tree,
                                  const ProgressCallback& progress) {
  DuplicateResult found = find_duplicates(cloud, params, tree, progress);
  if (found.removed > 0) cloud = merge_duplicates(cloud, found);
  return found;
}

const ResultTable<DuplicateResult>& DuplicateResult::results() {
  static const ResultTable<DuplicateResult> table = [] {
    ResultTable<DuplicateResult> t;
    t.count("removed", &DuplicateResult::removed, "Duplicates merged away").as_count();
    t.number("max_merge_distance", &DuplicateResult::max_distance, "Largest distance from a removed point to the one it merged into")
        .with_unit("cloud units");
    return t;
  }();
  return table;
}

}  // namespace pointsurf
