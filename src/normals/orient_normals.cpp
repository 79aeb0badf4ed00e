// SPDX-License-Identifier: GPL-3.0-or-later
#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <optional>
#include <vector>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "core/detail/progress_reporter.h"
#include "pointsurf/core/error.h"
#include "normals/detail/mst_orientation.h"
#include "pointsurf/normals/normals.h"

namespace pointsurf {
namespace {

using detail::DisjointSets;

// A normal that carries no direction (degenerate neighbourhood, or NaN from a file).
bool has_direction(const Eigen::Vector3d& n) { return n.squaredNorm() > 0.0; }

// Marks every normal with a negative dot product with `towards(i)` to be flipped.
template <class Towards>
void mark_against(const PointCloud& cloud, Towards towards, std::vector<std::uint8_t>& flip) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cloud.size(), 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) flip[i] = cloud.normals[i].dot(towards(i)) < 0.0;
  });
}

// Global sign of a component (MstOrientation::decide_component_signs), in this order:
// 1. Classified: a component holding points of LAS class 2 (ground) in a field
//    "classification" is terrain, and its ground points face up (the sum of their n_z > 0).
// 2. Terrain-like: a component is terrain when it is a mostly horizontal open sheet
//    (mean |n_z| >= kHorizontalShare and |mean unit normal| >= kSheetThreshold), or when it is
//    open, level and low even where vegetation and walls bring those two down: binned in xy
//    columns about two spacings wide, at least kOpenShare of its columns hold a single layer
//    (closed surfaces have a top and a bottom over every column; ground under a canopy has
//    two layers, bare ground and roofs one), the lowest point of each column has mean
//    |n_z| >= kLevelShare (ground is level, whatever else stands on it), and its extent in z is
//    at most kReliefShare of its larger extent in x and y. Terrain faces up: the lowest points
//    of the columns (the ground under trees, bridges and eaves) vote with their n_z.
// 3. Otherwise outward, by the divergence vote sum n·(p - c) (> 0 for a closed surface with
//    outward normals; also single views of convex objects), falling back on up for a sheet
//    that faces mostly up or down.
// On an open tile the outward vote is wrong: the ground lies below the centroid that
// buildings and trees raise, so it votes for facing down (issue 28: a flat, classified tile
// came out with every ground normal down). That is why terrain is recognised first.
// - mean |n_z| above which a component is made of mostly horizontal surfaces (a plane 1,
//   terrain with trees and buildings about 0.8, a sphere 0.5, a cube 1/3);
constexpr double kHorizontalShare = 0.7;
// - length of the mean unit normal above which it is an open sheet (closed surfaces ~0, a
//   hemisphere 0.5, a plane 1); a terrain tile whose roofs are still upside down scores ~0.7;
constexpr double kSheetThreshold = 0.5;
// - share of single-layer xy columns above which a component is open (spheres, tori, cubes
//   and a side view of a sphere score 0.04 at most; generated tiles 0.98 bare, 0.23-0.35 with
//   a third to half of their points in tree crowns; b9_training.ply 0.64);
constexpr double kOpenShare = 0.15;
// - mean |n_z| of the columns' lowest points above which the bottom is level ground;
constexpr double kLevelShare = 0.6;
// - extent in z over the larger horizontal extent below which a component is low (a tile);
constexpr double kReliefShare = 0.5;
// - in turn_up_level_regions, share of a region's mean normal along z above which it faces up or down;
constexpr double kVerticalShare = 0.5;
// - share of agreeing votes (|sum| / sum of |terms|) above which the outward vote decides:
//   a sphere scores 1, a torus with tube/ring ratio 0.3 about 0.5.
constexpr double kOutwardVoteThreshold = 0.05;
// - share of the deciding vote (weighted, on the winning side, 0.5..1) below which a vote is
//   close and orient_normals warns: a sphere scores 1, a torus 0.75, bare terrain 0.95 or more;
//   a single vertical wall 0.5 (it has no inside and no up);
constexpr double kCloseVote = 0.6;
// - components smaller than this share of the points are not warned of (stray clusters);
constexpr double kWarnedComponentShare = 0.01;
// LAS class of ground points (ASPRS).
constexpr double kGroundClass = 2.0;
// Columns are this many kNN reaches wide (about 4 spacings at k = 10: some 15 points of a
// layer in each); a column holds a single layer when its points span at most its width in z.
constexpr double kColumnInReaches = 2.0;
// Angle between neighbouring normals above which the forest edge crosses a crease (cut_at_creases).
constexpr double kCreaseAngleDeg = 45.0;

