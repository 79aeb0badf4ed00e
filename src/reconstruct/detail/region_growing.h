// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The phases of reconstruct_region_growing (src/reconstruct/triangulate.cpp) over their shared
// state: per-point measures, the umbrellas' candidate triangles, their merge and edge index, the
// region growing, then the front closing, hole filling and point insertion.
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <queue>
#include <span>
#include <vector>

#include "core/detail/progress_reporter.h"
#include "pointsurf/core/point_cloud.h"
#include "pointsurf/reconstruct/triangulate.h"
#include "pointsurf/spatial/kd_tree.h"
#include "reconstruct/detail/hole_filling.h"

namespace pointsurf::detail {

/// A triangle proposed by an umbrella, as (smallest index, next, next) in its orientation.
struct GrowthCandidate {
  std::array<std::uint32_t, 3> v;
  float min_angle_deg;
  std::uint8_t votes;
};

/// A directed edge (from, to) of candidate `id`, whose third vertex is `third`; key: the kd-tree
/// rank of `from` (high half) and `to`.
struct CandidateEdge {
  std::uint64_t key;
  std::uint32_t id, third;
};

/// The phases of reconstruct_region_growing, each runnable alone on state that the phases
/// before it (or a test) set up. Run in the order declared; the public function reports
/// progress between them. `cloud` has one normal per point (checked by the public function);
/// `tree` is built over its positions; `cloud`, `params`, `tree` and `progress` must outlive it.
class RegionGrowing {
public:
  RegionGrowing(const PointCloud& cloud, const TriangulateParams& params, const KdTree& tree,
                const ProgressCallback& progress);

  /// Reads the cloud (kNN in tree order); produces normals (unit, or zero), usable, local_spacing,
  /// nearest, line_like; result.duplicate_points and result.local_spacing_mean.
  void measure_points();
  /// Reads line_like, nearest, local_spacing; produces on_line (scan-line points, only for a
  /// radius in spacings) and radius_of (the radius, kLineReachFactor times wider on a line).
  void widen_scan_lines();
  /// Reads the per-point measures; produces candidates, each triangle of each point's umbrella
  /// (its Delaunay neighbours in the tangent plane), in tree order per thread.
  void propose_umbrellas();
  /// Reads candidates; merges the copies of each triangle (votes: how many proposed it) and
  /// sorts them best first (votes, then smallest angle); result.candidate_triangles.
  void merge_candidates();
  /// Reads candidates; produces rank, by_edge, edges_from (each directed candidate edge filed by
  /// the tree rank of its first vertex), and an empty selection (sel, in_mesh, accepted).
  void index_candidate_edges();
  /// Reads the index; grows the selection from seeds best first, across its front best first.
  void grow_regions();
  /// Adds the remaining candidates that share an edge with the selection (fronts that met out of
  /// step); frees the candidates; result.selected_triangles.
  void bridge_channels();
  /// Zips up the selection's front where it turns sharply; result.front_triangles.
  void close_front_corners();
  /// Closes the selection's small holes (larger ones where a hole holds an unused point or the
  /// density changes abruptly) and opens pinches; result.holes_filled, fill_triangles,
  /// pinch_triangles_removed.
  void close_small_holes();
  /// Inserts the usable points no triangle uses into the triangles about them;
  /// result.inserted_points.
  void insert_points();
  /// The mesh of the selection with its topology and stats (stats.seconds left to the caller).
  TriangulateResult result() &&;

  const PointCloud& cloud;
  const TriangulateParams& params;
  const KdTree& tree;
  ProgressReporter reporter;  // over the whole stage, [0, 1]
  std::size_t n = 0;
  std::span<const std::uint32_t> order;  // the tree's spatial order
  double min_dihedral_cos = 1.0;          // cos of params.max_dihedral_deg
  TriangulateResult out;

  // Per point.
  std::vector<Vector3d> normals;            // unit, or zero where the cloud's is unusable
  std::vector<double> local_spacing;        // mean distance to the 3 nearest distinct points
  std::vector<std::uint8_t> usable;         // a normal, no earlier copy
  std::vector<std::uint8_t> line_like;      // its neighbours lie along a line through it
  std::vector<std::uint8_t> on_line;        // line_like, and so is one of its two nearest
  std::vector<std::array<std::uint32_t, 2>> nearest;  // the two nearest distinct points (kNone: none)
  std::vector<double> radius_of;            // search radius and longest edge

  std::vector<GrowthCandidate> candidates;
  std::vector<std::uint32_t> rank;        // per point: its position in order
  std::vector<CandidateEdge> by_edge;     // sorted by key, then id
  std::vector<std::uint32_t> edges_from;  // by_edge[edges_from[r] .. edges_from[r + 1]): edges leaving rank r
  Selection sel{0};
  std::vector<std::uint8_t> in_mesh;   // per point
  std::vector<std::uint8_t> accepted;  // per candidate

private:
  bool try_accept(std::uint32_t id, const std::array<std::uint32_t, 3>& v, int mode);
  void push_neighbours(const std::array<std::uint32_t, 3>& v);
  void report_growth();

  const ProgressCallback& progress_;
  // Candidates sit in priority order, so a smaller id is a better one: a min-heap of ids, each
  // with its vertices (from by_edge, not from the candidate list, which the front visits at random).
  struct FrontEntry {
    std::uint32_t id;
    std::array<std::uint32_t, 3> v;
    bool operator>(const FrontEntry& other) const { return id > other.id; }
  };
  std::priority_queue<FrontEntry, std::vector<FrontEntry>, std::greater<>> front_;
  std::size_t grown_ = 0;
};

}  // namespace pointsurf::detail
