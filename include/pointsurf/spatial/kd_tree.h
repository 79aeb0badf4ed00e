// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// A static kd-tree over 3D points for k-nearest, radius and hybrid neighbour queries.
//
// Thread-safety: building is single-threaded; after construction every const query may be
// called from any number of threads at once (the tree is never modified by queries). The
// batch queries run in parallel with oneTBB themselves.
// Distances are Euclidean in cloud units; "squared_*" names say when they are squared.
// Coordinates are shifted internally to the tree's centre so far-from-origin clouds
// (georeferenced, 1e6..1e7 m) keep full double precision in the distance computations.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <Eigen/Core>

namespace pointsurf {

/// One neighbour: its index into the tree's points and the squared distance to the query.
struct Neighbor {
  // Left uninitialised on purpose: batch queries allocate tens of millions of these and fill
  // every one in parallel, so zero-filling them first would be a serial pass of page faults.
  Neighbor() noexcept {}  // NOLINT(cppcoreguidelines-pro-type-member-init)
  Neighbor(std::uint32_t i, double d) noexcept : index(i), squared_distance(d) {}
  std::uint32_t index;
  double squared_distance;
};

/// Neighbourhood lists of many queries in one flat array (compressed sparse rows):
/// the neighbours of query q are `neighbors[offsets[q] .. offsets[q+1])`, nearest first.
struct NeighborLists {
  std::vector<std::size_t> offsets;   // Q + 1
  std::vector<Neighbor> neighbors;    // offsets.back()
  std::size_t size() const noexcept { return offsets.empty() ? 0 : offsets.size() - 1; }
  std::span<const Neighbor> operator[](std::size_t q) const noexcept {
    return {neighbors.data() + offsets[q], offsets[q + 1] - offsets[q]};
  }
};

class KdTree {
public:
  /// Builds the tree over `points` (copied, so the caller's array may change afterwards).
  /// Throws UsageError for an empty point set. O(N log N), single-threaded.
  explicit KdTree(std::span<const Eigen::Vector3d> points, int leaf_size = 10);
  ~KdTree();
  KdTree(KdTree&&) noexcept;
  KdTree& operator=(KdTree&&) noexcept;
  KdTree(const KdTree&) = delete;
  KdTree& operator=(const KdTree&) = delete;

  std::size_t size() const noexcept;
  const Eigen::Vector3d& point(std::size_t i) const noexcept;

  /// The tree's points in the order its leaves list them: a spatial order (like a Morton
  /// order) that per-point stages should visit points in, so that neighbouring queries share
  /// cache lines. A permutation of 0..N-1, computed once when the tree is built.
  std::span<const std::uint32_t> spatial_order() const noexcept;

  /// The k nearest points to `query`, nearest first, into `out` (cleared first; min(k, N)
  /// entries). Ties are broken by index. A query point that is in the tree finds itself.
  void knn(const Eigen::Vector3d& query, std::size_t k, std::vector<Neighbor>& out) const;
  /// All points within `radius` (inclusive) of `query`, nearest first.
  void radius(const Eigen::Vector3d& query, double radius, std::vector<Neighbor>& out) const;
  /// At most `k` nearest points within `radius`, nearest first.
  void hybrid(const Eigen::Vector3d& query, std::size_t k, double radius, std::vector<Neighbor>& out) const;

  /// The nearest point whose label `labels[index]` differs from `label`, strictly closer than
  /// `max_squared_distance` (ties by index): the shortest edge from `query` out of its part of
  /// a partition (connecting the components of a graph). `labels` holds one label per point.
  /// Returns false, leaving `out` unchanged, when there is none.
  bool nearest_other(const Eigen::Vector3d& query, std::span<const std::uint32_t> labels, std::uint32_t label,
                     double max_squared_distance, Neighbor& out) const;

  /// Batch versions over many queries, in parallel. For the tree's own points pass
  /// `queries = {}`, which uses the tree's points and visits them in spatial_order().
  NeighborLists knn_all(std::span<const Eigen::Vector3d> queries, std::size_t k) const;
  NeighborLists radius_all(std::span<const Eigen::Vector3d> queries, double radius) const;
  NeighborLists hybrid_all(std::span<const Eigen::Vector3d> queries, std::size_t k, double radius) const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Mean spacing: the mean distance from each point to its nearest distinct point (distance > 0),
/// over all points, or over a seeded sample of `max_samples` points when the cloud is larger.
/// Every `*_in_spacings` default in pointsurf multiplies this value. Returns 0 when all points
/// coincide; throws UsageError for fewer than 2 points. Parallel; thread-safe.
double mean_spacing(const KdTree& tree, std::size_t max_samples = 100000, std::uint64_t seed = 42);
/// Same, building a temporary tree.
double mean_spacing(std::span<const Eigen::Vector3d> points, std::size_t max_samples = 100000, std::uint64_t seed = 42);

/// Indices of `points` sorted along a 3D Morton (Z-order) curve: visiting points in this order
/// keeps neighbouring queries in cache. O(N log N); parallel.
std::vector<std::uint32_t> morton_order(std::span<const Eigen::Vector3d> points);

}  // namespace pointsurf