// The next double above a non-negative one (infinity stays).
double just_above(double x) {
  return x < std::numeric_limits<double>::infinity() ? std::bit_cast<double>(std::bit_cast<std::uint64_t>(x) + 1) : x;
}

// Weight of an edge's length, in reaches, against the angle term 1 - |cos| (see edge_weight).
// Measured on the orientation table's scans (docs/benchmarks.md): 0.2 and below leave
// building.ply's roof reversed, 0.5 costs oni.ply 3 points; 0.3 is the value used.
constexpr double kDistanceWeight = 0.3;
// Components of the kNN graph further apart than this many reaches (of both ends) are
// separate objects and are not joined (see connect_components).
constexpr double kGapInReaches = 3.0;

constexpr std::uint64_t kNoEdge = ~std::uint64_t(0);

// Weight of the graph edge i-j: 1 - |cos| of the angle between the normals (Hoppe 1992), so
// the spanning forest follows the smoothest paths and crosses sharp creases last, plus
// kDistanceWeight times the edge's length over the reach of i (distance to its farthest kNN
// neighbour, capped at kGapInReaches): among equally smooth paths, short steps. Without the
// length term, on CGAL's building.ply (facade, gabled roof, eaves) the forest reaches the roof
// through the eaves' underside and turns it inside out (agreement 0.57 with the scan's own
// normals; 0.85 with it). Normals without direction get the maximal angle term 1. Scaled into
// [0, 1] for the sort keys.
float edge_weight(const Eigen::Vector3d& ni, const Eigen::Vector3d& nj, double squared_distance, double reach_squared) {
  double angle = 1.0;
  const double lengths = std::sqrt(ni.squaredNorm() * nj.squaredNorm());
  if (lengths > 0.0) angle = 1.0 - std::min(1.0, std::abs(ni.dot(nj)) / lengths);
  const double length = reach_squared > 0.0 ? std::min(kGapInReaches, std::sqrt(squared_distance / reach_squared)) : 0.0;
  return static_cast<float>((angle + kDistanceWeight * length) / (1.0 + kDistanceWeight * kGapInReaches));
}

// Shortest edges joining the components of the kNN graph (the part of the Euclidean minimum
// spanning tree that the kNN graph lacks, Hoppe 1992): Boruvka over components. Each round,
// every component but the largest takes its shortest edge to another component (a kd-tree
// query per point that skips its own component, bounded by the best edge found so far);
// the largest needs no query of its own, since every other component's shortest edge is
// found from its side. An edge longer than `gap_in_reaches` times the kNN reach (distance to the
// k-th neighbour) of both of its ends joins separate objects, not one surface with a sampling
// gap: such a component stays on its own (its sign is then decided by its own vote).
std::vector<std::pair<std::uint32_t, std::uint32_t>> connect_components(const PointCloud& cloud, const KdTree& tree,
                                                                       DisjointSets& sets, std::span<const float> reach,
                                                                       double gap_in_reaches) {
  const std::size_t n = cloud.size();
  std::vector<std::pair<std::uint32_t, std::uint32_t>> joins;
  std::vector<std::uint8_t> closed(n, 0);  // per root: its shortest edge was too long
  std::vector<std::uint32_t> label(n), root_label(n), size_of(n);
  const std::span<const std::uint32_t> order = tree.spatial_order();
  struct Edge {
    double squared = std::numeric_limits<double>::infinity();
    std::uint32_t a = 0, b = 0;
    bool better_than(const Edge& e) const {
      return squared < e.squared || (squared == e.squared && std::minmax(a, b) < std::minmax(e.a, e.b));
    }
  };
  for (;;) {
    // Labels 0..C-1 of the current components, and the largest one.
    std::uint32_t components = 0;
    std::fill(size_of.begin(), size_of.end(), 0u);
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t root = sets.find(static_cast<std::uint32_t>(i));
      if (root == i) root_label[i] = components++;
    }
    if (components <= 1) break;
    std::vector<std::uint8_t> active(components, 1);
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint32_t root = sets.find(static_cast<std::uint32_t>(i));
      label[i] = root_label[root];
      ++size_of[label[i]];
      if (closed[root]) active[label[i]] = 0;
    }
    const std::uint32_t largest = static_cast<std::uint32_t>(std::max_element(size_of.begin(), size_of.begin() + components) - size_of.begin());
    active[largest] = 0;
    if (std::none_of(active.begin(), active.end(), [](std::uint8_t a) { return a != 0; })) break;
    tbb::enumerable_thread_specific<std::vector<Edge>> local_best([&] { return std::vector<Edge>(components); });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
      std::vector<Edge>& best = local_best.local();
      for (std::size_t pos = r.begin(); pos != r.end(); ++pos) {
        const std::uint32_t i = order[pos];
        const std::uint32_t c = label[i];
        if (!active[c]) continue;
        Neighbor nb;
        if (!tree.nearest_other(cloud.positions[i], label, c, just_above(best[c].squared), nb)) continue;
        const Edge e{nb.squared_distance, i, nb.index};
        if (e.better_than(best[c])) best[c] = e;
      }
    });
    std::vector<Edge> best(components);
    for (const std::vector<Edge>& local : local_best)
      for (std::uint32_t c = 0; c < components; ++c)
        if (local[c].better_than(best[c])) best[c] = local[c];
    for (std::uint32_t c = 0; c < components; ++c) {
      if (!active[c] || !std::isfinite(best[c].squared)) continue;
      const Edge& e = best[c];
      const double allowed = gap_in_reaches * gap_in_reaches * std::max(reach[e.a], reach[e.b]);
      if (e.squared > allowed) {
        closed[sets.find(e.a)] = 1;
        continue;
      }
      if (!sets.unite(e.a, e.b)) continue;
      joins.emplace_back(e.a, e.b);
      closed[sets.find(e.a)] = 0;
    }
  }
  return joins;
}

}  // namespace

