// SPDX-License-Identifier: GPL-3.0-or-later
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <optional>
#include <queue>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "core/detail/progress_reporter.h"
#include "pointsurf/core/error.h"
#include "pointsurf/simplify/simplify.h"
#include "pointsurf/spatial/voronoi_poles.h"
#include "simplify/detail/simplify_common.h"

namespace pointsurf {
namespace {

// A kNN edge counts as "off the tangent plane" (it joins another sheet, or crosses a fold or a
// sharp edge) when its offset along either endpoint's normal exceeds sin(30 degrees) of its length.
constexpr double kOffPlaneSine = 0.5;
// A pole nearer its own sample than this many nearest-neighbour distances stems from noise or a
// sampling irregularity, not from the medial axis.
constexpr double kMinPoleInSpacings = 1.0;
// Share of a disk of radius t that one Poisson-disk sample covers on average (maximal
// Poisson-disk sets have about 1 / (0.7 t^2) samples per unit area): gives lambda for a count
// (and the count for a cell target); sample elimination then meets the count exactly.
constexpr double kPackingArea = 0.7;

// Sample elimination needs several candidates per output point to even out the density: where
// the input has fewer than this many, its kNN edges get new candidates for the rest (on a 4:1
// density step at half the points: 3 gave 1.40:1 after resampling, 6 about the same: their structure,
// not only their density, matters, see kWeightRange).
constexpr double kCandidatesPerOutput = 6.0;
// Sample elimination weighs the candidates within this many target spacings.
constexpr double kWeightRange = 3.0;  // a 4:1 step at half the points: 1 gave 1.36:1, 2 1.29, 3 1.22
                                      // (armadillo 100k at 0.1 under load: 15 s with 2, 21.6 s with 3)
// A kNN edge longer than this many target spacings holds a gap the output would fill.
constexpr double kGapFactor = 1.0;
// Candidates are inserted along such an edge every this many target spacings: several per disk
// radius, so that the Poisson-disk pass can reach the same packing in a sparse region as in a
// dense one (at 1 spacing, a 4:1 density split came out 1.65:1; at 0.4, 1.24:1).
constexpr double kInsertStep = 0.25;

struct Inserted {
  std::uint32_t from, to;  // the edge's endpoints
  double s;                // position along it, (0, 1)
};


// Weighted sample elimination (Yuksel 2015, "Sample elimination for generating Poisson disk
// sample sets"): a pair of candidates c, j on the same sheet (each nearer the other's tangent
// plane than its LFS) within R = kWeightRange × min(t_c, t_j) of each other weighs
// (1 - d / R)^8; the candidate with the heaviest sum (the most crowded) is removed and its
// neighbours' sums lowered, until `wanted` are left. The output density follows t wherever there
// are several candidates per output point. Neighbours are found again at each removal (no
// stored lists: memory O(candidates)). Returns the kept candidates.
std::vector<std::uint32_t> eliminate(const KdTree& tree, std::span<const Vector3d> positions, std::span<const Vector3d> normals,
                                     std::span<const double> spacing, std::span<const double> lfs, std::size_t wanted) {
  const std::size_t m = positions.size();
  std::vector<std::uint32_t> kept(m);
  std::iota(kept.begin(), kept.end(), std::uint32_t(0));
  if (wanted >= m) return kept;
  const auto for_each_pair = [&](std::uint32_t c, std::vector<Neighbor>& neighbors, auto&& visit) {
    tree.radius(positions[c], kWeightRange * spacing[c], neighbors);
    for (const Neighbor& q : neighbors) {
      const std::uint32_t j = q.index;
      const Vector3d d = positions[j] - positions[c];
      if (j == c || !(std::abs(d.dot(normals[c])) < lfs[c]) || !(std::abs(d.dot(normals[j])) < lfs[j])) continue;
      const double range = kWeightRange * std::min(spacing[c], spacing[j]);
      const double distance = std::sqrt(q.squared_distance);
      if (distance < range) visit(j, std::pow(1.0 - distance / range, 8));
    }
  };
  std::vector<double> weight(m, 0.0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m, 512), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<Neighbor> neighbors;
    for (std::size_t c = r.begin(); c != r.end(); ++c)
      for_each_pair(std::uint32_t(c), neighbors, [&](std::uint32_t, double w) { weight[c] += w; });
  });
  std::priority_queue<std::pair<double, std::uint32_t>> heap;
  for (std::uint32_t c = 0; c < m; ++c) heap.emplace(weight[c], c);
  std::vector<char> removed(m, 0);
  std::vector<Neighbor> neighbors;
  std::size_t left = m;
  while (left > wanted && !heap.empty()) {
    const auto [w, c] = heap.top();
    heap.pop();
    if (removed[c] || w != weight[c]) continue;  // stale entry
    removed[c] = 1;
    --left;
    for_each_pair(c, neighbors, [&](std::uint32_t j, double term) {
      if (!removed[j]) heap.emplace(weight[j] -= term, j);
    });
  }
  kept.clear();
  for (std::uint32_t c = 0; c < m; ++c)
    if (!removed[c]) kept.push_back(c);
  return kept;
}

}  // namespace

