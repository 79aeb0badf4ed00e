// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// A uniform grid of cubic cells over 3D points, for bulk neighbour queries over all of its own
// points at once (every point's k nearest, or every point's neighbours within a fixed radius):
// each cell gathers the points of the block of cells around it once, and all of its points
// search that short contiguous list. Faster than one kd-tree walk per point where the density
// is roughly even (scans, LiDAR); exact everywhere.
//
// The results are the KdTree's, bit for bit: positions are shifted to the same centre (the
// bounding box's), squared distances are summed in the same order, and ties are broken by
// index. A point whose k-th neighbour may lie beyond the searched block is searched again
// over wider blocks, and by a kd-tree (built on first need) beyond a few rings.
//
// Thread-safety: building is parallel; after construction every const query may be called
// from any number of threads; the for_each_* calls run in parallel with oneTBB themselves.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf {

class VoxelGrid {
public:
  /// Cells of side `cell_size` (cloud units) over `points` (copied). The side grows where the
  /// bounding box would need more than 2^20 cells along an axis. Throws UsageError for an empty
  /// point set, more than 2^32 - 1 points, or a cell size that is not finite and > 0.
  /// O(N log N) (one parallel sort).
  /// `tree`, if given, must be built over the same points: it answers the rare kNN queries
  /// whose neighbours lie beyond the searched rings (otherwise a tree is built on first need).
  VoxelGrid(std::span<const Eigen::Vector3d> points, double cell_size, const KdTree* tree = nullptr);
  ~VoxelGrid();
  VoxelGrid(VoxelGrid&&) noexcept;
  VoxelGrid& operator=(VoxelGrid&&) noexcept;
  VoxelGrid(const VoxelGrid&) = delete;
  VoxelGrid& operator=(const VoxelGrid&) = delete;

  /// A cell side suited to kNN queries with `k` neighbours: the cell of a typical point holds
  /// about k / 2 points (the fastest of k/4 .. k/1.5 on armadillo samples), from the occupancy
  /// of a sample. Any side gives exact results; this one makes them fast. Throws UsageError for an empty set.
  static double knn_cell_size(std::span<const Eigen::Vector3d> points, std::size_t k);

  std::size_t size() const noexcept;
  double cell_size() const noexcept;
  /// Number of non-empty cells.
  std::size_t cells() const noexcept;
  /// Points in the order the grid stores them (cell by cell, x fastest): a spatial order.
  std::span<const std::uint32_t> grid_order() const noexcept;

  /// `visit(i, neighbours)` for one point i and its neighbours (nearest first, ties by index).
  using Visit = std::function<void(std::uint32_t, std::span<const Neighbor>)>;

  /// Calls `visit` for every point with its min(k, N) nearest points: the lists
  /// KdTree::knn(point(i), k) gives, itself included. In parallel (a thread per block of
  /// cells), in grid order. `sorted = false` skips sorting each list (about a third of the
  /// time where k is 30): the same set, in no particular order except the farthest last.
  void for_each_knn(std::size_t k, const Visit& visit, bool sorted = true) const;
  /// Calls `visit` for every point with all points within `radius` (inclusive), nearest
  /// first: the lists KdTree::radius gives. Throws UsageError for a negative or NaN radius.
  void for_each_radius(double radius, const Visit& visit) const;
  /// For every point, the number of points within `radius` (inclusive, itself included),
  /// counting stopped at `cap`: min(count, cap). Indexed by point.
  std::vector<std::uint32_t> count_within(double radius, std::uint32_t cap) const;

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pointsurf
