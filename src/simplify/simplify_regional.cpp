// SPDX-License-Identifier: GPL-3.0-or-later
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <tuple>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "core/detail/lexicographic.h"
#include "core/detail/progress_reporter.h"
#include "pointsurf/core/error.h"
#include "pointsurf/features/boundary_points.h"
#include "pointsurf/simplify/simplify.h"
#include "simplify/detail/regional_simplification.h"
#include "simplify/detail/simplify_common.h"

namespace pointsurf {
namespace {

using detail::CellScratch;
using detail::RegionCluster;

// A cluster holding less than this share of its cell's points is a transition, not a region.
constexpr double kSmallClusterShare = 0.2;

// Rim points (boundary points of open surfaces) are thinned along the rim on a grid of this
// share of the flat points' cell: a rim keeps about twice the density of the area it bounds,
// without the dense band that keeping every rim point leaves (on CGAL's building.ply, a facade
// with window rims, keeping all 2,642 made the mesh of the rest fall apart: area change 7.6 %
// against 0.2 % without them).
constexpr double kRimCell = 0.5;

// Distance to another cluster's plane, in mean spacings, below which a point counts as lying on
// the crease between the two (linearly from 1 at the crease to 0 at this distance).
constexpr double kCreaseInSpacings = 2.0;

constexpr int kAxisBits = 21;  // as the cell keys of detail::sort_into_cells
constexpr std::uint64_t kAxisMask = (std::uint64_t(1) << kAxisBits) - 1;

// Mean normal (sign-aligned sum), centroid (relative to `origin`) and radius of each cluster
// from the current membership.
void compute_statistics(CellScratch& s, const std::vector<Vector3d>& positions, const std::vector<Vector3d>& normals,
                        const Vector3d& origin) {
  for (RegionCluster& c : s.clusters) c = RegionCluster{};
  for (std::size_t q = 0; q < s.members.size(); ++q) {
    const std::uint32_t i = s.members[q];
    RegionCluster& c = s.clusters[s.cluster[q]];
    c.normal_sum += c.normal_sum.dot(normals[i]) < 0.0 ? Vector3d(-normals[i]) : normals[i];
    c.offset_sum += positions[i] - origin;
    ++c.count;
  }
  for (RegionCluster& c : s.clusters) {
    const double len = c.normal_sum.norm();
    c.mean = len > 0.0 ? Vector3d(c.normal_sum / len) : Vector3d::Zero();
    if (c.count > 0) c.centroid = c.offset_sum / double(c.count);
  }
  for (std::size_t q = 0; q < s.members.size(); ++q) {
    RegionCluster& c = s.clusters[s.cluster[q]];
    c.radius = std::max(c.radius, (positions[s.members[q]] - origin - c.centroid).norm());
  }
}

}  // namespace

namespace detail {

std::uint64_t normal_class(const Vector3d& m) {
  if (!(m.squaredNorm() > 0.0)) return 27;
  int axis = 0;
  m.cwiseAbs().maxCoeff(&axis);
  const Vector3d n = m[axis] < 0.0 ? Vector3d(-m) : m;
  const double scale = n[axis];
  const auto bin = [&](int k) { return std::uint64_t(std::clamp(int(std::floor((n[k] / scale + 1.0) * 1.5)), 0, 2)); };
  return std::uint64_t(axis) * 9 + bin((axis + 1) % 3) * 3 + bin((axis + 2) % 3);
}

RegionalSimplification::RegionalSimplification(const PointCloud& cloud_, const RegionalParams& params_)
    : cloud(cloud_), params(params_), n(cloud_.size()), feature_field(cloud_.fields.find("feature")) {
  out.input_points = n;
}

// One kd-tree for normals and variation (when missing), the spacing, the boundary test and the
// thinning.
void RegionalSimplification::measure_surface(const KdTree* tree, const ProgressCallback& progress) {
  const ScalarField* given_variation = cloud.fields.find("variation");
  const bool have_surface = cloud.has_normals() && given_variation != nullptr && given_variation->values.size() == n;
  t = &tree_or_own("simplify_regional", cloud, tree, own);
  box = bounding_box(cloud.positions);
  spacing = params.spacing > 0.0 ? params.spacing : mean_spacing(*t);
  if (!(spacing > 0.0)) spacing = box.diagonal() > 0.0 ? box.diagonal() / std::sqrt(double(n)) : 1.0;
  if (have_surface) {
    surface.normals = cloud.normals;
    surface.variation = given_variation->values;
  } else {
    surface = surface_properties(cloud, params.k, *t, true, sub_progress(progress, 0.0, 0.6));
  }
}

// Clusters by position (grid cells) and normal (greedy grouping inside each cell), cell by cell
// in key order, inside a cell by position: a visiting order that does not depend on the input
// order (the tree's does, through its ties).
void RegionalSimplification::cluster_regions(ProgressReporter& reporter) {
  const Grid region_grid = make_grid("simplify_regional", box, std::max(params.region_size.resolve(spacing), box.extent().maxCoeff() * 1e-6));
  regions = sort_into_cells(cloud.positions, {}, true, region_grid);
  cos_join = std::cos(params.region_angle_deg * std::numbers::pi / 180.0);
  crease_scale = kCreaseInSpacings * spacing;
  weight_sum = params.variation_weight + params.normal_weight + params.distance_weight;
  factor.assign(n, 0.0f);
  cluster_normal.assign(n, Vector3d::Zero());
  base_terms.assign(n, 0.0f), own_delta.assign(n, 0.0f), crease.assign(n, 0.0f);
  cluster_key.assign(n, 0);
  planes.assign(regions.size(), {});
  visit_order.assign(n, 0);
  tbb::enumerable_thread_specific<CellScratch> scratch;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, regions.size(), 16), [&](const tbb::blocked_range<std::size_t>& r) {
    if (reporter.cancelled()) return;
    CellScratch& s = scratch.local();
    std::size_t visited = 0;
    for (std::size_t cell = r.begin(); cell != r.end(); ++cell) {
      cluster_cell(cell, s);
      visited += s.members.size();
    }
    reporter.advance(visited / 2);
  });
}

