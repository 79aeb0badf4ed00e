// SPDX-License-Identifier: GPL-3.0-or-later
#include "simplify/detail/simplify_common.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "pointsurf/core/error.h"
#include "pointsurf/normals/normals.h"

namespace pointsurf::detail {
namespace {

constexpr int kAxisBits = 21;
constexpr std::int64_t kAxisCells = std::int64_t(1) << kAxisBits;

struct KeyIndex {
  std::uint64_t key;
  std::uint32_t index;
};

std::uint64_t cell_key(const Vector3d& p, const Grid& grid) {
  // Offsets from the grid origin are small numbers, so georeferenced clouds keep their cells.
  const Vector3d r = (p - grid.origin) / grid.cell;
  const auto axis = [](double v) {
    return static_cast<std::uint64_t>(std::clamp<std::int64_t>(static_cast<std::int64_t>(std::floor(v)), 0, kAxisCells - 1));
  };
  return (axis(r.z()) << (2 * kAxisBits)) | (axis(r.y()) << kAxisBits) | axis(r.x());
}

std::vector<KeyIndex> keyed(std::span<const Vector3d> points, std::span<const std::uint32_t> subset, bool all, const Grid& grid) {
  const std::size_t m = all ? points.size() : subset.size();
  std::vector<KeyIndex> out(m);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t q = r.begin(); q != r.end(); ++q) {
      const std::uint32_t i = all ? static_cast<std::uint32_t>(q) : subset[q];
      out[q] = {cell_key(points[i], grid), i};
    }
  });
  tbb::parallel_sort(out.begin(), out.end(),
                     [](const KeyIndex& a, const KeyIndex& b) { return a.key < b.key || (a.key == b.key && a.index < b.index); });
  return out;
}

}  // namespace

void check_simplify_input(std::string_view function, const PointCloud& cloud, const SimplifyTarget& target, bool allow_cell,
                          bool allow_growth) {
  if (cloud.empty()) throw UsageError(fmt::format("{}: the cloud is empty", function));
  cloud.validate();
  if (cloud.size() > std::size_t(0xffffffffu))
    throw UsageError(fmt::format("{}: {} points; at most 2^32 - 1 are supported", function, cloud.size()));
  if (!(target.cell >= 0.0) || !std::isfinite(target.cell))
    throw UsageError(fmt::format("{}: target.cell must be >= 0 (cloud units), got {}", function, target.cell));
  if (target.cell > 0.0 && !allow_cell)
    throw UsageError(fmt::format("{}: target.cell {} is not supported by this method; give a ratio or a count", function, target.cell));
  if (target.cell == 0.0 && target.count == 0 && !(target.ratio > 0.0 && target.ratio <= 1.0))
    throw UsageError(fmt::format("{}: target.ratio must be in (0, 1], got {}", function, target.ratio));
  if (target.cell == 0.0 && target.count > cloud.size() && !allow_growth)
    throw UsageError(fmt::format("{}: target.count {} exceeds the {} input points", function, target.count, cloud.size()));
}

void check_k(std::string_view function, int k) {
  if (k < 3) throw UsageError(fmt::format("{}: k must be >= 3, got {}", function, k));
}

const KdTree& tree_or_own(std::string_view function, const PointCloud& cloud, const KdTree* tree, std::optional<KdTree>& own) {
  if (tree == nullptr) return own.emplace(cloud.positions);
  if (tree->size() != cloud.size())
    throw UsageError(fmt::format("{}: the kd-tree holds {} points but the cloud has {}", function, tree->size(), cloud.size()));
  return *tree;
}

ProgressCallback sub_progress(const ProgressCallback& progress, double begin, double end) {
  if (!progress) return {};
  return [&progress, begin, end](double f) { return progress(begin + (end - begin) * f); };
}

std::size_t target_count(const SimplifyTarget& target, std::size_t n) {
  if (target.count > 0) return target.count;
  return std::max<std::size_t>(1, static_cast<std::size_t>(std::llround(target.ratio * double(n))));
}

SurfaceProperties surface_properties(const PointCloud& cloud, int k, const KdTree& tree, bool need_normals,
                                     const ProgressCallback& progress) {
  SurfaceProperties out;
  const ScalarField* variation = cloud.fields.find("variation");
  const bool have_variation = variation != nullptr && variation->values.size() == cloud.size();
  if (have_variation && (!need_normals || cloud.has_normals())) {
    out.variation = variation->values;
    if (need_normals) out.normals = cloud.normals;
    return out;
  }
  if (cloud.size() < 3) {  // too few points for PCA: no curvature information
    out.variation.assign(cloud.size(), 0.0);
    out.normals = cloud.has_normals() ? cloud.normals : std::vector<Vector3d>(cloud.size(), Vector3d::Zero());
    return out;
  }
  PointCloud work;
  work.positions = cloud.positions;
  NormalParams params;
  params.k = k;
  estimate_normals(work, params, &tree, progress);
  out.variation = std::move(work.fields.find("variation")->values);
  if (need_normals) {
    out.estimated_normals = !cloud.has_normals();
    out.normals = cloud.has_normals() ? cloud.normals : std::move(work.normals);
  }
  return out;
}

Grid make_grid(std::string_view function, const BoundingBox& box, double cell) {
  if (!(cell > 0.0) || !std::isfinite(cell)) throw UsageError(fmt::format("{}: cell must be > 0 (cloud units), got {}", function, cell));
  Grid grid;
  grid.cell = cell;
  grid.origin = box.min - Vector3d::Constant(0.5 * cell);
  const double cells = (box.extent().maxCoeff() + cell) / cell;
  if (!(cells < double(kAxisCells)))
    throw UsageError(fmt::format("{}: cell {} is too small for the cloud's extent {} (more than 2^21 cells along an axis)", function,
                                 cell, box.extent().maxCoeff()));
  return grid;
}

GridCells sort_into_cells(std::span<const Vector3d> points, std::span<const std::uint32_t> subset, bool all, const Grid& grid) {
  const std::vector<KeyIndex> sorted = keyed(points, subset, all, grid);
  GridCells cells;
  cells.order.resize(sorted.size());
  for (std::size_t q = 0; q < sorted.size(); ++q) {
    cells.order[q] = sorted[q].index;
    if (q == 0 || sorted[q].key != sorted[q - 1].key) {
      cells.keys.push_back(sorted[q].key);
      cells.starts.push_back(q);
    }
  }
  cells.starts.push_back(sorted.size());
  return cells;
}

std::size_t count_cells(std::span<const Vector3d> points, std::span<const std::uint32_t> subset, bool all, const Grid& grid) {
  const std::size_t m = all ? points.size() : subset.size();
  std::vector<std::uint64_t> keys(m);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t q = r.begin(); q != r.end(); ++q) keys[q] = cell_key(points[all ? q : subset[q]], grid);
  });
  tbb::parallel_sort(keys.begin(), keys.end());
  return static_cast<std::size_t>(std::unique(keys.begin(), keys.end()) - keys.begin());
}

std::uint32_t nearest_to_centroid(std::span<const Vector3d> points, std::span<const std::uint32_t> members) {
  const Vector3d& base = points[members[0]];
  Vector3d sum = Vector3d::Zero();
  for (std::uint32_t i : members) sum += points[i] - base;
  const Vector3d mean = sum / double(members.size());
  std::uint32_t best = members[0];
  double best_d = (points[best] - base - mean).squaredNorm();
  for (std::uint32_t i : members) {
    const double d = (points[i] - base - mean).squaredNorm();
    if (d < best_d) best = i, best_d = d;
  }
  return best;
}

}  // namespace pointsurf::detail
