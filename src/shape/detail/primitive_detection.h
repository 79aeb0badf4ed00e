// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// detect_primitives as a phase object (Schnabel, Wahl, Klein 2007): the shared state of the
// search as named members, one member function per phase, so that each phase can be run alone
// on a small cloud or on hand-made state.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "pointsurf/core/point_cloud.h"
#include "pointsurf/shape/primitives.h"
#include "shape/detail/point_octree.h"

namespace pointsurf::detail {

/// The largest connected component of the points `idx` of `pts` on a grid of cells of `cell`:
/// points in cells that touch (26-neighbourhood) are connected. Ties go to the component found
/// first (in the order of `idx`). Returns its points in the order of `idx`.
std::vector<std::uint32_t> largest_component(const std::vector<Eigen::Vector3d>& pts, const std::vector<std::uint32_t>& idx, double cell);

/// A candidate primitive and its support among the remaining points.
struct PrimitiveCandidate {
  Primitive shape;                  // in the shifted frame
  int level = 0;                    // octree level its minimal set came from
  int subsets = 0;                  // scoring subsets evaluated
  std::vector<std::uint32_t> hits;  // compatible unassigned points in the evaluated subsets
  double low = 0.0, estimate = 0.0, high = 0.0;  // its support among the remaining points
};

/// A candidate whose points were scattered, and a few of its points: its kind is not drawn again.
struct FailedShape {
  Primitive shape;
  std::vector<std::uint32_t> probes;
};

/// A primitive being extracted and its points (ranks).
struct ExtractedShape {
  Primitive shape;
  std::vector<std::uint32_t> points;
};

/// The state and phases of detect_primitives. Points are addressed by rank: their place in
/// Morton order (`order[rank]` is the input index). The search draws batches of candidates
/// (`draw_candidates`), scores them lazily (`choose_best`) and extracts the best one
/// (`extract_best`) until too few points remain.
class PrimitiveDetection {
public:
  /// What `choose_best` asks for next.
  enum class Next { Draw, Extract, Stop };

  /// Over `cloud` (with normals) and `params` (validated); both must outlive the object. Sets
  /// every label to unassigned.
  PrimitiveDetection(const PointCloud& cloud, const PrimitiveParams& params);
  PrimitiveDetection(const PointCloud&, PrimitiveParams&&) = delete;  // it would dangle
  PrimitiveDetection(PointCloud&&, const PrimitiveParams&) = delete;

  /// Reads the params and the spacing; produces the lengths, `min_points`, the normal-angle
  /// bound and the result's used values. False when there is nothing to fit (zero lengths).
  bool resolve_parameters();
  /// Reads positions and normals; produces `pts`, `nrm` (unit; zero and not `usable` where a
  /// normal is unusable), `sorted_codes` and `order`: the points relative to the box centre in
  /// Morton order (ties by coordinates, normal, index), and the box's `centre`, `side`, `scene`.
  void sort_in_morton_order();
  /// Reads `usable` and the seed; produces the scoring subsets (`subset_ranks`, `subset_of`:
  /// subset 0 about 500 points, each next about twice as large) and `remaining` (usable ranks).
  void draw_scoring_subsets();
  /// Reads the subsets and `remaining`; produces their octrees, the octree of all points,
  /// `evaluated` and the octree `levels` minimal sets are drawn from (down to a few cluster cells).
  void build_octrees();

  /// Whether the search goes on: at least min_points remain, and not too many failures in a row.
  bool searching() const;
  /// The share of the points assigned (for progress).
  double assigned_share() const;

  /// Reads the unassigned points, the level weights and the failed shapes; draws a batch of
  /// minimal sets, scores their candidates on the first subset and adds to `candidates` those
  /// that may reach min_points.
  void draw_candidates();
  /// Reads `candidates`; refines the best and those whose interval overlaps its until the best
  /// stands apart. Returns its index.
  std::size_t score_lazily();
  /// Reads `candidates` and the draws so far; sets `best` (by `score_lazily`) and says whether
  /// to draw more, extract the best, or stop.
  Next choose_best();
  /// Takes `candidates[best]` out, extracts it (`extract_points`, `prefer_plane`) and assigns its
  /// points (`assign_points`) or, when they are too few, drops it (`drop_scattered`).
  void extract_best();