void RegionalSimplification::cluster_cell(std::size_t cell, CellScratch& s) {
  s.members.assign(regions.order.begin() + std::ptrdiff_t(regions.starts[cell]), regions.order.begin() + std::ptrdiff_t(regions.starts[cell + 1]));
  // A fixed visiting order independent of the input order (permutation invariance).
  std::sort(s.members.begin(), s.members.end(), [&](std::uint32_t a, std::uint32_t b) {
    return lexicographic_less(cloud.positions[a], cloud.positions[b]) || (cloud.positions[a] == cloud.positions[b] && a < b);
  });
  std::copy(s.members.begin(), s.members.end(), visit_order.begin() + std::ptrdiff_t(regions.starts[cell]));
  group_by_normal(s);
  compute_statistics(s, cloud.positions, surface.normals, box.min);
  // The planes of the greedy clusters of at least 3 points: a point close to the plane of a
  // cluster whose normal differs from its own cluster's lies on a crease.
  for (const RegionCluster& c : s.clusters)
    if (c.count >= 3 && c.mean.squaredNorm() > 0.0) planes[cell].push_back({c.centroid, c.mean, c.radius});
  merge_small_clusters(s);
  point_terms(s);
}

// Greedy grouping: each member joins the cluster whose mean normal is closest, within the
// joining angle, or starts a new one.
void RegionalSimplification::group_by_normal(CellScratch& s) const {
  s.clusters.clear();
  s.cluster.resize(s.members.size());
  for (std::size_t q = 0; q < s.members.size(); ++q) {
    const Vector3d& normal = surface.normals[s.members[q]];
    std::size_t best = s.clusters.size();
    double best_cos = cos_join;
    if (normal.squaredNorm() > 0.0) {
      for (std::size_t c = 0; c < s.clusters.size(); ++c) {
        const double cosine = std::abs(normal.dot(s.clusters[c].mean));
        if (cosine >= best_cos) best = c, best_cos = cosine;
      }
    }
    if (best == s.clusters.size()) s.clusters.emplace_back();
    RegionCluster& c = s.clusters[best];
    if (normal.squaredNorm() > 0.0) {
      c.normal_sum += c.normal_sum.dot(normal) < 0.0 ? Vector3d(-normal) : normal;
      const double len = c.normal_sum.norm();
      if (len > 0.0) c.mean = c.normal_sum / len;
    }
    ++c.count;
    s.cluster[q] = static_cast<std::uint32_t>(best);
  }
}

