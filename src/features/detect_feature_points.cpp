// SPDX-License-Identifier: GPL-3.0-or-later
#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <cmath>
#include <functional>
#include <numbers>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include <Eigen/Eigenvalues>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "core/detail/local_pca.h"
#include "core/detail/progress_reporter.h"
#include "pointsurf/core/error.h"
#include "pointsurf/features/feature_points.h"

namespace pointsurf {
namespace {

// Multiple of the median variation in the derived candidate threshold, and the share of a
// crease's own variation that the floor keeps (see the header).
constexpr double kVariationMedianFactor = 4.0;
constexpr double kCreaseVariationShare = 0.5;

// Surface variation at a point on a straight crease of the given turn, with the neighbours
// uniform on a disc of radius R folded along a diameter (faces tilted by +-turn/2): across the
// crease z = |x| sin(turn/2), so l0 = (1/4 - 16/(9 pi^2)) R^2 sin^2, l1 = R^2 cos^2 / 4,
// l2 = R^2 / 4. Scale-free; 0.0084 at 28 degrees, 0.085 at 90.
double crease_variation(double turn_deg) {
  const double half = 0.5 * turn_deg * std::numbers::pi / 180.0;
  const double s2 = std::sin(half) * std::sin(half), c2 = 1.0 - s2;
  const double l0 = (0.25 - 16.0 / (9.0 * std::numbers::pi * std::numbers::pi)) * s2;
  return l0 / (l0 + 0.25 * c2 + 0.25);
}

// A corner is labelled within this many dd of the meeting point of three planes; the planes'
// normals must span space (|det| of the three unit normals at least kMinCornerDeterminant, 1 for
// a cube's corner) so that the meeting point is well defined.
constexpr double kCornerReach = 2.0;
constexpr double kMinCornerDeterminant = 0.1;
// Leader clustering keeps at most this many clusters; later neighbours join the nearest one.
constexpr int kMaxClusters = 8;

struct LocalFit {
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // zero when degenerate
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();  // offset from the reference point
  double variation = 1.0;                             // 1 (worse than any real value) when degenerate
};

// PCA of points given as offsets from a reference point (see detail::local_pca).
template <class Offsets>
LocalFit fit_plane(const Offsets& offsets, std::size_t m) {
  LocalFit out;
  const detail::LocalPca pca = detail::local_pca(offsets, m);
  if (!pca.valid) return out;
  out.normal = pca.normal();
  out.centroid = pca.mean;
  out.variation = pca.variation();
  return out;
}

LocalFit fit_neighbourhood(const KdTree& tree, const Eigen::Vector3d& center, const std::vector<Neighbor>& neighbors) {
  return fit_plane([&](std::size_t i) { return Eigen::Vector3d(tree.point(neighbors[i].index) - center); }, neighbors.size());
}

struct Cluster {
  Eigen::Vector3d normal_sum = Eigen::Vector3d::Zero();  // sign-aligned sum of member normals
  int members = 0;
};

// Per-thread scratch of the screening, reused across candidates (no per-point allocation).
struct ScreenBuffers {
  std::vector<int> assignment;
  std::vector<Eigen::Vector3d> offsets;
  std::array<Cluster, kMaxClusters> clusters;
  // Where three planes of the last screened neighbourhood meet, as an offset from its point,
  // when that is inside the neighbourhood but farther than kCornerReach dd (see pass 5).
  std::optional<Eigen::Vector3d> far_corner;
};

// Index of the cluster whose mean direction is nearest to n (unoriented), and that |cos|.
std::pair<int, double> nearest_cluster(const std::array<Cluster, kMaxClusters>& clusters, int count, const Eigen::Vector3d& n) {
  int best = -1;
  double best_cos = -1.0;
  for (int c = 0; c < count; ++c) {
    const double len = clusters[c].normal_sum.norm();
    if (len == 0.0) continue;
    const double cos = std::abs(clusters[c].normal_sum.dot(n)) / len;
    if (cos > best_cos) best_cos = cos, best = c;
  }
  return {best, best_cos};
}

void add_to(Cluster& cluster, const Eigen::Vector3d& n) {
  cluster.normal_sum += cluster.normal_sum.dot(n) < 0.0 ? Eigen::Vector3d(-n) : n;
  ++cluster.members;
}

// Number of distinct neighbour planes within `dd` of p (the screening of one candidate).
int planes_near(const KdTree& tree, const Eigen::Vector3d& p, std::span<const std::uint32_t> neighbors,
                const std::vector<Eigen::Vector3d>& normals, double cos_dn, double dd, double min_sin2, int min_points,
                double reach, ScreenBuffers& b) {
  const std::size_t m = neighbors.size();
  b.far_corner.reset();
  b.assignment.assign(m, -1);
  int count = 0;
  // Leader clustering, nearest neighbour first.
  for (std::size_t i = 0; i < m; ++i) {
    const Eigen::Vector3d& n = normals[neighbors[i]];
    if (n.squaredNorm() == 0.0) continue;
    auto [best, cos] = nearest_cluster(b.clusters, count, n);
    if ((best < 0 || cos < cos_dn) && count < kMaxClusters) {
      b.clusters[count] = Cluster{};
      best = count++;
    }
    add_to(b.clusters[best], n);
    b.assignment[i] = best;
  }
  if (count < 2) return count == 1 ? 1 : 0;
  // One reassignment to the nearest final mean: the leader pass depends on the visiting order.
  std::array<Cluster, kMaxClusters> means = b.clusters;
  for (int c = 0; c < count; ++c) b.clusters[c] = Cluster{};
  for (std::size_t i = 0; i < m; ++i) {
    if (b.assignment[i] < 0) continue;
    const Eigen::Vector3d& n = normals[neighbors[i]];
    const int best = nearest_cluster(means, count, n).first;
    add_to(b.clusters[best], n);
    b.assignment[i] = best;
  }
  // Planes of the clusters, largest first; near-parallel duplicates of a larger one are dropped.
  std::array<int, kMaxClusters> by_size{};
  for (int c = 0; c < count; ++c) by_size[c] = c;
  std::sort(by_size.begin(), by_size.begin() + count,
            [&](int a, int c) { return b.clusters[a].members > b.clusters[c].members || (b.clusters[a].members == b.clusters[c].members && a < c); });
  std::array<Eigen::Vector3d, kMaxClusters> kept;
  std::array<double, kMaxClusters> kept_offset{};  // n . c of every kept plane
  std::array<double, kMaxClusters> near_offset{};  // n . c of the planes within dd
  std::array<Eigen::Vector3d, kMaxClusters> near_normal;
  int kept_count = 0, near = 0;
  for (int r = 0; r < count; ++r) {
    const int c = by_size[r];
    if (b.clusters[c].members < min_points) break;
    b.offsets.clear();
    for (std::size_t i = 0; i < m; ++i)
      if (b.assignment[i] == c) b.offsets.push_back(tree.point(neighbors[i]) - p);
    const LocalFit plane = fit_plane([&](std::size_t i) { return b.offsets[i]; }, b.offsets.size());
    if (plane.normal.squaredNorm() == 0.0) continue;
    bool duplicate = false;
    for (int q = 0; q < kept_count; ++q) duplicate = duplicate || std::abs(kept[q].dot(plane.normal)) > cos_dn;
    if (duplicate) continue;
    kept_offset[kept_count] = plane.normal.dot(plane.centroid);
    kept[kept_count++] = plane.normal;
    // p is the origin of the offsets: its distance to the plane is |n . centroid|.
    if (const double offset = kept_offset[kept_count - 1]; std::abs(offset) <= dd) {
      near_offset[near] = offset;
      near_normal[near++] = plane.normal;
    }
  }
  // Corner: three planes, pairwise turning by at least min_turn, meet within kCornerReach dd
  // of p. Only about one point lies within dd of a corner's three faces, so the plane test
  // alone often leaves a corner without a Corner label.
  for (int a = 0; a < kept_count; ++a)
    for (int c = a + 1; c < kept_count; ++c)
      for (int e = c + 1; e < kept_count; ++e) {
        Eigen::Matrix3d normals_abc;
        normals_abc << kept[a].transpose(), kept[c].transpose(), kept[e].transpose();
        if (kept[a].cross(kept[c]).squaredNorm() < min_sin2 || kept[a].cross(kept[e]).squaredNorm() < min_sin2 ||
            kept[c].cross(kept[e]).squaredNorm() < min_sin2 || std::abs(normals_abc.determinant()) < kMinCornerDeterminant)
          continue;
        const Eigen::Vector3d corner = normals_abc.partialPivLu().solve(Eigen::Vector3d(kept_offset[a], kept_offset[c], kept_offset[e]));
        if (corner.norm() <= kCornerReach * dd) return 3;
        if (corner.norm() <= reach && !b.far_corner) b.far_corner = corner;
      }
  if (near < 2) return near;
  // A pair of planes makes p an edge point when they turn by at least min_turn and p lies
  // within dd of their intersection line. Near a shallow crease (turn t) a point x from the line
  // is only x sin(t) from the other face's plane, so the plane test alone labels a band
  // 1 / sin(t) times wider than at a right angle.
  int pairs = 0;
  for (int a = 0; a < near; ++a)
    for (int c = a + 1; c < near; ++c) {
      const Eigen::Vector3d d = near_normal[a].cross(near_normal[c]);
      const double d2 = d.squaredNorm();
      if (!(d2 > 0.0) || d2 < min_sin2) continue;
      // The point of the line nearest p (the origin) lies in the span of the two normals.
      const Eigen::Vector3d foot = (near_offset[a] * near_normal[c].cross(d) + near_offset[c] * d.cross(near_normal[a])) / d2;
      pairs += foot.norm() <= dd;
    }
  return pairs == 0 ? 1 : pairs == 1 || near == 2 ? 2 : 3;
}

}  // namespace

const EnumNames<FeatureNormals>& feature_normals_names() {
  static const EnumNames<FeatureNormals> names{{{FeatureNormals::Robust, "robust"}, {FeatureNormals::Input, "input"}}};
  return names;
}

const FieldTable<FeatureParams>& FeatureParams::fields() {
  static const FieldTable<FeatureParams> table = [] {
    using P = FeatureParams;
    FieldTable<P> t;
    t.integer("k", &P::k, "Neighbours per point").at_least(6).unit("points");
    t.number("variation_threshold", &P::variation_threshold,
             "Candidate surface-variation threshold; 0: max(half a min_turn_deg crease's, 4 x median variation)")
        .range(0.0, 1.0 / 3.0, false, true);
    t.number("cluster_angle_deg", &P::cluster_angle_deg, "Normal-angle clustering threshold").unit("degrees").range(0.0, 90.0, true, true).was("dn_deg");
    t.number("min_turn_deg", &P::min_turn_deg, "Smallest crease kept (angle between its two planes); sets the candidate floor")
        .unit("degrees")
        .range(0.0, 90.0, true, true);
    t.length("plane_distance", &P::plane_distance, "Point-to-plane distance of a cluster's plane").positive().was("dd").was("dd_in_spacings");
    t.integer("min_cluster_points", &P::min_cluster_points, "Fewest neighbours a cluster needs to give a plane, at most k").at_least(3);
    t.choice("normals", &P::normals, feature_normals_names(),
             "Normals to cluster by: robust (flattest shifted neighbourhood) or input (estimated when absent)");
    return t;
  }();
  return table;
}

void FeatureParams::validate() const {
  const FeatureParams& params = *this;
  if (params.k < 6) throw UsageError(fmt::format("detect_feature_points: k must be >= 6, got {}", params.k));
  if (!(params.variation_threshold >= 0.0 && params.variation_threshold < 1.0 / 3.0))
    throw UsageError(fmt::format("detect_feature_points: variation_threshold must be in [0, 1/3) (0: derived), got {}",
                                 params.variation_threshold));
  if (!(params.cluster_angle_deg > 0.0 && params.cluster_angle_deg < 90.0))
    throw UsageError(fmt::format("detect_feature_points: cluster_angle_deg must be in (0, 90) degrees, got {}", params.cluster_angle_deg));
  if (!(params.min_turn_deg > 0.0 && params.min_turn_deg < 90.0))
    throw UsageError(fmt::format("detect_feature_points: min_turn_deg must be in (0, 90) degrees, got {}", params.min_turn_deg));
  if (params.min_cluster_points < 3 || params.min_cluster_points > params.k)
    throw UsageError(fmt::format("detect_feature_points: min_cluster_points must be in [3, k = {}], got {}", params.k,
                                 params.min_cluster_points));
  fields().validate(*this, "detect_feature_points");
}

FeatureResult detect_feature_points(PointCloud& cloud, const FeatureParams& params, const KdTree* tree,
                                    const ProgressCallback& progress) {
  const std::size_t n = cloud.size();
  params.validate();
  if (n < static_cast<std::size_t>(params.k) + 1)
    throw UsageError(fmt::format("detect_feature_points: needs at least k + 1 = {} points, got {}", params.k + 1, n));
  const bool input_normals = params.normals == FeatureNormals::Input;
  if (input_normals && cloud.normals.size() != n)
    throw UsageError(fmt::format("detect_feature_points: normals = Input needs one normal per point, the cloud has {} for {} points",
                                 cloud.normals.size(), n));
  if (tree != nullptr && tree->size() != n)
    throw UsageError(fmt::format("detect_feature_points: the kd-tree holds {} points but the cloud has {}", tree->size(), n));

  std::optional<KdTree> own_tree;
  if (tree == nullptr) tree = &own_tree.emplace(cloud.positions);
  FeatureResult result;
  result.mean_spacing = mean_spacing(*tree);
  result.dd_used = params.plane_distance.resolve(result.mean_spacing);

  const std::span<const std::uint32_t> order = tree->spatial_order();
  const std::size_t k = static_cast<std::size_t>(params.k);
  const std::size_t grain = 256;
  // Progress shares: the PCA of every point dominates; the other passes visit candidates and
  // their neighbours only.
  constexpr double kPcaShare = 0.6, kNeighborsShare = 0.7, kRobustShare = 0.85;

  // Pass 1: PCA of every k-neighbourhood: variation, normal, and the squared reach (distance to
  // the k-th neighbour), which tells the robust-normal pass whose neighbourhoods contain a point.
  std::vector<double> variation(n), reach2(n);
  std::vector<Eigen::Vector3d> pca_normals(input_normals ? 0 : n);
  tbb::enumerable_thread_specific<std::vector<Neighbor>> buffers;
  {
    detail::ProgressReporter reporter(progress, 0.0, kPcaShare, n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, grain), [&](const tbb::blocked_range<std::size_t>& r) {
      if (reporter.cancelled()) return;
      std::vector<Neighbor>& neighbors = buffers.local();
      for (std::size_t pos = r.begin(); pos != r.end(); ++pos) {
        const std::uint32_t i = order[pos];
        const Eigen::Vector3d& p = cloud.positions[i];
        tree->knn(p, k, neighbors);
        const LocalFit fit = fit_neighbourhood(*tree, p, neighbors);
        variation[i] = fit.variation;
        reach2[i] = neighbors.back().squared_distance;
        if (!input_normals) pca_normals[i] = fit.normal;
      }
      reporter.advance(r.size());
    });
    reporter.throw_if_cancelled();
  }

