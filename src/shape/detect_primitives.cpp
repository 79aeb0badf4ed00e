// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/shape/primitives.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <vector>

#include <Eigen/Dense>
#include <fmt/format.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "core/detail/plane_fit.h"
#include "core/detail/progress_reporter.h"
#include "pointsurf/core/error.h"
#include "pointsurf/spatial/kd_tree.h"
#include "shape/detail/point_octree.h"
#include "shape/detail/primitive_detection.h"
#include "shape/detail/primitive_models.h"
#include "spatial/detail/morton.h"

namespace pointsurf {
namespace {

using detail::kDeg;
using detail::PointOctree;
using detail::residual;
using Eigen::Vector3d;
constexpr int kMortonBits = 21;               // per axis
constexpr std::size_t kSmallestSubset = 500;  // points in the first scoring subset, about
constexpr std::size_t kBatch = 32;            // minimal sets drawn between extraction tests
constexpr std::size_t kMaxDraws = 400000;     // per extraction: a cap that ends hopeless searches
constexpr int kMaxFailures = 2000;            // extractions in a row that fall below min_points (a cap)
constexpr std::size_t kSameProbes = 9;        // points compared by `same_shape`

// The objective distance of `s`, for the octrees' culling.
auto distance_to(const Primitive& s) {
  return [&s](const Vector3d& x) { return residual(s, x, Vector3d::Zero()).distance; };
}

// Evenly spaced picks from `points`, for Schnabel et al.'s / CGAL's test of two candidates
// describing one shape (most of a few of each one's points fit the other).
std::vector<std::uint32_t> probes(const std::vector<std::uint32_t>& points) {
  std::vector<std::uint32_t> out;
  for (std::size_t j = 0; j < kSameProbes && !points.empty(); ++j) out.push_back(points[j * points.size() / kSameProbes]);
  return out;
}

}  // namespace

namespace detail {

std::vector<std::uint32_t> largest_component(const std::vector<Vector3d>& pts, const std::vector<std::uint32_t>& idx, double cell) {
  if (idx.empty()) return {};
  auto key = [](std::int64_t x, std::int64_t y, std::int64_t z) {
    constexpr std::int64_t off = std::int64_t(1) << 20, mask = (std::int64_t(1) << 21) - 1;
    return std::uint64_t(((x + off) & mask) | (((y + off) & mask) << 21) | (((z + off) & mask) << 42));
  };
  // Open addressing: cell key -> cell number, grown at half load.
  constexpr std::uint64_t kEmpty = ~std::uint64_t(0);
  std::size_t capacity = 1024;
  std::vector<std::uint64_t> keys(capacity, kEmpty);
  std::vector<std::uint32_t> slots(capacity);
  auto slot = [&](std::uint64_t k) {
    std::size_t h = std::size_t(detail::mix(k)) & (capacity - 1);
    while (keys[h] != kEmpty && keys[h] != k) h = (h + 1) & (capacity - 1);
    return h;
  };
  auto grow = [&] {
    std::vector<std::uint64_t> old_keys(capacity * 2, kEmpty);
    std::vector<std::uint32_t> old_slots(capacity * 2);
    old_keys.swap(keys);
    old_slots.swap(slots);
    capacity *= 2;
    for (std::size_t h = 0; h < old_keys.size(); ++h)
      if (old_keys[h] != kEmpty) {
        const std::size_t g = slot(old_keys[h]);
        keys[g] = old_keys[h], slots[g] = old_slots[h];
      }
  };
  std::vector<Eigen::Array3i> coords;
  std::vector<std::uint32_t> cell_of(idx.size()), count;
  std::uint64_t previous = kEmpty;
  for (std::size_t j = 0; j < idx.size(); ++j) {
    const Eigen::Array3i c = (pts[idx[j]].array() / cell).floor().cast<int>();
    const std::uint64_t k = key(c.x(), c.y(), c.z());
    if (k != previous) {  // points in Morton order: runs of one cell are common
      std::size_t h = slot(k);
      if (keys[h] == kEmpty) {
        if (2 * (coords.size() + 1) > capacity) grow(), h = slot(k);
        keys[h] = k, slots[h] = std::uint32_t(coords.size()), coords.push_back(c), count.push_back(0);
      }
      cell_of[j] = slots[h];
      previous = k;
    } else {
      cell_of[j] = cell_of[j - 1];
    }
    ++count[cell_of[j]];
  }
  // Union-find over the cells, each joined to the half of its 26 neighbours that precede it.
  std::vector<std::uint32_t> parent(coords.size());
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](std::uint32_t c) {
    while (parent[c] != c) c = parent[c] = parent[parent[c]];
    return c;
  };
  for (std::uint32_t c = 0; c < coords.size(); ++c)
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          if (dx > 0 || (dx == 0 && (dy > 0 || (dy == 0 && dz >= 0)))) continue;
          const std::size_t h = slot(key(coords[c].x() + dx, coords[c].y() + dy, coords[c].z() + dz));
          if (keys[h] == kEmpty) continue;
          const std::uint32_t x = find(c), y = find(slots[h]);
          if (x != y) parent[std::max(x, y)] = std::min(x, y);
        }
  std::vector<std::int32_t> comp(coords.size());
  std::vector<std::size_t> comp_points(coords.size(), 0);
  for (std::uint32_t c = 0; c < coords.size(); ++c) {
    comp[c] = std::int32_t(find(c));
    comp_points[std::size_t(comp[c])] += count[c];
  }
  const std::int32_t best = std::int32_t(std::max_element(comp_points.begin(), comp_points.end()) - comp_points.begin());
  std::vector<std::uint32_t> out;
  out.reserve(comp_points[std::size_t(best)]);
  for (std::size_t j = 0; j < idx.size(); ++j)
    if (comp[cell_of[j]] == best) out.push_back(idx[j]);
  return out;
}

}  // namespace detail