// Small clusters are transitions between large ones (the points along an edge, whose normals
// turn from one face to the other): their members join the large cluster closest in normal, so
// that their deviation from it shows.
void RegionalSimplification::merge_small_clusters(CellScratch& s) const {
  const std::size_t small = std::max<std::size_t>(3, static_cast<std::size_t>(kSmallClusterShare * double(s.members.size())));
  bool any_large = false;
  for (const RegionCluster& c : s.clusters) any_large |= c.count >= small;
  if (!any_large) return;
  for (std::size_t q = 0; q < s.members.size(); ++q) {
    if (s.clusters[s.cluster[q]].count >= small) continue;
    const Vector3d& normal = surface.normals[s.members[q]];
    std::size_t best = s.clusters.size();
    double best_cos = -1.0;
    for (std::size_t c = 0; c < s.clusters.size(); ++c) {
      if (s.clusters[c].count < small) continue;
      const double cosine = std::abs(normal.dot(s.clusters[c].mean));
      if (cosine > best_cos) best = c, best_cos = cosine;
    }
    s.cluster[q] = static_cast<std::uint32_t>(best);
  }
  compute_statistics(s, cloud.positions, surface.normals, box.min);
}

// The variation and normal terms of each member, and its distance to its cluster's plane.
void RegionalSimplification::point_terms(const CellScratch& s) {
  for (std::size_t q = 0; q < s.members.size(); ++q) {
    const std::uint32_t i = s.members[q];
    const RegionCluster& c = s.clusters[s.cluster[q]];
    const Vector3d& normal = surface.normals[i];
    const double sigma = std::min(1.0, 3.0 * std::max(surface.variation[i], 0.0));
    cluster_key[i] = normal_class(c.mean);
    // A point without a normal (degenerate neighbourhood) or in a cluster without one deviates
    // as much as it can.
    const double theta = normal.squaredNorm() > 0.0 && c.mean.squaredNorm() > 0.0
                             ? std::acos(std::min(1.0, std::abs(normal.dot(c.mean)))) / (0.5 * std::numbers::pi)
                             : 1.0;
    const double delta = c.radius > 0.0 && c.mean.squaredNorm() > 0.0
                             ? std::min(1.0, std::abs((cloud.positions[i] - box.min - c.centroid).dot(c.mean)) / (0.5 * c.radius))
                             : 0.0;
    cluster_normal[i] = c.mean;
    base_terms[i] = static_cast<float>(params.variation_weight * sigma + params.normal_weight * theta);
    own_delta[i] = static_cast<float>(delta);
  }
}

// The crease term looks at the planes of the 27 cells around each point's cell, so a crease
// near a cell border is seen from both sides.
void RegionalSimplification::find_creases(ProgressReporter& reporter) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, regions.size(), 16), [&](const tbb::blocked_range<std::size_t>& r) {
    if (reporter.cancelled()) return;
    std::size_t visited = 0;
    for (std::size_t cell = r.begin(); cell != r.end(); ++cell) {
      crease_cell(cell);
      visited += regions.starts[cell + 1] - regions.starts[cell];
    }
    reporter.advance(visited / 2);
  });
}

// The occupied cells among the 27 around `cell` (itself included), in `around`; returns how many.
std::size_t RegionalSimplification::cells_around(std::size_t cell, std::array<std::size_t, 27>& around) const {
  const std::uint64_t key = regions.keys[cell];
  const std::int64_t cx = std::int64_t(key & kAxisMask), cy = std::int64_t((key >> kAxisBits) & kAxisMask), cz = std::int64_t(key >> (2 * kAxisBits));
  std::size_t around_count = 0;
  for (std::int64_t dz = -1; dz <= 1; ++dz)
    for (std::int64_t dy = -1; dy <= 1; ++dy)
      for (std::int64_t dx = -1; dx <= 1; ++dx) {
        if (cx + dx < 0 || cy + dy < 0 || cz + dz < 0) continue;
        const std::uint64_t other = std::uint64_t(cx + dx) | (std::uint64_t(cy + dy) << kAxisBits) | (std::uint64_t(cz + dz) << (2 * kAxisBits));
        const auto it = std::lower_bound(regions.keys.begin(), regions.keys.end(), other);
        if (it != regions.keys.end() && *it == other) around[around_count++] = std::size_t(it - regions.keys.begin());
      }
  return around_count;
}

