// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Pieces shared by the simplification methods: parameter checks, the target count, surface
// variation on demand, sorted grid cells and greedy Poisson-disk thinning.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "pointsurf/simplify/simplify.h"

namespace pointsurf::detail {

/// Throws UsageError for an empty cloud or a malformed target. `allow_cell`: whether the
/// method accepts a cell length; `allow_growth`: whether a count above N is allowed.
void check_simplify_input(std::string_view function, const PointCloud& cloud, const SimplifyTarget& target, bool allow_cell,
                          bool allow_growth = false);
/// The tree to use: `tree` (checked against the cloud size) or a new one built in `own`.
const KdTree& tree_or_own(std::string_view function, const PointCloud& cloud, const KdTree* tree, std::optional<KdTree>& own);

/// A callback mapping a sub-stage's [0, 1] onto [begin, end] of `progress` (empty if it is).
ProgressCallback sub_progress(const ProgressCallback& progress, double begin, double end);

/// Output count for a ratio or count target (at least 1).
std::size_t target_count(const SimplifyTarget& target, std::size_t n);

/// Normals and surface variation of every point: taken from the cloud (normals, field
/// "variation") where present, estimated by PCA with k neighbours otherwise.
struct SurfaceProperties {
  std::vector<Vector3d> normals;   // N, unit or zero
  std::vector<double> variation;   // N, [0, 1/3]
  bool estimated_normals = false;
};
SurfaceProperties surface_properties(const PointCloud& cloud, int k, const KdTree& tree, bool need_normals,
                                     const ProgressCallback& progress);

/// A uniform grid of cubic cells of side `cell` with its origin at `min - cell/2`.
struct Grid {
  Vector3d origin = Vector3d::Zero();
  double cell = 0.0;
  std::uint64_t nx = 0, ny = 0, nz = 0;  // cells along each axis up to the box's maximum corner
  std::uint64_t cells() const noexcept { return nx * ny * nz; }
};
/// Grid over the bounding box of `points` (Open3D's anchoring). Throws UsageError when the cell
/// is not positive or the box spans more than 2^21 cells along an axis.
Grid make_grid(std::string_view function, const BoundingBox& box, double cell);

/// Point indices sorted by cell (x fastest), ties by index, and the segment boundaries:
/// cell s holds order[starts[s] .. starts[s+1]).
struct GridCells {
  std::vector<std::uint64_t> keys;     // per segment
  std::vector<std::uint32_t> order;    // point indices, grouped by cell
  std::vector<std::size_t> starts;     // segments + 1
  std::size_t size() const noexcept { return keys.size(); }
};
/// Sorts `subset` (or all points when it is empty and `all` is true) into grid cells.
GridCells sort_into_cells(std::span<const Vector3d> points, std::span<const std::uint32_t> subset, bool all, const Grid& grid);
/// Every point's cell, without grouping the points: the occupied cells in ascending key
/// (as sort_into_cells numbers them), each point's cell number and each cell's point count.
/// O(N + cells) with an array over the grid's cells when they are not many more than the
/// points, sort_into_cells otherwise.
struct CellLabels {
  std::vector<std::uint64_t> keys;     // per occupied cell, ascending
  std::vector<std::uint32_t> cell_of;  // per point
  std::vector<std::uint32_t> count;    // per occupied cell
  std::size_t size() const noexcept { return keys.size(); }
};
CellLabels label_cells(std::span<const Vector3d> points, const Grid& grid);
/// Only the number of occupied cells.
std::size_t count_cells(std::span<const Vector3d> points, std::span<const std::uint32_t> subset, bool all, const Grid& grid);

/// Solves for a length L such that count(L) is near `wanted`, assuming count ~ L^-2 locally,
/// by secant steps in log-log space from `initial`. Returns the best length and its count.
template <typename CountFn>
std::pair<double, std::size_t> solve_length(double initial, std::size_t wanted, double tolerance, int max_steps, CountFn&& count);

/// The index of the point of `members` nearest to the centroid of the members.
std::uint32_t nearest_to_centroid(std::span<const Vector3d> points, std::span<const std::uint32_t> members);

/// A well-mixed 64-bit hash of an index (splitmix64's finaliser): a seeded, order-free coin.
constexpr std::uint64_t mix_index(std::uint64_t x) noexcept {
  x += 0x9E3779B97F4A7C15ull;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
  return x ^ (x >> 31);
}

/// Greedy Poisson-disk thinning: the points of `order` are visited in turn; one not yet
/// `removed` is appended to `kept` and marks removed every point j within `radius(i)` of it
/// (`tree` built over `positions`) for which `removes(i, j)` holds. `removed` is read as given
/// (points marked beforehand are never kept) and updated. Serial; radius queries only from
/// kept points.
template <typename RadiusFn, typename RemovesFn>
void poisson_disk(const KdTree& tree, std::span<const Vector3d> positions, std::span<const std::uint32_t> order,
                  std::vector<char>& removed, std::vector<std::uint32_t>& kept, RadiusFn&& radius, RemovesFn&& removes) {
  std::vector<Neighbor> neighbors;
  for (std::uint32_t i : order) {
    if (removed[i]) continue;
    kept.push_back(i);
    tree.radius(positions[i], radius(i), neighbors);
    for (const Neighbor& nb : neighbors)
      if (removes(i, nb.index)) removed[nb.index] = 1;
  }
}

}  // namespace pointsurf::detail

#include "simplify/detail/solve_length.inl"