const EnumNames<PrimitiveType>& primitive_type_names() {
  static const EnumNames<PrimitiveType> names{{{PrimitiveType::Plane, "plane"},
                                               {PrimitiveType::Sphere, "sphere"},
                                               {PrimitiveType::Cylinder, "cylinder"},
                                               {PrimitiveType::Cone, "cone"},
                                               {PrimitiveType::Torus, "torus"}}};
  return names;
}

const char* primitive_type_name(PrimitiveType type) noexcept {
  const std::string& name = primitive_type_names().name(type);
  return name.empty() ? "unknown" : name.c_str();
}

unsigned primitive_mask(const std::vector<PrimitiveType>& types) noexcept {
  unsigned mask = 0;
  for (const PrimitiveType t : types)
    if (static_cast<unsigned>(t) < 5) mask |= 1u << static_cast<unsigned>(t);
  return mask;
}

const FieldTable<PrimitiveParams>& PrimitiveParams::fields() {
  static const FieldTable<PrimitiveParams> table = [] {
    using P = PrimitiveParams;
    FieldTable<P> t;
    t.choices("types", &P::types, primitive_type_names(), "Primitive types to detect, comma-separated: plane, sphere, cylinder, cone, torus");
    t.length("epsilon", &P::epsilon, "A candidate's score counts the points this close").positive().was("epsilon_in_spacings");
    t.length("cluster_epsilon", &P::cluster_epsilon, "Connectivity grid cell").positive().was("cluster_in_spacings");
    t.number("max_normal_angle_deg", &P::max_normal_angle_deg, "Largest angle between a point's normal and the primitive's")
        .unit("degrees")
        .range(0.0, 90.0, true, true)
        .was("max_normal_deg");
    t.integer("min_points", &P::min_points, "Fewest inliers of a primitive; 0: max(30, N / 200)").unit("points");
    t.number("probability", &P::probability, "Accepted chance of missing a primitive of min_points").range(0.0, 1.0, true, true);
    t.number("band_in_epsilons", &P::band_in_epsilons, "A found primitive takes the points within this many epsilons of its refit")
        .unit("epsilons")
        .at_least(1.0);
    t.integer("seed", &P::seed, "Random seed");
    return t;
  }();
  return table;
}