void RegionalSimplification::crease_cell(std::size_t cell) {
  std::array<std::size_t, 27> around{};
  const std::size_t around_count = cells_around(cell, around);
  for (std::size_t q = regions.starts[cell]; q != regions.starts[cell + 1]; ++q) {
    const std::uint32_t i = regions.order[q];
    const Vector3d p = cloud.positions[i] - box.min;
    double delta = own_delta[i], on_crease = 0.0;
    for (std::size_t a = 0; a < around_count; ++a)
      for (const ClusterPlane& plane : planes[around[a]]) {
        if (std::abs(plane.normal.dot(cluster_normal[i])) >= cos_join) continue;  // the same region
        if ((p - plane.centroid).norm() > plane.radius + crease_scale) continue;   // beyond its cluster
        const double dist = std::abs((p - plane.centroid).dot(plane.normal));
        on_crease = std::max(on_crease, 1.0 - std::min(1.0, dist / crease_scale));
      }
    delta = std::max(delta, on_crease);
    crease[i] = static_cast<float>(on_crease);
    factor[i] = static_cast<float>((base_terms[i] + params.distance_weight * delta) / weight_sum);
  }
}

// A robust outlier bound on F (median + 3 MAD), at least 0.02.
void RegionalSimplification::choose_threshold() {
  threshold = params.feature_threshold;
  if (threshold >= 0.0) return;
  std::vector<float> sorted(factor);
  const auto mid = sorted.begin() + std::ptrdiff_t(n / 2);
  std::nth_element(sorted.begin(), mid, sorted.end());
  const double median = *mid;
  for (float& v : sorted) v = std::abs(v - static_cast<float>(median));
  std::nth_element(sorted.begin(), mid, sorted.end());
  threshold = std::max(0.02, median + 3.0 * 1.4826 * double(*mid));
}

bool RegionalSimplification::marked(std::uint32_t i) const {
  return feature_field != nullptr && feature_field->values[i] > 0.0;
}

// A rim point passes the angular-gap test off a crease; one on a crease (its neighbours on two
// faces) is an edge of a closed surface, kept only as a feature (by F).
bool RegionalSimplification::rim(std::uint32_t i) const { return boundary.boundary[i] && crease[i] < 0.5f; }

// Priority when the candidates are more than the budget: marked points first, then by
// decreasing F + crease term (the crease term again: of the band of high-F points along an edge,
// those on the crease).
bool RegionalSimplification::before(std::uint32_t a, std::uint32_t b) const {
  const auto priority = [&](std::uint32_t i) { return (marked(i) ? 4.0 : 0.0) + double(factor[i]) + double(crease[i]); };
  const double pa = priority(a), pb = priority(b);
  return pa > pb || (pa == pb && lexicographic_less(cloud.positions[a], cloud.positions[b]));
}

// Kept as they are: points the features module marked, boundary points of open surfaces (the
// angular-gap test) and points whose feature factor passes the threshold. Rim points are thinned
// along the rim with the flat points.
void RegionalSimplification::select_features() {
  boundary = params.keep_boundary ? detect_boundary_points(cloud, {}, t) : BoundaryResult{std::vector<std::uint8_t>(n, 0), {}, 0};
  candidates.clear();
  for (std::uint32_t i = 0; i < n; ++i)
    if (marked(i) || factor[i] >= threshold) candidates.push_back(i);
  by_cell = params.target.cell > 0.0;
  wanted = by_cell ? 0 : target_count(params.target, n);
  std::size_t feature_budget = candidates.size();
  if (!by_cell) feature_budget = std::min(feature_budget, static_cast<std::size_t>(params.max_feature_share * double(wanted)));
  if (feature_budget < candidates.size()) {
    std::nth_element(candidates.begin(), candidates.begin() + std::ptrdiff_t(feature_budget), candidates.end(),
                     [&](std::uint32_t a, std::uint32_t b) { return before(a, b); });
    candidates.resize(feature_budget);
  }
  std::sort(candidates.begin(), candidates.end());
  out.feature_points = candidates.size();
}