  /// Reads `shape`; produces its compatible unassigned points within epsilon, cut to their
  /// largest component, and the shape refitted to them (`settle`).
  ExtractedShape extract_points(const Primitive& shape) const;
  /// Reads a curved `e`; replaces it with the plane refitted to its points when that plane
  /// holds at least as many points.
  void prefer_plane(ExtractedShape& e) const;
  /// Reads a `chosen` candidate whose points were too few; drops it and the candidates
  /// describing the same shape, and records it in `failed`.
  void drop_scattered(const PrimitiveCandidate& chosen);
  /// Reads `e` (at least min_points) from a minimal set of octree `level`; produces a primitive
  /// of the result, its labels, and removes its points from `remaining`, the octrees and the
  /// candidates.
  void assign_points(ExtractedShape e, int level);

  /// The result (labels in input order, primitives in the input frame).
  PrimitiveResult result() &&;

  // Inputs and resolved parameters.
  const PointCloud& cloud;
  const PrimitiveParams& params;
  std::size_t n_all = 0;
  double eps = 0.0, cluster = 0.0, cos_max = 0.0, band = 0.0;
  unsigned types = 0;
  std::size_t min_points = 0;
  int samples = 3;  // points of a minimal set: 4 when tori are enabled

  // The frame: points relative to the box centre, in Morton order.
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double side = 0.0, scene = 0.0;
  std::vector<std::uint32_t> order;  // rank -> input index
  std::vector<Eigen::Vector3d> pts, nrm;
  std::vector<std::uint64_t> sorted_codes;
  std::vector<std::uint8_t> usable;

  // Scoring subsets and octrees.
  int subset_count = 1;
  std::vector<std::vector<std::uint32_t>> subset_ranks;  // moved into `trees` by build_octrees
  std::vector<std::int8_t> subset_of;
  std::vector<std::uint32_t> remaining;  // unassigned usable ranks, ascending
  std::vector<PointOctree> trees;
  std::optional<PointOctree> all;
  std::vector<std::uint32_t> leaf_in_subset, leaf_in_all;
  std::vector<std::size_t> evaluated;  // unassigned points in subsets [0, k)
  std::vector<std::uint8_t> assigned;
  int levels = 1;
  std::vector<double> level_weight;

  // The search.
  std::uint64_t stream = 0;  // the draws' random stream
  std::vector<PrimitiveCandidate> candidates;
  std::vector<std::vector<PrimitiveCandidate>> drawn;  // per minimal set of a batch
  std::vector<FailedShape> failed;
  std::size_t best = 0;
  std::size_t draws = 0, total_draws = 0;
  int failures = 0;
  PrimitiveResult out;

private:
  bool compatible(const Primitive& s, std::uint32_t r, double reach) const;
  void count_subsets();
  void refine(PrimitiveCandidate& c) const;
  void bound(PrimitiveCandidate& c) const;
  std::vector<std::uint32_t> collect(const Primitive& s, double reach) const;
  std::size_t fit_count(const Primitive& s, const std::vector<std::uint32_t>& probe) const;
  bool same_shape(const Primitive& a, const std::vector<std::uint32_t>& probes_a, const Primitive& b,
                  const std::vector<std::uint32_t>& probes_b) const;
  double miss(double n) const;
  bool gave_up() const;
  bool draw_minimal_set(std::size_t draw, double total_weight, std::uint32_t (&rs)[4], int& level) const;
  void draw_one(std::size_t b, double total_weight);
  void settle(Primitive& s, std::vector<std::uint32_t>& points) const;
};

}  // namespace pointsurf::detail