double Primitive::distance(const Eigen::Vector3d& p) const { return residual(*this, p, Vector3d::Zero()).distance; }

void PrimitiveParams::validate() const {
  constexpr std::string_view fn = "detect_primitives";
  if (types.empty()) throw UsageError(fmt::format("{}: types must name at least one of plane, sphere, cylinder, cone, torus", fn));
  for (const PrimitiveType t : types)
    if (primitive_type_names().name(t).empty())
      throw UsageError(fmt::format("{}: types: unknown primitive type {}", fn, static_cast<unsigned>(t)));
  if (!(band_in_epsilons >= 1.0 && std::isfinite(band_in_epsilons)))
    throw UsageError(fmt::format("{}: band_in_epsilons must be >= 1 (epsilons), got {}", fn, band_in_epsilons));
  if (!(max_normal_angle_deg > 0.0 && max_normal_angle_deg < 90.0))
    throw UsageError(fmt::format("{}: max_normal_angle_deg must be in (0, 90) degrees, got {}", fn, max_normal_angle_deg));
  if (!(probability > 0.0 && probability < 1.0)) throw UsageError(fmt::format("{}: probability must be in (0, 1), got {}", fn, probability));
  fields().validate(*this, fn);
}

namespace detail {

PrimitiveDetection::PrimitiveDetection(const PointCloud& cloud_, const PrimitiveParams& params_)
    : cloud(cloud_), params(params_), n_all(cloud_.size()), stream(mix(params_.seed ^ 0x6a09e667f3bcc909ULL)), drawn(kBatch) {
  out.labels.assign(n_all, -1);
  out.unassigned = n_all;
}

bool PrimitiveDetection::resolve_parameters() {
  const double spacing = (params.epsilon.in_spacings() || params.cluster_epsilon.in_spacings()) ? mean_spacing(cloud.positions) : 0.0;
  eps = params.epsilon.resolve(spacing);
  cluster = params.cluster_epsilon.resolve(spacing);
  types = primitive_mask(params.types);
  min_points = params.min_points > 0 ? params.min_points : std::max<std::size_t>(30, n_all / 200);
  out.epsilon_used = eps;
  out.cluster_epsilon_used = cluster;
  out.min_points_used = min_points;
  if (!(eps > 0.0) || !(cluster > 0.0)) return false;  // every point at one place: nothing to fit
  cos_max = std::cos(params.max_normal_angle_deg * kDeg);
  band = params.band_in_epsilons * eps;
  samples = (types & kTori) ? 4 : 3;  // a torus needs a fourth oriented point
  return true;
}

// Points relative to the box centre, in Morton order, so that sampling does not depend on the
// input order.
void PrimitiveDetection::sort_in_morton_order() {
  const BoundingBox box = bounding_box(cloud.positions);
  centre = box.center();
  side = std::max(box.extent().maxCoeff(), 1e-300);
  scene = 10.0 * box.diagonal();
  std::vector<std::uint64_t> codes(n_all);
  tbb::parallel_for(std::size_t(0), n_all, [&](std::size_t i) {
    const Eigen::Array3d t = ((cloud.positions[i] - box.min).array() / side * double((1 << kMortonBits) - 1)).round();
    const auto q = t.cast<std::uint64_t>();
    codes[i] = morton_code(q.x(), q.y(), q.z());
  });
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(n_all);
  for (std::uint32_t i = 0; i < n_all; ++i) keyed[i] = {codes[i], i};
  tbb::parallel_sort(keyed.begin(), keyed.end(), [&](const auto& a, const auto& b) {
    if (a.first != b.first) return a.first < b.first;
    // Ties by coordinates, then normal, then index (equal points), so that the order is total.
    const Vector3d &pa = cloud.positions[a.second], &pb = cloud.positions[b.second];
    if (pa != pb) return std::lexicographical_compare(pa.data(), pa.data() + 3, pb.data(), pb.data() + 3);
    const Vector3d &na = cloud.normals[a.second], &nb = cloud.normals[b.second];
    if (na != nb) return std::lexicographical_compare(na.data(), na.data() + 3, nb.data(), nb.data() + 3);
    return a.second < b.second;
  });
  order.resize(n_all);
  for (std::size_t r = 0; r < n_all; ++r) order[r] = keyed[r].second;
  keyed = {};
  pts.resize(n_all), nrm.resize(n_all);
  sorted_codes.resize(n_all);
  usable.resize(n_all);
  tbb::parallel_for(std::size_t(0), n_all, [&](std::size_t r) {
    pts[r] = cloud.positions[order[r]] - centre;
    const Vector3d& nn = cloud.normals[order[r]];
    const double l = nn.norm();
    usable[r] = std::isfinite(l) && l > 0.0;
    nrm[r] = usable[r] ? Vector3d(nn / l) : Vector3d::Zero();
    sorted_codes[r] = codes[order[r]];
  });
}

// Subset 0 about kSmallestSubset points, each next one about twice as large (the last holds
// about half); a point's subset comes from the seed and its rank.
void PrimitiveDetection::draw_scoring_subsets() {
  subset_count = 1;
  while (subset_count < 16 && (n_all >> subset_count) >= kSmallestSubset) ++subset_count;
  subset_ranks.assign(static_cast<std::size_t>(subset_count), {});
  subset_of.assign(n_all, -1);
  remaining.clear();
  std::uint64_t state = mix(params.seed);
  for (std::uint32_t r = 0; r < n_all; ++r) {
    if (!usable[r]) continue;
    const double u = uniform01(state);
    int j = subset_count - 1;
    while (j > 0 && u < std::ldexp(1.0, -(subset_count - j))) --j;
    subset_ranks[std::size_t(j)].push_back(r);
    subset_of[r] = std::int8_t(j);
    remaining.push_back(r);
  }
}

void PrimitiveDetection::build_octrees() {
  leaf_in_subset.assign(n_all, 0);
  leaf_in_all.assign(n_all, 0);
  trees.clear();
  for (auto& ranks : subset_ranks) trees.emplace_back(std::move(ranks), pts, sorted_codes, kMortonBits, leaf_in_subset);
  all.emplace(remaining, pts, sorted_codes, kMortonBits, leaf_in_all);
  evaluated.assign(std::size_t(subset_count) + 1, 0);
  count_subsets();
  assigned.assign(n_all, 0);
  // Octree levels: from the whole box down to cells of a few cluster cells.
  levels = 1;
  while (levels < kMortonBits && side / std::ldexp(1.0, levels + 1) > 2.0 * cluster) ++levels;
  level_weight.assign(std::size_t(levels) + 1, 1.0);
  level_weight[0] = 0.0;
}

bool PrimitiveDetection::searching() const { return remaining.size() >= min_points && failures < kMaxFailures; }

double PrimitiveDetection::assigned_share() const { return 1.0 - double(remaining.size()) / double(n_all); }

bool PrimitiveDetection::compatible(const Primitive& s, std::uint32_t r, double reach) const {
  const Residual res = residual(s, pts[r], nrm[r]);
  return res.distance <= reach && res.cosine >= cos_max;
}

void PrimitiveDetection::count_subsets() {
  for (int j = 0; j < subset_count; ++j) evaluated[std::size_t(j) + 1] = evaluated[std::size_t(j)] + trees[std::size_t(j)].alive();
}

// One more subset (at least kSmallestSubset unassigned points in all, when there are).
void PrimitiveDetection::refine(PrimitiveCandidate& c) const {
  do {
    trees[std::size_t(c.subsets++)].visit(distance_to(c.shape), eps, [&](const std::uint32_t* r, const std::uint32_t* end) {
      for (; r != end; ++r)
        if (!assigned[*r] && compatible(c.shape, *r, eps)) c.hits.push_back(*r);
    });
  } while (c.subsets < subset_count && evaluated[std::size_t(c.subsets)] < kSmallestSubset);
}

// The support among the remaining points: estimate and an interval of about two standard
// deviations of the hypergeometric draw (Schnabel et al. 2007, section 4.4).
void PrimitiveDetection::bound(PrimitiveCandidate& c) const {
  const double left = double(remaining.size());
  const double m = double(evaluated[std::size_t(c.subsets)]), k = double(c.hits.size());
  if (!(m > 0.0)) {
    c.low = c.estimate = 0.0, c.high = left;
    return;
  }
  c.estimate = k / m * left;
  const double p = (k + 1.0) / (m + 2.0);
  const double sd = c.subsets == subset_count ? 0.0 : left * std::sqrt(p * (1.0 - p) / m * std::max(0.0, (left - m) / std::max(left - 1.0, 1.0)));
  c.low = c.estimate - 2.0 * sd;
  c.high = c.estimate + 2.0 * sd;
}

// All compatible unassigned points within `reach`, in Morton order; parallel over leaves.
std::vector<std::uint32_t> PrimitiveDetection::collect(const Primitive& s, double reach) const {
  std::vector<std::uint32_t> leaves;
  all->leaves(distance_to(s), reach, leaves);
  constexpr std::size_t kChunk = 64;
  std::vector<std::vector<std::uint32_t>> parts((leaves.size() + kChunk - 1) / kChunk);
  tbb::parallel_for(std::size_t(0), parts.size(), [&](std::size_t c) {
    for (std::size_t l = c * kChunk; l < std::min(leaves.size(), (c + 1) * kChunk); ++l)
      for (const std::uint32_t* r = all->leaf_begin(leaves[l]); r != all->leaf_end(leaves[l]); ++r)
        if (!assigned[*r] && compatible(s, *r, reach)) parts[c].push_back(*r);
  });
  std::vector<std::uint32_t> idx;
  for (const auto& part : parts) idx.insert(idx.end(), part.begin(), part.end());
  return idx;
}

std::size_t PrimitiveDetection::fit_count(const Primitive& s, const std::vector<std::uint32_t>& probe) const {
  std::size_t fit = 0;
  for (std::uint32_t r : probe) fit += compatible(s, r, eps);
  return fit;
}

bool PrimitiveDetection::same_shape(const Primitive& a, const std::vector<std::uint32_t>& probes_a, const Primitive& b,
                                    const std::vector<std::uint32_t>& probes_b) const {
  if (a.type != b.type || probes_a.empty() || probes_b.empty()) return false;
  return 3 * fit_count(b, probes_a) >= 2 * probes_a.size() && 3 * fit_count(a, probes_b) >= 2 * probes_b.size();
}

// Chance that `draws` draws all miss a primitive of n points: its first point on it, and
// (about) the right level with the other points on it as well; a conservative estimate.
double PrimitiveDetection::miss(double n) const {
  const double hit = n / (double(remaining.size()) * double(levels) * 4.0);
  return std::pow(1.0 - std::min(hit, 1.0), double(draws));
}

bool PrimitiveDetection::gave_up() const { return miss(double(min_points)) < params.probability || draws > kMaxDraws; }

// A minimal set from the random stream of draw `draw`: the first point uniformly among the
// unassigned ones, the others from its octree cell at a level chosen by the levels' past success.
bool PrimitiveDetection::draw_minimal_set(std::size_t draw, double total_weight, std::uint32_t (&rs)[4], int& level) const {
  std::uint64_t st = mix(stream ^ mix(draw));
  const std::uint32_t r0 = remaining[std::size_t(uniform01(st) * double(remaining.size()))];
  double pick = uniform01(st) * total_weight;
  level = 1;
  while (level < levels && pick >= level_weight[std::size_t(level)]) pick -= level_weight[std::size_t(level++)];
  const int shift = 3 * (kMortonBits - level);
  const std::uint64_t lo_code = (sorted_codes[r0] >> shift) << shift;
  const std::uint64_t hi_code = lo_code | ((std::uint64_t(1) << shift) - 1);
  const std::size_t lo = std::size_t(std::lower_bound(sorted_codes.begin(), sorted_codes.end(), lo_code) - sorted_codes.begin());
  const std::size_t hi = std::size_t(std::upper_bound(sorted_codes.begin(), sorted_codes.end(), hi_code) - sorted_codes.begin());
  if (hi - lo < std::size_t(samples)) return false;
  rs[0] = rs[1] = rs[2] = rs[3] = r0;
  for (int k = 1; k < samples; ++k) {
    bool ok = false;
    for (int attempt = 0; attempt < 8 && !ok; ++attempt) {
      const std::uint32_t r = std::uint32_t(lo + std::size_t(uniform01(st) * double(hi - lo)));
      ok = usable[r] && !assigned[r] && std::find(rs, rs + k, r) == rs + k;
      if (ok) rs[k] = r;
    }
    if (!ok) return false;
  }
  return true;
}

// The candidates of minimal set `b` of the batch, scored on the first subset, less those that
// describe a failed shape.
void PrimitiveDetection::draw_one(std::size_t b, double total_weight) {
  drawn[b].clear();
  std::uint32_t rs[4];
  int level = 0;
  if (!draw_minimal_set(total_draws + b, total_weight, rs, level)) return;
  Vector3d p[4], nn[4];
  for (int k = 0; k < samples; ++k) p[k] = pts[rs[k]], nn[k] = nrm[rs[k]];
  std::vector<Primitive> made;
  make_candidates(p, nn, samples, types, eps, cos_max, scene, made);
  for (const Primitive& s : made) {
    PrimitiveCandidate c;
    c.shape = s;
    c.level = level;
    refine(c);
    const std::vector<std::uint32_t> mine = probes(c.hits);
    if (std::any_of(failed.begin(), failed.end(), [&](const FailedShape& f) { return same_shape(f.shape, f.probes, s, mine); })) continue;
    drawn[b].push_back(std::move(c));
  }
}

// A batch of minimal sets, in parallel, each from its own random stream.
void PrimitiveDetection::draw_candidates() {
  const double total_weight = std::accumulate(level_weight.begin(), level_weight.end(), 0.0);
  tbb::parallel_for(std::size_t(0), kBatch, [&](std::size_t b) { draw_one(b, total_weight); });
  draws += kBatch;
  total_draws += kBatch;
  for (auto& batch : drawn)
    for (PrimitiveCandidate& c : batch) {
      bound(c);
      if (c.high >= double(min_points)) candidates.push_back(std::move(c));
    }
  out.candidates = total_draws;
}

// Lazy scoring: refine the candidate with the best estimate and those whose interval overlaps
// its, one subset at a time, until the best stands apart.
std::size_t PrimitiveDetection::score_lazily() {
  std::size_t top = 0;
  std::vector<std::size_t> todo;
  for (;;) {
    for (PrimitiveCandidate& c : candidates) bound(c);
    top = 0;
    for (std::size_t i = 1; i < candidates.size(); ++i)
      if (candidates[i].estimate > candidates[top].estimate) top = i;
    todo.clear();
    for (std::size_t i = 0; i < candidates.size(); ++i)
      if (i != top && candidates[i].subsets < subset_count && candidates[i].high >= candidates[top].low) todo.push_back(i);
    if (todo.empty()) break;
    if (candidates[top].subsets < subset_count) todo.push_back(top);
    tbb::parallel_for(std::size_t(0), todo.size(), [&](std::size_t t) { refine(candidates[todo[t]]); });
  }
  return top;
}

PrimitiveDetection::Next PrimitiveDetection::choose_best() {
  if (candidates.empty()) return gave_up() ? Next::Stop : Next::Draw;
  best = score_lazily();
  const double found = candidates[best].estimate;
  if (found < double(min_points)) return gave_up() ? Next::Stop : Next::Draw;
  if (miss(found) >= params.probability && draws <= kMaxDraws) return Next::Draw;
  return Next::Extract;
}

// A least-squares refit and the compatible points of the refit within the band, twice, unless
// the refit loses its points.
void PrimitiveDetection::settle(Primitive& s, std::vector<std::uint32_t>& points) const {
  for (int pass = 0; pass < 2 && points.size() >= min_points; ++pass) {
    const std::optional<Primitive> fitted = refit(s, pts, nrm, points);
    if (!fitted) break;
    std::vector<std::uint32_t> again = largest_component(pts, collect(*fitted, band), cluster);
    if (again.size() < points.size() * 9 / 10) break;  // the refit lost its points: keep the sample's fit
    s = *fitted;
    points = std::move(again);
  }
}

ExtractedShape PrimitiveDetection::extract_points(const Primitive& shape) const {
  ExtractedShape e{shape, largest_component(pts, collect(shape, eps), cluster)};
  settle(e.shape, e.points);
  return e;
}

// A curved primitive can stand in for a noisy plane (a flat cone, a wide cylinder): the plane,
// the simpler model, is taken when it holds at least as many points.
void PrimitiveDetection::prefer_plane(ExtractedShape& e) const {
  if (e.shape.type == PrimitiveType::Plane || !(types & kPlanes) || e.points.size() < min_points) return;
  Primitive plane;
  plane.type = PrimitiveType::Plane;
  if (std::optional<Primitive> fitted = refit(plane, pts, nrm, e.points)) {
    std::vector<std::uint32_t> flat = largest_component(pts, collect(*fitted, band), cluster);
    settle(*fitted, flat);
    if (flat.size() >= e.points.size()) e.shape = *fitted, e.points = std::move(flat);
  }
}

// Its points are scattered (Schnabel et al.: the score is the largest component): it and the
// candidates describing the same shape are dropped, and so are later draws of it.
void PrimitiveDetection::drop_scattered(const PrimitiveCandidate& chosen) {
  FailedShape f{chosen.shape, probes(chosen.hits)};
  std::erase_if(candidates, [&](const PrimitiveCandidate& c) { return same_shape(f.shape, f.probes, c.shape, probes(c.hits)); });
  failed.push_back(std::move(f));
  ++failures;
}

void PrimitiveDetection::assign_points(ExtractedShape e, int level) {
  failures = 0;
  level_weight[std::size_t(level)] += 1.0;
  double squares = 0.0;
  for (std::uint32_t r : e.points) {
    const double d = residual(e.shape, pts[r], nrm[r]).distance;
    squares += d * d;
    assigned[r] = 1;
    all->remove(leaf_in_all[r]);
    trees[std::size_t(subset_of[r])].remove(leaf_in_subset[r]);
    out.labels[order[r]] = std::int32_t(out.primitives.size());
  }
  e.shape.inliers = e.points.size();
  e.shape.rms = std::sqrt(squares / double(e.points.size()));
  e.shape.point += centre;
  out.primitives.push_back(e.shape);
  // The earlier draws still count, as that many draws among the fewer points left would miss
  // a primitive as often (the chance of a hit grows as 1 / remaining).
  const std::size_t before = remaining.size();
  std::erase_if(remaining, [&](std::uint32_t r) { return assigned[r] != 0; });
  draws = std::size_t(double(draws) * double(remaining.size()) / double(before));
  count_subsets();
  tbb::parallel_for(std::size_t(0), candidates.size(), [&](std::size_t i) {
    std::erase_if(candidates[i].hits, [&](std::uint32_t r) { return assigned[r] != 0; });
  });
  std::erase_if(candidates, [&](PrimitiveCandidate& c) {
    bound(c);
    return c.high < double(min_points);
  });
}

// Extract: compatible points, their largest connected component, a least-squares refit, and
// twice again with the refitted primitive and the wider band.
void PrimitiveDetection::extract_best() {
  const PrimitiveCandidate chosen = std::move(candidates[best]);
  candidates.erase(candidates.begin() + std::ptrdiff_t(best));
  ExtractedShape e = extract_points(chosen.shape);
  prefer_plane(e);
  if (e.points.size() < min_points) return drop_scattered(chosen);
  assign_points(std::move(e), chosen.level);
}

PrimitiveResult PrimitiveDetection::result() && {
  out.unassigned = static_cast<std::size_t>(std::count(out.labels.begin(), out.labels.end(), -1));
  return std::move(out);
}

}  // namespace detail