// The flat points by normal class (rim points in a class of their own, on a finer grid) and
// grid cell of side `length`, in `cells` and `starts`; returns the output count it would give.
std::size_t RegionalSimplification::group_flat(double length) {
  constexpr std::uint64_t kRimClass = 28;  // after the 27 normal classes and the zero normal
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, flat.size(), 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t q = r.begin(); q != r.end(); ++q) {
      const bool on_rim = rim(flat[q]);
      const Vector3d g = (cloud.positions[flat[q]] - box.min) / (on_rim ? kRimCell * length : length);
      cells[q] = {on_rim ? kRimClass : cluster_key[flat[q]], {std::int64_t(std::floor(g.x())), std::int64_t(std::floor(g.y())), std::int64_t(std::floor(g.z()))},
                  flat[q]};
    }
  });
  tbb::parallel_sort(cells.begin(), cells.end());
  starts.clear();
  for (std::size_t q = 0; q < cells.size(); ++q)
    if (q == 0 || !cells[q].same_cell(cells[q - 1])) starts.push_back(q);
  starts.push_back(cells.size());
  return candidates.size() + starts.size() - 1;
}

// Flat areas, thinned per cluster: the other points of the clusters of one normal class (27
// classes of about 35 degrees) on one grid of cell d, one point per occupied cell and class
// (the one nearest the centroid of the cell's points of that class), so that no cell mixes
// two orientations (a roof and the ground beside it). A flat area cut into many region cubes
// is one class: grids per cube measured worse (a partial cell at every cube border, one point
// at least per cluster of about 25 points: building's area change 10.9 % against 1.1 %), and so
// did a Poisson-disk pass (b9: 11.4 % against 1.3 %). d is solved for the count.
void RegionalSimplification::thin_flat_areas(ProgressReporter& reporter) {
  is_candidate.assign(n, 0);
  for (std::uint32_t i : candidates) is_candidate[i] = 1;
  flat.clear();
  for (std::uint32_t i : visit_order)
    if (!is_candidate[i]) flat.push_back(i);
  cells.resize(flat.size());
  d = params.target.cell;
  if (!by_cell && !flat.empty() && wanted > candidates.size()) {
    const double initial = spacing * std::sqrt(double(flat.size()) / double(wanted - candidates.size()));
    d = solve_length(initial, wanted, 0.01, 8, [&](double l) {
          reporter.throw_if_cancelled();
          return group_flat(l);
        }).first;
  }
  kept_mask.assign(n, 0);
  for (std::uint32_t i : candidates) kept_mask[i] = 1;
  if (d > 0.0 && !flat.empty()) keep_representatives();
}

// One point per group of `d` (nearest its centroid); of the groups, when a few too many, those
// of the most points, so the count is exact (the others are partial cells at borders).
void RegionalSimplification::keep_representatives() {
  group_flat(d);
  out.length_used = d;
  std::vector<std::size_t> order(starts.size() - 1);
  std::iota(order.begin(), order.end(), std::size_t(0));
  if (!by_cell && candidates.size() + order.size() > wanted) {
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return starts[a + 1] - starts[a] > starts[b + 1] - starts[b]; });
    order.resize(wanted - candidates.size());
  }
  std::vector<std::uint32_t> members;
  for (std::size_t g : order) {
    members.clear();
    for (std::size_t q = starts[g]; q < starts[g + 1]; ++q) members.push_back(cells[q].point);
    kept_mask[nearest_to_centroid(cloud.positions, members)] = 1;
  }
}

// A few too few: add the leftover points with the highest F.
void RegionalSimplification::top_up() {
  const std::size_t kept = std::size_t(std::count(kept_mask.begin(), kept_mask.end(), char(1)));
  if (by_cell || kept >= wanted) return;
  std::vector<std::uint32_t> rest;
  for (std::uint32_t i = 0; i < n; ++i)
    if (!kept_mask[i]) rest.push_back(i);
  const std::size_t extra = std::min(rest.size(), wanted - kept);
  std::nth_element(rest.begin(), rest.begin() + std::ptrdiff_t(extra), rest.end(), [&](std::uint32_t a, std::uint32_t b) { return before(a, b); });
  for (std::size_t q = 0; q < extra; ++q) kept_mask[rest[q]] = 1;
}