  // Candidate threshold from the data: the median variation measures how much noise and smooth
  // curvature ordinary points carry.
  if (params.variation_threshold > 0.0) {
    result.variation_threshold_used = params.variation_threshold;
  } else {
    std::vector<double> sorted = variation;
    auto mid = sorted.begin() + static_cast<std::ptrdiff_t>(n / 2);
    std::nth_element(sorted.begin(), mid, sorted.end());
    const double floor = kCreaseVariationShare * crease_variation(params.min_turn_deg);
    result.variation_threshold_used = std::min(std::max(floor, kVariationMedianFactor * *mid), 0.3);
  }
  const double threshold = result.variation_threshold_used;
  std::vector<std::uint32_t> candidates;  // in spatial order
  for (const std::uint32_t i : order)
    if (variation[i] > threshold) candidates.push_back(i);
  const std::size_t c = candidates.size();
  result.candidates = c;

  // Pass 2: the candidates' neighbours (k each, since n > k), kept for the screening; the points
  // among them are the only ones whose robust normal is needed.
  std::vector<std::uint32_t> candidate_neighbors(c * k);
  std::vector<std::atomic<std::uint8_t>> needed(input_normals ? 0 : n);
  {
    detail::ProgressReporter reporter(progress, kPcaShare, kNeighborsShare, c);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, c, grain), [&](const tbb::blocked_range<std::size_t>& r) {
      if (reporter.cancelled()) return;
      std::vector<Neighbor>& neighbors = buffers.local();
      for (std::size_t q = r.begin(); q != r.end(); ++q) {
        tree->knn(cloud.positions[candidates[q]], k, neighbors);
        for (std::size_t j = 0; j < k; ++j) {
          candidate_neighbors[q * k + j] = neighbors[j].index;
          if (!input_normals) needed[neighbors[j].index].store(1, std::memory_order_relaxed);
        }
      }
      reporter.advance(r.size());
    });
    reporter.throw_if_cancelled();
  }

  // Pass 3 (Robust): each needed point takes the normal of the flattest neighbourhood containing it.
  std::vector<Eigen::Vector3d> robust_normals(input_normals ? 0 : n, Eigen::Vector3d::Zero());
  if (!input_normals) {
    detail::ProgressReporter reporter(progress, kNeighborsShare, kRobustShare, n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, grain), [&](const tbb::blocked_range<std::size_t>& r) {
      if (reporter.cancelled()) return;
      std::vector<Neighbor>& neighbors = buffers.local();
      for (std::size_t pos = r.begin(); pos != r.end(); ++pos) {
        const std::uint32_t i = order[pos];
        if (needed[i].load(std::memory_order_relaxed) == 0) continue;
        tree->knn(cloud.positions[i], k, neighbors);
        std::uint32_t best = i;
        for (const Neighbor& nb : neighbors)
          if (nb.squared_distance <= reach2[nb.index] && variation[nb.index] < variation[best]) best = nb.index;
        robust_normals[i] = pca_normals[best];
      }
      reporter.advance(r.size());
    });
    reporter.throw_if_cancelled();
  }
  const std::vector<Eigen::Vector3d>& normals = input_normals ? cloud.normals : robust_normals;

  // Pass 4: screening of the candidates.
  std::vector<double> labels(n, 0.0);
  const double cos_dn = std::cos(params.cluster_angle_deg * std::numbers::pi / 180.0);
  const double min_sin2 = std::pow(std::sin(params.min_turn_deg * std::numbers::pi / 180.0), 2);
  tbb::enumerable_thread_specific<ScreenBuffers> screen;
  tbb::enumerable_thread_specific<std::array<std::size_t, 2>> counts(std::array<std::size_t, 2>{0, 0});
  tbb::enumerable_thread_specific<std::vector<Eigen::Vector3d>> far_corners;
  {
    detail::ProgressReporter reporter(progress, kRobustShare, 1.0, c);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, c, grain), [&](const tbb::blocked_range<std::size_t>& r) {
      if (reporter.cancelled()) return;
      ScreenBuffers& b = screen.local();
      std::array<std::size_t, 2>& count = counts.local();
      for (std::size_t q = r.begin(); q != r.end(); ++q) {
        const std::uint32_t i = candidates[q];
        const std::span<const std::uint32_t> neighbors(candidate_neighbors.data() + q * k, k);
        const int planes = planes_near(*tree, cloud.positions[i], neighbors, normals, cos_dn, result.dd_used, min_sin2,
                                       params.min_cluster_points, std::sqrt(reach2[i]), b);
        if (b.far_corner) far_corners.local().push_back(cloud.positions[i] + *b.far_corner);
        if (planes >= 3) {
          labels[i] = double(FeatureLabel::Corner);
          ++count[1];
        } else if (planes == 2) {
          labels[i] = double(FeatureLabel::Edge);
          ++count[0];
        }
      }
      reporter.advance(r.size());
    });
    reporter.throw_if_cancelled();
    reporter.report(1.0);
    reporter.throw_if_cancelled();
  }
  for (const auto& count : counts) {
    result.edges += count[0];
    result.corners += count[1];
  }
  // Pass 5: a corner whose three faces meet a few spacings from every candidate (random samples
  // leave a corner's own neighbourhoods with too few points of one face) is still found by the
  // candidates farther out, whose three planes meet there: the sample nearest that meeting point
  // is a Corner when it lies within kCornerReach dd of it.
  std::vector<Neighbor> nearest;
  for (const auto& located : far_corners)
    for (const Eigen::Vector3d& corner : located) {
      tree->knn(corner, 1, nearest);
      if (nearest.empty() || nearest[0].squared_distance > std::pow(kCornerReach * result.dd_used, 2)) continue;
      double& label = labels[nearest[0].index];
      if (label == double(FeatureLabel::Corner)) continue;
      if (label == double(FeatureLabel::Edge)) --result.edges;
      label = double(FeatureLabel::Corner);
      ++result.corners;
    }
  // A field "feature" already there keeps its old type through add(), hence the explicit type.
  ScalarField& field = cloud.fields.add("feature", 0, ScalarType::UInt8);
  field.type = ScalarType::UInt8;
  field.values = std::move(labels);
  return result;
}

const ResultTable<FeatureResult>& FeatureResult::results() {
  static const ResultTable<FeatureResult> table = [] {
    ResultTable<FeatureResult> t;
    t.count("candidates", &FeatureResult::candidates, "Points whose variation exceeded the threshold").as_count();
    t.count("edges", &FeatureResult::edges, "Points labelled edge").as_count();
    t.count("corners", &FeatureResult::corners, "Points labelled corner").as_count();
    t.number("mean_spacing", &FeatureResult::mean_spacing, "Mean distance to the nearest neighbour").with_unit("cloud units");
    return t;
  }();
  return table;
}

}  // namespace pointsurf