PrimitiveResult detect_primitives(const PointCloud& cloud, const PrimitiveParams& params, const ProgressCallback& progress) {
  params.validate();
  if (cloud.size() > 0 && !cloud.has_normals())
    throw UsageError("detect_primitives: the cloud has no normals (estimate them first: pointsurf normals)");
  detail::PrimitiveDetection x(cloud, params);
  if (cloud.size() < 3 || !x.resolve_parameters()) return std::move(x).result();
  x.sort_in_morton_order();
  x.draw_scoring_subsets();
  x.build_octrees();
  detail::ProgressReporter reporter(progress, 0.0, 1.0, cloud.size());
  while (x.searching()) {
    reporter.report(x.assigned_share());
    if (reporter.cancelled()) break;
    x.draw_candidates();
    const detail::PrimitiveDetection::Next next = x.choose_best();
    if (next == detail::PrimitiveDetection::Next::Stop) break;
    if (next == detail::PrimitiveDetection::Next::Extract) x.extract_best();
  }
  reporter.throw_if_cancelled();
  return std::move(x).result();
}

const ResultTable<Primitive>& Primitive::results() {
  static const ResultTable<Primitive> table = [] {
    using S = Primitive;
    const std::string u = "cloud units";
    auto list = [](const Eigen::Vector3d& v) { return std::vector<double>{v.x(), v.y(), v.z()}; };
    ResultTable<S> t;
    t.computed("type", ResultType::Text, [](const S& s) { return ResultValue(std::string(primitive_type_name(s.type))); },
               "Type of the primitive: plane, sphere, cylinder, cone or torus");
    t.computed("point", ResultType::Numbers, [list](const S& s) { return ResultValue(list(s.point)); },
               "Plane: the inliers' centroid; sphere, torus: centre; cylinder: axis point; cone: apex")
        .with_unit(u);
    t.computed("axis", ResultType::Numbers, [list](const S& s) { return ResultValue(list(s.axis)); },
               "Plane: unit normal; cylinder, cone, torus: unit axis (cone: from the apex into the cone)");
    t.number("radius", &S::radius, "Sphere, cylinder: radius; torus: major radius").with_unit(u);
    t.number("angle_deg", &S::angle_deg, "Cone: half opening angle").with_unit("degrees");
    t.count("inliers", &S::inliers, "Points assigned to it");
    t.number("rms", &S::rms, "RMS distance of those points to it").with_unit(u).lower_is_better();
    t.number("minor_radius", &S::minor_radius, "Torus: tube radius").with_unit(u);
    return t;
  }();
  return table;
}

const ResultTable<PrimitiveResult>& PrimitiveResult::results() {
  static const ResultTable<PrimitiveResult> table = [] {
    ResultTable<PrimitiveResult> t;
    t.count("candidates", &PrimitiveResult::candidates, "Candidate primitives drawn (ransac)").as_count();
    return t;
  }();
  return table;
}

}  // namespace pointsurf