namespace detail {

MstOrientation::MstOrientation(const PointCloud& cloud, const OrientParams& params, const KdTree* tree)
    : cloud(cloud),
      params(params),
      n(cloud.size()),
      degree(std::min(static_cast<std::size_t>(params.k), n - 1)),
      slots(n * degree),
      flip(n, 0),
      tree_(tree) {
  if (tree_ == nullptr && n > std::numeric_limits<std::uint32_t>::max())
    throw UsageError(fmt::format("orient_normals: {} points exceed the limit of {}", n,
                                 std::numeric_limits<std::uint32_t>::max()));
  if (tree_ == nullptr) tree_ = &own_tree_.emplace(cloud.positions);
  if (slots > kSlotMask)
    throw UsageError(fmt::format("orient_normals: {} points with k = {} exceed the graph limit of {} edges", n,
                                 params.k, kSlotMask));
}

MstOrientation::Edge MstOrientation::ends(std::size_t slot) const {
  return slot < slots ? Edge(static_cast<std::uint32_t>(slot / degree), target[slot]) : joins[slot - slots];
}

Eigen::Vector3d MstOrientation::oriented(std::uint32_t i) const {
  return flip[i] ? Eigen::Vector3d(-cloud.normals[i]) : cloud.normals[i];
}

void MstOrientation::build_knn_graph(const ProgressCallback& progress) {
  target.assign(slots, 0);
  weight.assign(slots, 0.0f);
  reach.assign(n, 0.0f);
  const std::span<const std::uint32_t> order = tree_->spatial_order();
  const std::vector<Eigen::Vector3d>& normals = cloud.normals;
  ProgressReporter reporter(progress, 0.0, 0.5, n);
  tbb::enumerable_thread_specific<std::vector<Neighbor>> buffers;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256), [&](const tbb::blocked_range<std::size_t>& r) {
    if (reporter.cancelled()) return;
    std::vector<Neighbor>& neighbors = buffers.local();
    for (std::size_t pos = r.begin(); pos != r.end(); ++pos) {
      const std::uint32_t i = order[pos];
      tree_->knn(cloud.positions[i], degree + 1, neighbors);
      const double farthest = neighbors.back().squared_distance;
      reach[i] = static_cast<float>(farthest);
      std::size_t slot = std::size_t(i) * degree;
      const std::size_t end = slot + degree;
      // The point itself is normally first, but among duplicates a lower index may precede
      // it or push it out of the list: skip it wherever it is and keep `degree` others.
      for (const Neighbor& nb : neighbors) {
        if (nb.index == i) continue;
        if (slot == end) break;
        target[slot] = nb.index;
        weight[slot++] = edge_weight(normals[i], normals[nb.index], nb.squared_distance, farthest);
      }
    }
    reporter.advance(r.size());
  });
  reporter.throw_if_cancelled();
}

