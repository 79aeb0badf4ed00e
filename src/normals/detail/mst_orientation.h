// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The consistent (MST) orientation of orient_normals as a phase object: the state its phases
// share is held as named members, so each phase can be run and checked alone.
#include <cstddef>
#include <cstdint>
#include <numeric>
#include <optional>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/normals/normals.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf::detail {

// Union-find with path halving and union by rank, over uint32 to keep it at 5 bytes a point.
class DisjointSets {
public:
  explicit DisjointSets(std::size_t n = 0) : parent_(n), rank_(n, 0) { std::iota(parent_.begin(), parent_.end(), 0u); }
  std::uint32_t find(std::uint32_t x) {
    while (parent_[x] != x) {
      parent_[x] = parent_[parent_[x]];
      x = parent_[x];
    }
    return x;
  }
  bool unite(std::uint32_t a, std::uint32_t b) {
    a = find(a);
    b = find(b);
    if (a == b) return false;
    if (rank_[a] < rank_[b]) std::swap(a, b);
    parent_[b] = a;
    if (rank_[a] == rank_[b]) ++rank_[a];
    return true;
  }

private:
  std::vector<std::uint32_t> parent_;
  std::vector<std::uint8_t> rank_;
};

// Marks the normals of a non-empty cloud to flip for a consistent orientation (Hoppe 1992):
// a kNN graph plus the shortest edges between its components, its minimum spanning forest,
// a propagation from one seed per tree, a global sign per component by a vote of all its
// points, and in terrain the smooth regions turned to face up. The phases run in the order
// they are declared; each reads the members named in its comment. Nothing is applied to the
// cloud: `flip` says which normals the caller should negate.
class MstOrientation {
public:
  using Edge = std::pair<std::uint32_t, std::uint32_t>;
  // Sort keys of graph edges: float weight bits above a kSlotBits-bit edge slot.
  static constexpr int kSlotBits = 34;
  static constexpr std::uint64_t kSlotMask = (std::uint64_t(1) << kSlotBits) - 1;

  // Per-component sums of the global sign vote (tally_votes).
  struct Votes {
    std::vector<double> signed_sum;          // sum of n·(p - centroid) over unit normals
    std::vector<double> absolute_sum;        // sum of |n·(p - centroid)|
    std::vector<double> horizontal_sum;      // sum of |n_z|
    std::vector<Eigen::Vector3d> normal_sum; // sum of unit normals
    std::vector<std::size_t> directed;       // points with a normal
    // Columns: the component's points binned on an xy grid (tally_columns).
    std::vector<std::size_t> columns;        // occupied columns
    std::vector<std::size_t> cells;          // columns holding at least two points
    std::vector<std::size_t> single_layer;   // of those, the ones whose points span at most the column's width in z
    std::vector<double> bottom_sum;          // sum of n_z of the lowest point of each cell
    std::vector<double> bottom_absolute;     // sum of |n_z| of those points
    std::vector<double> ground_sum;          // sum of n_z over points of LAS class 2 (field "classification")
    std::vector<double> ground_absolute;     // sum of |n_z| over those points
    std::vector<Eigen::Vector3d> low, high;  // bounding box, relative to origin
  };

  /// Checks the cloud's size (non-empty) against the graph's limits and builds a kd-tree when
  /// `tree` is null; throws UsageError past uint32 points or kSlotMask edges.
  MstOrientation(const PointCloud& cloud, const OrientParams& params, const KdTree* tree);
  MstOrientation(const MstOrientation&) = delete;
  MstOrientation& operator=(const MstOrientation&) = delete;

  /// Reads the cloud and tree; produces target/weight (slot i * degree + t: the t-th nearest
  /// other point of i and the edge's weight) and reach (squared kNN reach). Reports [0, 0.5].
  void build_knn_graph(const ProgressCallback& progress);
  /// Reads target and reach; produces joins, the shortest edges between the kNN graph's
  /// components that are not gaps between separate objects (edge slots from `slots` on).
  void join_components();
  /// Reads target, weight and joins; produces keys, the (weight, slot) sort keys of the
  /// distinct edges in ascending order, and frees weight.
  void sort_edges();
  /// Reads keys (Kruskal); produces sets (the forest's trees) and forest (its edges); frees
  /// keys and target.
  void span_forest();
  /// Reads forest; produces offsets and adjacency (the forest in compressed rows); frees forest.
  void build_adjacency();
  /// Reads sets; produces component (per point), centroid and count per component (positions
  /// relative to origin, the first point).
  void label_components();
  /// Reads component and centroid; produces seed per component: the point with a normal
  /// farthest from the centroid (or none: uint32 max).
  void choose_seeds();
  /// Reads seed and adjacency; produces flip: each seed facing away from its centroid, each
  /// child agreeing with its nearest ancestor that has a direction.
  void propagate_from_seeds();
  /// Reads flip, component, centroid and the cloud's field "classification"; produces votes.
  void tally_votes();
  /// Reads component, flip and votes' boxes (tally_votes calls it); produces votes' columns.
  void tally_columns();
  /// Reads votes; produces terrain (classified ground, or open, level and low sheets: see
  /// orient_normals.cpp), flip_component (the components whose sign the vote reverses) and
  /// agreement (the winning side's share of the deciding vote, 0.5..1; 1 when undecided).
  void decide_component_signs();
  /// Reads flip_component; toggles flip on those components' points with a direction.
  void apply_component_signs();
  /// True when decide_component_signs found a terrain component (then the last two phases run).
  bool has_terrain() const;
  /// Reads adjacency and terrain; produces regions: terrain forest trees cut at creases.
  void cut_at_creases();
  /// Reads regions and flip; toggles flip on terrain regions whose mean normal faces down.
  void turn_up_level_regions();

  /// Number of components (after label_components).
  std::size_t components() const { return centroid.size(); }
  /// The two points of an edge slot: a kNN slot below `slots`, a join from there on.
  Edge ends(std::size_t slot) const;

  const PointCloud& cloud;
  const OrientParams& params;
  const std::size_t n;       // points
  const std::size_t degree;  // kNN neighbours per point: min(k, n - 1)
  const std::size_t slots;   // kNN edge slots: n * degree

  std::vector<std::uint32_t> target;   // build_knn_graph .. span_forest
  std::vector<float> weight;           // build_knn_graph .. sort_edges
  std::vector<float> reach;            // squared distance to the farthest of the degree + 1 nearest
  std::vector<Edge> joins;             // join_components
  std::vector<std::uint64_t> keys;     // sort_edges .. span_forest
  DisjointSets sets;                   // span_forest
  std::vector<Edge> forest;            // span_forest .. build_adjacency
  std::vector<std::size_t> offsets;    // build_adjacency: point u's neighbours are
  std::vector<std::uint32_t> adjacency;//   adjacency[offsets[u] .. offsets[u + 1])
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  std::vector<std::uint32_t> component;       // label_components
  std::vector<Eigen::Vector3d> centroid;      // relative to origin
  std::vector<std::size_t> count;
  std::vector<std::uint32_t> seed;            // choose_seeds
  std::vector<std::uint8_t> flip;             // n zeros, then propagate_from_seeds on
  Votes votes;                                // tally_votes
  std::vector<std::uint8_t> flip_component;   // decide_component_signs
  std::vector<std::uint8_t> terrain;
  std::vector<double> agreement;
  DisjointSets regions;                       // cut_at_creases

private:
  // The normal of i as flip has it now.
  Eigen::Vector3d oriented(std::uint32_t i) const;

  std::optional<KdTree> own_tree_;
  const KdTree* tree_;
};

}  // namespace pointsurf::detail