std::vector<double> local_feature_size(const PointCloud& cloud, const KdTree* tree) {
  constexpr std::string_view f = "local_feature_size";
  const std::size_t n = cloud.size();
  if (n < 4) throw UsageError(fmt::format("{}: needs at least 4 points, got {}", f, n));
  std::vector<double> lfs(n, std::numeric_limits<double>::infinity());
  VoronoiPoles poles;
  try {
    poles = voronoi_poles(cloud.positions);
  } catch (const ComputeError&) {
    return lfs;  // coplanar (or collinear) samples: no medial axis
  }
  std::optional<KdTree> own;
  const KdTree& t = detail::tree_or_own(f, cloud, tree, own);
  const NeighborLists nearest = t.knn_all({}, std::min<std::size_t>(n, 2));
  std::vector<Vector3d> medial;
  for (std::size_t i = 0; i < n; ++i) {
    const std::span<const Neighbor> nb = nearest[i];
    const double own_spacing = nb.size() > 1 ? std::sqrt(nb.back().squared_distance) : 0.0;
    for (const Vector3d& pole : {poles.positive[i], poles.negative[i]})
      if (pole.allFinite() && (pole - cloud.positions[i]).norm() > kMinPoleInSpacings * own_spacing) medial.push_back(pole);
  }
  if (medial.empty()) return lfs;
  const KdTree medial_tree(medial);
  const NeighborLists to_axis = medial_tree.knn_all(cloud.positions, 1);
  for (std::size_t i = 0; i < n; ++i) lfs[i] = std::sqrt(to_axis[i].front().squared_distance);
  return lfs;
}

const FieldTable<LfsParams>& LfsParams::fields() {
  static const FieldTable<LfsParams> table = [] {
    using P = LfsParams;
    FieldTable<P> t;
    t.nested(&P::target, SimplifyTarget::fields());
    t.integer("k", &P::k, "Neighbours for normals, variation and feature size").at_least(3).unit("points");
    t.number("adaptivity", &P::adaptivity, "Feature size clamped to [median/a, median*a]").at_least(1.0);
    t.integer("fill_neighbors", &P::fill_neighbours, "kNN edges tested for gaps when filling").at_least(1).was("fill_neighbours");
    return t;
  }();
  return table;
}

void LfsParams::validate() const { fields().validate(*this, "resample_lfs"); }