void MstOrientation::join_components() {
  {
    DisjointSets knn_sets(n);
    for (std::size_t slot = 0; slot < slots; ++slot) knn_sets.unite(static_cast<std::uint32_t>(slot / degree), target[slot]);
    joins = connect_components(cloud, *tree_, knn_sets, reach, kGapInReaches);
  }
  if (slots + joins.size() > kSlotMask)
    throw UsageError(fmt::format("orient_normals: {} points with k = {} exceed the graph limit of {} edges", n, params.k, kSlotMask));
}

// The weight's bits above the slot: weights lie in [0, 2), whose float bit patterns are below
// 2^30 and ordered like the values, so one uint64 sorts by (weight, slot): deterministic, and
// cheaper to sort than (weight, a, b) records. An edge found from both ends is kept once,
// from the end with the lower index.
void MstOrientation::sort_edges() {
  keys.assign(slots, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      for (std::size_t slot = i * degree; slot < (i + 1) * degree; ++slot) {
        const std::uint32_t j = target[slot];
        const std::uint32_t* back = target.data() + std::size_t(j) * degree;
        const bool mutual = std::find(back, back + degree, static_cast<std::uint32_t>(i)) != back + degree;
        keys[slot] = (j < i && mutual) ? kNoEdge
                                       : (std::uint64_t(std::bit_cast<std::uint32_t>(weight[slot])) << kSlotBits) | slot;
      }
    }
  });
  std::vector<float>().swap(weight);
  for (std::size_t e = 0; e < joins.size(); ++e) {
    const auto [a, b] = joins[e];
    const float w = edge_weight(cloud.normals[a], cloud.normals[b], (cloud.positions[a] - cloud.positions[b]).squaredNorm(),
                                std::max(reach[a], reach[b]));
    keys.push_back((std::uint64_t(std::bit_cast<std::uint32_t>(w)) << kSlotBits) | (slots + e));
  }
  keys.erase(std::remove(keys.begin(), keys.end(), kNoEdge), keys.end());
  tbb::parallel_sort(keys.begin(), keys.end());
}

void MstOrientation::span_forest() {
  sets = DisjointSets(n);
  forest.clear();
  forest.reserve(n - 1);
  for (const std::uint64_t key : keys) {
    const auto [a, b] = ends(key & kSlotMask);
    if (!sets.unite(a, b)) continue;
    forest.emplace_back(a, b);
    if (forest.size() == n - 1) break;
  }
  std::vector<std::uint64_t>().swap(keys);
  std::vector<std::uint32_t>().swap(target);
}

void MstOrientation::build_adjacency() {
  offsets.assign(n + 1, 0);  // degrees first, then their prefix sums
  for (const auto& [a, b] : forest) {
    ++offsets[a + 1];
    ++offsets[b + 1];
  }
  for (std::size_t i = 0; i < n; ++i) offsets[i + 1] += offsets[i];
  adjacency.assign(offsets[n], 0);
  std::vector<std::size_t> fill(offsets.begin(), offsets.end() - 1);
  for (const auto& [a, b] : forest) {
    adjacency[fill[a]++] = b;
    adjacency[fill[b]++] = a;
  }
  std::vector<Edge>().swap(forest);
}

// Positions are taken relative to the first point to keep the sums small for georeferenced
// clouds.
void MstOrientation::label_components() {
  origin = cloud.positions[0];
  component.assign(n, 0);
  centroid.clear();
  count.clear();
  constexpr std::uint32_t kUnset = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> id_of_root(n, kUnset);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t root = sets.find(static_cast<std::uint32_t>(i));
    if (id_of_root[root] == kUnset) {
      id_of_root[root] = static_cast<std::uint32_t>(centroid.size());
      centroid.push_back(Eigen::Vector3d::Zero());
      count.push_back(0);
    }
    component[i] = id_of_root[root];
    centroid[component[i]] += cloud.positions[i] - origin;
    ++count[component[i]];
  }
  for (std::size_t c = 0; c < centroid.size(); ++c) centroid[c] /= double(count[c]);
}

// On a closed surface the outward side of the farthest point faces away from the centroid.
// The seed only starts the propagation: the vote settles each component's global sign.
void MstOrientation::choose_seeds() {
  seed.assign(components(), std::numeric_limits<std::uint32_t>::max());
  std::vector<double> seed_distance(components(), -1.0);
  for (std::size_t i = 0; i < n; ++i) {
    if (!has_direction(cloud.normals[i])) continue;
    const std::uint32_t c = component[i];
    const double d = (cloud.positions[i] - origin - centroid[c]).squaredNorm();
    if (d > seed_distance[c]) {
      seed_distance[c] = d;
      seed[c] = static_cast<std::uint32_t>(i);
    }
  }
}