SimplifyResult RegionalSimplification::result() && {
  std::vector<std::size_t> keep;
  for (std::size_t i = 0; i < n; ++i)
    if (kept_mask[i]) keep.push_back(i);
  for (std::size_t i : keep) out.boundary_points += rim(std::uint32_t(i)) && !is_candidate[i];
  out.cloud = cloud.select(keep);
  ScalarField& field = out.cloud.fields.add("feature_factor", keep.size(), ScalarType::Float32);
  for (std::size_t j = 0; j < keep.size(); ++j) field.values[j] = factor[keep[j]];
  out.source_index = std::move(keep);
  return std::move(out);
}

}  // namespace detail


const FieldTable<RegionalParams>& RegionalParams::fields() {
  static const FieldTable<RegionalParams> table = [] {
    using P = RegionalParams;
    FieldTable<P> t;
    t.nested(&P::target, SimplifyTarget::fields());
    t.integer("k", &P::k, "Neighbours for normals and variation when the input has none").at_least(3).unit("points");
    t.length("region_size", &P::region_size, "Cluster cell size").positive().was("region_in_spacings");
    t.number("region_angle_deg", &P::region_angle_deg, "Normal angle joining a cluster").unit("degrees").range(0.0, 90.0, true, false);
    t.number("variation_weight", &P::variation_weight, "Weight of the surface variation in the feature factor").non_negative();
    t.number("normal_weight", &P::normal_weight, "Weight of the normal deviation in the feature factor").non_negative();
    t.number("distance_weight", &P::distance_weight, "Weight of the plane distance in the feature factor").non_negative();
    t.number("feature_threshold", &P::feature_threshold, "Feature factor above which a point is a candidate, [0, 1]; < 0: derived")
        .range(-std::numeric_limits<double>::infinity(), 1.0);
    t.number("max_feature_share", &P::max_feature_share, "At most this share of the output are feature points").range(0.0, 1.0, true, false);
    t.boolean("keep_boundary", &P::keep_boundary, "Thin the rims of open surfaces (angular-gap test) on a grid of half the cell");
    t.number("spacing", &P::spacing, "The cloud's mean spacing; 0: measured").unit("cloud units").non_negative().internal();
    return t;
  }();
  return table;
}

void RegionalParams::validate() const {
  const RegionalParams& p = *this;
  constexpr std::string_view f = "simplify_regional";
  if (!(p.region_angle_deg > 0.0 && p.region_angle_deg <= 90.0))
    throw UsageError(fmt::format("{}: region_angle_deg must be in (0, 90] degrees, got {}", f, p.region_angle_deg));
  if (!(p.feature_threshold <= 1.0) || std::isnan(p.feature_threshold))
    throw UsageError(fmt::format("{}: feature_threshold must be in [0, 1] (or < 0 for the derived default), got {}", f,
                                 p.feature_threshold));
  if (!(p.spacing >= 0.0) || !std::isfinite(p.spacing))
    throw UsageError(fmt::format("{}: spacing must be >= 0 (cloud units; 0: measured), got {}", f, p.spacing));
  fields().validate(*this, f);
  if (!(p.variation_weight + p.normal_weight + p.distance_weight > 0.0))
    throw UsageError(fmt::format("{}: variation_weight, normal_weight and distance_weight are all 0; at least one must be > 0", f));
}

SimplifyResult simplify_regional(const PointCloud& cloud, const RegionalParams& params, const KdTree* tree,
                                 const ProgressCallback& progress) {
  detail::check_simplify_input("simplify_regional", cloud, params.target, true);
  params.validate();
  const std::size_t n = cloud.size();
  if (n < 3) {  // nothing to cluster: keep what the target asks for, in input order
    SimplifyResult result;
    result.input_points = n;
    std::vector<std::size_t> keep(params.target.cell > 0.0 ? n : std::min(n, detail::target_count(params.target, n)));
    std::iota(keep.begin(), keep.end(), std::size_t(0));
    result.cloud = cloud.select(keep);
    result.source_index = std::move(keep);
    return result;
  }
  detail::RegionalSimplification x(cloud, params);
  x.measure_surface(tree, progress);
  detail::ProgressReporter reporter(progress, 0.6, 1.0, n);
  x.cluster_regions(reporter);
  reporter.throw_if_cancelled();
  x.find_creases(reporter);
  reporter.throw_if_cancelled();
  x.choose_threshold();
  x.select_features();
  x.thin_flat_areas(reporter);
  x.top_up();
  reporter.report(1.0);
  reporter.throw_if_cancelled();
  return std::move(x).result();
}

}  // namespace pointsurf