SimplifyResult resample_lfs(const PointCloud& cloud, const LfsParams& params, const KdTree* tree, const ProgressCallback& progress) {
  constexpr std::string_view f = "resample_lfs";
  detail::check_simplify_input(f, cloud, params.target, true, true);
  params.validate();
  const std::size_t n = cloud.size();
  if (n < 3) throw UsageError(fmt::format("{}: needs at least 3 points, got {}", f, n));
  std::optional<KdTree> own;
  const KdTree& t = detail::tree_or_own(f, cloud, tree, own);
  const detail::SurfaceProperties surface = detail::surface_properties(cloud, params.k, t, true, detail::sub_progress(progress, 0.0, 0.3));
  detail::ProgressReporter reporter(progress, 0.3, 1.0, 4);

  // Local feature size and the area each input point stands for.
  const double diagonal = std::max(bounding_box(cloud.positions).diagonal(), 1e-300);
  const std::size_t k = std::min<std::size_t>(n, std::size_t(params.k));
  const std::size_t fill_k = std::min<std::size_t>(n - 1, std::size_t(params.fill_neighbours));
  const NeighborLists knn = t.knn_all({}, std::max(k, fill_k + 1));
  std::vector<double> lfs = n >= 4 ? local_feature_size(cloud, &t) : std::vector<double>(n, diagonal);
  std::vector<double> area(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double radius = std::sqrt(knn[i][std::min(k, knn[i].size()) - 1].squared_distance);
    area[i] = std::numbers::pi * radius * radius / double(std::min(k, knn[i].size()));
    lfs[i] = std::min(lfs[i], diagonal);
  }
  std::vector<double> sorted(lfs);
  const auto mid = sorted.begin() + std::ptrdiff_t(n / 2);
  std::nth_element(sorted.begin(), mid, sorted.end());
  const double median = *mid;
  std::vector<double> scale(n);  // LFS clamped to [median / a, median × a]
  for (std::size_t i = 0; i < n; ++i) scale[i] = std::clamp(lfs[i], median / params.adaptivity, median * params.adaptivity);
  reporter.advance(1);
  reporter.throw_if_cancelled();

  // Candidates for a given lambda (the input points and new ones in the gaps along kNN edges),
  // then sample elimination down to the wanted count.
  std::vector<std::size_t> offsets(n + 1);
  std::vector<Inserted> inserted;
  std::vector<Vector3d> positions, normals;
  std::vector<double> radius_of, lfs_of;
  std::vector<std::uint32_t> kept;
  const auto run = [&](double lambda, std::size_t wanted) {
    const auto gap_inserts = [&](std::size_t i, const Neighbor& q) -> std::size_t {
      if (q.index <= i) return 0;
      const double spacing = 0.5 * lambda * (scale[i] + scale[q.index]);
      const double len = std::sqrt(q.squared_distance);
      // Where the input has fewer than kCandidatesPerOutput points per output point (area per
      // input point against kPackingArea t^2 per output point) at either end, the edge gets
      // candidates for what is lacking
      // (the edges of a point, about fill_k / 2 of them its own, share what it lacks).
      const double lacking = kCandidatesPerOutput * std::max(area[i], area[q.index]) / (kPackingArea * spacing * spacing) - 1.0;
      // f per edge on average: floor(f), plus one by a coin seeded by the edge.
      const double f = std::max(0.0, 2.0 * lacking / double(fill_k));
      const double coin = double(detail::mix_index(i * 1315423911u + q.index) >> 11) * 0x1.0p-53;
      const std::size_t fill = static_cast<std::size_t>(f) + (coin < f - std::floor(f) ? 1 : 0);
      if (fill == 0 && !(len > kGapFactor * spacing)) return 0;
      const Vector3d d = cloud.positions[q.index] - cloud.positions[i];
      if (std::abs(d.dot(surface.normals[i])) > kOffPlaneSine * len || std::abs(d.dot(surface.normals[q.index])) > kOffPlaneSine * len)
        return 0;  // across a thin part or a sharp edge: not a gap in one sheet
      return std::max(fill, static_cast<std::size_t>(std::ceil(len / (kInsertStep * spacing))) - 1);
    };
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) {
        std::size_t c = 0;
        for (const Neighbor& q : knn[i].subspan(1, std::min(fill_k, knn[i].size() - 1))) c += gap_inserts(i, q);
        offsets[i + 1] = c;
      }
    });
    offsets[0] = 0;
    for (std::size_t i = 0; i < n; ++i) offsets[i + 1] += offsets[i];
    const std::size_t added = offsets[n];
    inserted.resize(added);
    positions.resize(n + added);
    normals.resize(n + added);
    radius_of.resize(n + added);
    lfs_of.resize(n + added);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t i = r.begin(); i != r.end(); ++i) {
        positions[i] = cloud.positions[i];
        normals[i] = surface.normals[i];
        radius_of[i] = lambda * scale[i];
        lfs_of[i] = lfs[i];
        std::size_t out = offsets[i];
        for (const Neighbor& q : knn[i].subspan(1, std::min(fill_k, knn[i].size() - 1))) {
          const std::size_t m = gap_inserts(i, q);
          const std::uint32_t j = q.index;
          const Vector3d& pi = cloud.positions[i];
          const Vector3d& pj = cloud.positions[j];
          const Vector3d& ni = surface.normals[i];
          Vector3d nj = surface.normals[j];
          if (nj.dot(ni) < 0.0) nj = -nj;
          for (std::size_t step = 1; step <= m; ++step, ++out) {
            const double s = double(step) / double(m + 1);
            // The point on the chord, pulled onto each endpoint's tangent plane and blended:
            // a curved (Hermite-like) interpolation in place of the straight chord.
            const Vector3d chord = s * (pj - pi);
            const Vector3d on_i = chord - chord.dot(ni) * ni;
            const Vector3d back = (s - 1.0) * (pj - pi);
            const Vector3d on_j = back - back.dot(nj) * nj;
            positions[n + out] = pi + (1.0 - s) * on_i + s * ((pj - pi) + on_j);
            const Vector3d normal = (1.0 - s) * ni + s * nj;
            normals[n + out] = normal.squaredNorm() > 0.0 ? Vector3d(normal.normalized()) : Vector3d::Zero();
            radius_of[n + out] = lambda * ((1.0 - s) * scale[i] + s * scale[j]);
            lfs_of[n + out] = (1.0 - s) * lfs[i] + s * lfs[j];
            inserted[out] = {static_cast<std::uint32_t>(i), j, s};
          }
        }
      }
    });
    // Where the input is denser than kCandidatesPerOutput points per output point, a random
    // subset of that density (seeded by the index) takes part: elimination from candidates of
    // the same density everywhere gives the same output density everywhere.
    std::vector<std::uint32_t> active;
    for (std::uint32_t c = 0; c < n + added; ++c) {
      const double keep = c < n ? kCandidatesPerOutput * area[c] / (kPackingArea * radius_of[c] * radius_of[c]) : 1.0;
      if (keep >= 1.0 || double(detail::mix_index(c) >> 11) * 0x1.0p-53 < keep) active.push_back(c);
    }
    if (active.size() < wanted) {
      active.resize(n + added);
      std::iota(active.begin(), active.end(), std::uint32_t(0));
    }
    const auto pick = [&](const auto& all) {
      std::vector<std::decay_t<decltype(all[0])>> out(active.size());
      for (std::size_t a = 0; a < active.size(); ++a) out[a] = all[active[a]];
      return out;
    };
    const std::vector<Vector3d> candidates = pick(positions);
    const KdTree ct(candidates);
    kept = eliminate(ct, candidates, pick(normals), pick(radius_of), pick(lfs_of), wanted);
    for (std::uint32_t& c : kept) c = active[c];
  };

  // The scale lambda: the expected count of a Poisson-disk set with spacing lambda × scale is
  // sum(area / (0.7 (lambda scale)^2)); a cell target fixes lambda and so the count.
  const double estimate = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, n, 4096), 0.0,
      [&](const tbb::blocked_range<std::size_t>& r, double sum) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) sum += area[i] / (kPackingArea * scale[i] * scale[i]);
        return sum;
      },
      std::plus<>());
  const bool by_cell = params.target.cell > 0.0;
  const double lambda = by_cell ? params.target.cell / median : std::sqrt(estimate / double(detail::target_count(params.target, n)));
  const std::size_t wanted = by_cell ? std::max<std::size_t>(1, std::size_t(std::llround(estimate / (lambda * lambda))))
                                     : detail::target_count(params.target, n);
  reporter.advance(1);
  reporter.throw_if_cancelled();
  run(lambda, wanted);
  reporter.throw_if_cancelled();

  // Output: kept input points (ascending index) with all attributes, then inserted points.
  std::vector<std::size_t> originals;
  std::vector<std::uint32_t> added_kept;
  for (std::uint32_t c : kept) (c < n ? void(originals.push_back(c)) : added_kept.push_back(c));
  std::sort(originals.begin(), originals.end());
  std::sort(added_kept.begin(), added_kept.end());
  SimplifyResult result;
  result.input_points = n;
  result.added_points = added_kept.size();
  result.length_used = lambda * median;
  result.cloud = cloud.select(originals);
  result.source_index = originals;
  PointCloud& out = result.cloud;
  if (surface.estimated_normals) out.normals.clear();
  for (std::uint32_t c : added_kept) {
    const Inserted& e = inserted[c - n];
    const std::size_t nearer = e.s < 0.5 ? e.from : e.to;
    out.positions.push_back(positions[c]);
    if (out.has_normals()) out.normals.push_back(normals[c]);
    if (out.has_colors())
      out.colors.push_back((1.0f - float(e.s)) * cloud.colors[e.from] + float(e.s) * cloud.colors[e.to]);
    for (std::size_t q = 0; q < out.fields.size(); ++q) out.fields[q].values.push_back(cloud.fields[q].values[nearer]);
    result.source_index.push_back(nearer);
  }
  reporter.report(1.0);
  reporter.throw_if_cancelled();
  return result;
}

}  // namespace pointsurf