// A child is flipped when it disagrees with the nearest ancestor that has a direction (a zero
// normal passes its parent's on).
void MstOrientation::propagate_from_seeds() {
  const std::vector<Eigen::Vector3d>& normals = cloud.normals;
  std::vector<std::uint8_t> visited(n, 0);
  std::vector<std::uint32_t> reference(n);
  std::vector<std::uint32_t> queue;
  for (std::size_t c = 0; c < components(); ++c) {
    const std::uint32_t s = seed[c];
    if (s == std::numeric_limits<std::uint32_t>::max()) continue;  // no normal to orient
    flip[s] = normals[s].dot(cloud.positions[s] - origin - centroid[c]) < 0.0;
    queue.assign(1, s);
    visited[s] = 1;
    reference[s] = s;
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const std::uint32_t u = queue[head];
      const Eigen::Vector3d parent_normal = oriented(reference[u]);
      for (std::size_t e = offsets[u]; e < offsets[u + 1]; ++e) {
        const std::uint32_t v = adjacency[e];
        if (visited[v]) continue;
        visited[v] = 1;
        if (has_direction(normals[v])) {
          flip[v] = parent_normal.dot(normals[v]) < 0.0;
          reference[v] = v;
        } else {
          reference[v] = reference[u];
        }
        queue.push_back(v);
      }
    }
  }
}

void MstOrientation::tally_votes() {
  const std::size_t components = this->components();
  votes.signed_sum.assign(components, 0.0);
  votes.absolute_sum.assign(components, 0.0);
  votes.horizontal_sum.assign(components, 0.0);
  votes.normal_sum.assign(components, Eigen::Vector3d::Zero());
  votes.directed.assign(components, 0);
  votes.ground_sum.assign(components, 0.0);
  votes.ground_absolute.assign(components, 0.0);
  votes.low.assign(components, Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()));
  votes.high.assign(components, Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity()));
  const ScalarField* classes = cloud.fields.find("classification");
  if (classes != nullptr && classes->values.size() != n) classes = nullptr;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t c = component[i];
    const Eigen::Vector3d p = cloud.positions[i] - origin;
    votes.low[c] = votes.low[c].cwiseMin(p);
    votes.high[c] = votes.high[c].cwiseMax(p);
    if (!has_direction(cloud.normals[i])) continue;
    const Eigen::Vector3d nrm = oriented(static_cast<std::uint32_t>(i)).normalized();
    const double d = nrm.dot(p - centroid[c]);
    votes.signed_sum[c] += d;
    votes.absolute_sum[c] += std::abs(d);
    votes.horizontal_sum[c] += std::abs(nrm.z());
    votes.normal_sum[c] += nrm;
    ++votes.directed[c];
    if (classes != nullptr && classes->values[i] == kGroundClass) {
      votes.ground_sum[c] += nrm.z();
      votes.ground_absolute[c] += std::abs(nrm.z());
    }
  }
  tally_columns();
}

// Bins each component's points with a direction in xy columns kColumnInReaches kNN reaches
// wide (about 4 spacings; sqrt(xy box area / points) where the reaches are not known yet),
// sorted by (component, column).
void MstOrientation::tally_columns() {
  const std::size_t components = this->components();
  votes.cells.assign(components, 0);
  votes.columns.assign(components, 0);
  votes.single_layer.assign(components, 0);
  votes.bottom_sum.assign(components, 0.0);
  votes.bottom_absolute.assign(components, 0.0);
  std::vector<double> side(components, 0.0);
  if (reach.size() == n) {
    for (std::size_t i = 0; i < n; ++i) side[component[i]] += std::sqrt(double(reach[i]));
    for (std::size_t c = 0; c < components; ++c) side[c] *= kColumnInReaches / double(count[c]);
  } else {
    for (std::size_t c = 0; c < components; ++c) {
      const Eigen::Vector3d extent = votes.high[c] - votes.low[c];
      if (votes.directed[c] > 0) side[c] = kColumnInReaches * std::sqrt(extent.x() * extent.y() / double(votes.directed[c]));
    }
  }
  struct Binned {
    std::uint32_t component;
    std::uint64_t column;
    std::uint32_t point;
  };
  std::vector<Binned> binned;
  binned.reserve(n);
  constexpr double kMaxColumn = double(std::numeric_limits<std::uint32_t>::max());
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t c = component[i];
    if (!(side[c] > 0.0) || !has_direction(cloud.normals[i])) continue;
    const Eigen::Vector3d p = cloud.positions[i] - origin - votes.low[c];
    const auto column_of = [&](double v) { return static_cast<std::uint64_t>(std::min(kMaxColumn, std::floor(v / side[c]))); };
    binned.push_back({c, (column_of(p.x()) << 32) | column_of(p.y()), static_cast<std::uint32_t>(i)});
  }
  tbb::parallel_sort(binned.begin(), binned.end(), [](const Binned& a, const Binned& b) {
    return a.component != b.component ? a.component < b.component : a.column != b.column ? a.column < b.column : a.point < b.point;
  });
  for (std::size_t first = 0; first < binned.size();) {
    std::size_t last = first;
    const std::uint32_t c = binned[first].component;
    std::uint32_t lowest = binned[first].point;
    double z_min = cloud.positions[lowest].z(), z_max = z_min;
    while (last < binned.size() && binned[last].component == c && binned[last].column == binned[first].column) {
      const double z = cloud.positions[binned[last].point].z();
      if (z < z_min) lowest = binned[last].point;
      z_min = std::min(z_min, z);
      z_max = std::max(z_max, z);
      ++last;
    }
    if (last - first >= 2) {  // a lone point says nothing of layers
      ++votes.cells[c];
      votes.single_layer[c] += z_max - z_min <= side[c];
    }
    ++votes.columns[c];
    const double nz = oriented(lowest).normalized().z();
    votes.bottom_sum[c] += nz;
    votes.bottom_absolute[c] += std::abs(nz);
    first = last;
  }
}

// The rule and its thresholds: the comment block of kHorizontalShare above.
void MstOrientation::decide_component_signs() {
  const std::size_t components = votes.directed.size();
  flip_component.assign(components, 0);
  terrain.assign(components, 0);
  agreement.assign(components, 1.0);
  // The winning side's share of a vote whose terms sum to `sum` and their magnitudes to `absolute`.
  const auto share = [](double sum, double absolute) { return absolute > 0.0 ? 0.5 * (1.0 + std::abs(sum) / absolute) : 0.5; };
  for (std::size_t c = 0; c < components; ++c) {
    if (votes.directed[c] == 0) continue;
    const double count = double(votes.directed[c]);
    const Eigen::Vector3d mean_normal = votes.normal_sum[c] / count;
    const double sheet = mean_normal.norm();  // ~0 closed, 0.5 hemisphere, 1 flat patch
    const double signed_sum = votes.signed_sum[c], absolute_sum = votes.absolute_sum[c];
    const Eigen::Vector3d extent = votes.high[c] - votes.low[c];
    const double cells = double(votes.cells[c]);
    const bool horizontal_sheet = votes.horizontal_sum[c] / count >= kHorizontalShare && sheet >= kSheetThreshold;
    const bool open_level_low = cells > 0.0 && double(votes.single_layer[c]) >= kOpenShare * cells &&
                                votes.bottom_absolute[c] >= kLevelShare * double(votes.columns[c]) && extent.z() <= kReliefShare * std::max(extent.x(), extent.y());
    if (votes.ground_absolute[c] > 0.0) {
      terrain[c] = 1;
      flip_component[c] = votes.ground_sum[c] < 0.0;
      agreement[c] = share(votes.ground_sum[c], votes.ground_absolute[c]);
    } else if (horizontal_sheet || open_level_low) {
      terrain[c] = 1;
      if (votes.bottom_absolute[c] > 0.0) {
        flip_component[c] = votes.bottom_sum[c] < 0.0;
        agreement[c] = share(votes.bottom_sum[c], votes.bottom_absolute[c]);
      } else {
        flip_component[c] = mean_normal.z() < 0.0;
      }
    } else if (absolute_sum > 0.0 && std::abs(signed_sum) >= kOutwardVoteThreshold * absolute_sum) {
      flip_component[c] = signed_sum < 0.0;
      agreement[c] = share(signed_sum, absolute_sum);
    } else if (std::abs(mean_normal.z()) >= 0.5 * sheet && sheet > 0.0) {
      flip_component[c] = mean_normal.z() < 0.0;
      agreement[c] = share(signed_sum, absolute_sum);
    } else {
      flip_component[c] = signed_sum < 0.0;
      agreement[c] = share(signed_sum, absolute_sum);
    }
  }
}

void MstOrientation::apply_component_signs() {
  for (std::size_t i = 0; i < n; ++i)
    if (flip_component[component[i]] && has_direction(cloud.normals[i])) flip[i] = !flip[i];
}

bool MstOrientation::has_terrain() const {
  return std::any_of(terrain.begin(), terrain.end(), [](std::uint8_t u) { return u != 0; });
}

// Inside terrain (ground with buildings), the propagation must cross creases such as the walls
// between ground and a roof, where the sign of nearly perpendicular normals is a guess. The
// forest cut at creases falls into smooth regions. It is also cut where a normal within 45
// degrees of vertical meets one that is not: otherwise tree crowns, whose normals turn every
// way in small steps, join a roof to the ground in one region, and a roof turned upside down
// by the propagation stays so (generated tiles with a third of their points in crowns: roofs
// 0.03-0.33 up on half the seeds; cut so, 0.99 up or more).
void MstOrientation::cut_at_creases() {
  const std::vector<Eigen::Vector3d>& normals = cloud.normals;
  regions = DisjointSets(n);
  const double crease_cos = std::cos(kCreaseAngleDeg * std::numbers::pi / 180.0);
  for (std::size_t u = 0; u < n; ++u) {
    if (!terrain[component[u]] || !has_direction(normals[u])) continue;
    const Eigen::Vector3d nu = normals[u].normalized();
    for (std::size_t e = offsets[u]; e < offsets[u + 1]; ++e) {
      const std::uint32_t v = adjacency[e];
      if (v < u || !has_direction(normals[v])) continue;
      const Eigen::Vector3d nv = normals[v].normalized();
      if (std::abs(nu.dot(nv)) >= crease_cos && (std::abs(nu.z()) >= crease_cos) == (std::abs(nv.z()) >= crease_cos))
        regions.unite(static_cast<std::uint32_t>(u), v);
    }
  }
}

// Every smooth region of terrain that faces up or down is turned up: a flat roof is as much
// "terrain" as the ground.
void MstOrientation::turn_up_level_regions() {
  std::vector<Eigen::Vector3d> region_sum(n, Eigen::Vector3d::Zero());
  for (std::size_t i = 0; i < n; ++i)
    if (terrain[component[i]] && has_direction(cloud.normals[i]))
      region_sum[regions.find(static_cast<std::uint32_t>(i))] += oriented(static_cast<std::uint32_t>(i)).normalized();
  for (std::size_t i = 0; i < n; ++i) {
    if (!terrain[component[i]] || !has_direction(cloud.normals[i])) continue;
    const Eigen::Vector3d& mean = region_sum[regions.find(static_cast<std::uint32_t>(i))];
    if (mean.z() < 0.0 && std::abs(mean.z()) >= kVerticalShare * mean.norm()) flip[i] = !flip[i];
  }
}

}  // namespace detail

namespace {

// Marks the normals to flip for a consistent orientation; sets the number of components and
// warns of close votes in `result`. Flips are only marked here; the caller applies them once
// the stage can no longer be cancelled.
void mark_mst(const PointCloud& cloud, const OrientParams& params, const KdTree* tree, detail::ProgressReporter& steps,
              const ProgressCallback& progress, std::vector<std::uint8_t>& flip, OrientResult& result) {
  if (cloud.size() == 0) return;
  detail::MstOrientation mst(cloud, params, tree);
  mst.build_knn_graph(progress);
  mst.join_components();
  mst.sort_edges();
  steps.report(0.75);
  steps.throw_if_cancelled();
  mst.span_forest();
  steps.report(0.85);
  steps.throw_if_cancelled();
  mst.build_adjacency();
  mst.label_components();
  mst.choose_seeds();
  mst.propagate_from_seeds();
  // The global sign of each component is decided by all of its points rather than by one
  // possibly noisy seed; then terrain regions are turned up.
  mst.tally_votes();
  mst.decide_component_signs();
  mst.apply_component_signs();
  if (mst.has_terrain()) {
    mst.cut_at_creases();
    mst.turn_up_level_regions();
  }
  for (std::size_t c = 0; c < mst.components(); ++c) {
    if (mst.agreement[c] >= kCloseVote || double(mst.count[c]) < kWarnedComponentShare * double(cloud.size())) continue;
    const char* vote = mst.votes.ground_absolute[c] > 0.0 ? "its ground points (class 2) facing up"
                       : mst.terrain[c]                   ? "terrain facing up"
                                                          : "facing outward";
    result.warnings.push_back(fmt::format("orient mst: close vote on the sign of a component of {} points ({:.1f} % for {}): "
                                          "its normals may all be reversed; orient viewpoint or direction decides instead",
                                          mst.count[c], 100.0 * mst.agreement[c], vote));
  }
  result.components = mst.components();
  flip = std::move(mst.flip);
}

}  // namespace

const EnumNames<Orientation>& orientation_names() {
  static const EnumNames<Orientation> names{
      {{Orientation::Mst, "mst"}, {Orientation::Viewpoint, "viewpoint"}, {Orientation::Direction, "direction"}, {Orientation::None, "none"}}};
  return names;
}

const FieldTable<OrientParams>& OrientParams::fields() {
  static const FieldTable<OrientParams> table = [] {
    using P = OrientParams;
    FieldTable<P> t;
    t.choice("orient", &P::method, orientation_names(),
             "Orientation: mst (consistent, Hoppe 1992), viewpoint (towards the scanner), direction or none");
    t.vector3("viewpoint", &P::viewpoint, "Scanner position (orient viewpoint)").unit("cloud units");
    t.vector3("direction", &P::direction, "Direction normals should face (orient direction)");
    t.integer("orient_k", &P::k, "Neighbours per point in the MST graph (orient mst)")
        .at_least(1)
        .unit("points")
        .when([](const P& p) { return p.method == Orientation::Mst; });
    return t;
  }();
  return table;
}

void OrientParams::validate() const {
  fields().validate(*this, "orient_normals");
  if (method == Orientation::Viewpoint && !viewpoint.allFinite()) throw UsageError("orient_normals: the viewpoint must be finite");
  if (method == Orientation::Direction && (!direction.allFinite() || direction.squaredNorm() == 0.0))
    throw UsageError(fmt::format("orient_normals: the direction must be a finite non-zero vector, got ({}, {}, {})", direction.x(),
                                 direction.y(), direction.z()));
}

OrientResult orient_normals(PointCloud& cloud, const OrientParams& params, const KdTree* tree,
                            const ProgressCallback& progress) {
  const std::size_t n = cloud.size();
  params.validate();
  if (!cloud.has_normals()) throw UsageError("orient_normals: the cloud has no normals (estimate them first)");
  if (cloud.normals.size() != n)
    throw UsageError(fmt::format("orient_normals: the cloud has {} normals for {} points", cloud.normals.size(), n));
  if (tree != nullptr && tree->size() != n)
    throw UsageError(fmt::format("orient_normals: the kd-tree holds {} points but the cloud has {}", tree->size(), n));

  OrientResult result;
  std::vector<std::uint8_t> flip(n, 0);
  detail::ProgressReporter steps(progress, 0.0, 1.0, 1);
  switch (params.method) {
    case Orientation::None:
      break;
    case Orientation::Viewpoint: {
      if (!params.viewpoint.allFinite()) throw UsageError("orient_normals: the viewpoint must be finite");
      const Eigen::Vector3d v = params.viewpoint;
      mark_against(cloud, [&](std::size_t i) { return Eigen::Vector3d(v - cloud.positions[i]); }, flip);
      break;
    }
    case Orientation::Direction: {
      const Eigen::Vector3d d = params.direction;
      if (!d.allFinite() || d.squaredNorm() == 0.0)
        throw UsageError(fmt::format("orient_normals: the direction must be a finite non-zero vector, got ({}, {}, {})",
                                     d.x(), d.y(), d.z()));
      mark_against(cloud, [&](std::size_t) { return d; }, flip);
      break;
    }
    case Orientation::Mst:
      if (params.k < 1) throw UsageError(fmt::format("orient_normals: k must be >= 1, got {}", params.k));
      mark_mst(cloud, params, tree, steps, progress, flip, result);
      break;
  }
  // The last chance to cancel comes before the cloud is touched, so a cancelled call leaves
  // the normals as they were.
  steps.report(1.0);
  steps.throw_if_cancelled();
  for (std::size_t i = 0; i < n; ++i) {
    if (!flip[i]) continue;
    cloud.normals[i] = -cloud.normals[i];
    ++result.flipped;
  }
  return result;
}

const ResultTable<OrientResult>& OrientResult::results(Orientation method) {
  static const std::vector<ResultTable<OrientResult>> tables = [] {  // any method, then Mst
    std::vector<ResultTable<OrientResult>> out(2);
    for (ResultTable<OrientResult>& t : out) t.count("flipped", &OrientResult::flipped, "Normals whose sign the orientation changed").as_count();
    out[1].count("components", &OrientResult::components, "Connected components of the orientation graph (orient mst)").as_count();
    return out;
  }();
  return tables[method == Orientation::Mst ? 1 : 0];
}

}  // namespace pointsurf
