// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/register/align.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <fmt/format.h>
#include <nanoflann.hpp>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "core/detail/progress_reporter.h"
#include "pointsurf/core/error.h"
#include "pointsurf/spatial/kd_tree.h"
#include "register/detail/align_kabsch.h"

namespace pointsurf {
namespace {

using MatchList = std::vector<std::pair<std::uint32_t, std::uint32_t>>;
constexpr double kDegToRad = 0.017453292519943295769;

// ---------------------------------------------------------------------------------------------
// Nearest neighbours in descriptor space.

// The valid rows of a descriptor set, as nanoflann reads them.
struct DescriptorRows {
  const Descriptors* descriptors = nullptr;
  std::vector<std::uint32_t> rows;  // indices of the valid descriptors

  std::size_t kdtree_get_point_count() const { return rows.size(); }
  float kdtree_get_pt(std::uint32_t k, std::size_t dim) const {
    return descriptors->values[std::size_t(rows[k]) * descriptors->dimension + dim];
  }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};

using DescriptorMetric = nanoflann::L2_Simple_Adaptor<float, DescriptorRows, float, std::uint32_t>;
using DescriptorIndex = nanoflann::KDTreeSingleIndexAdaptor<DescriptorMetric, DescriptorRows, -1, std::uint32_t>;

class DescriptorTree {
public:
  explicit DescriptorTree(const Descriptors& d) {
    rows_.descriptors = &d;
    for (std::uint32_t i = 0; i < d.size(); ++i)
      if (d.valid[i]) rows_.rows.push_back(i);
    if (!rows_.rows.empty())
      index_ = std::make_unique<DescriptorIndex>(static_cast<int>(d.dimension), rows_, nanoflann::KDTreeSingleIndexAdaptorParams(10));
  }
  bool empty() const { return rows_.rows.empty(); }
  // The descriptor index of the nearest valid row to `query` (exact search).
  std::uint32_t nearest(const float* query) const {
    std::uint32_t k = 0;
    float d = 0.0f;
    nanoflann::KNNResultSet<float, std::uint32_t, std::uint32_t> result(1);
    result.init(&k, &d);
    index_->findNeighbors(result, query, nanoflann::SearchParams());
    return rows_.rows[k];
  }

private:
  DescriptorRows rows_;
  std::unique_ptr<DescriptorIndex> index_;
};

// ---------------------------------------------------------------------------------------------
// RANSAC over triples of matches.

// A small, fast generator seeded per trial, so that a trial draws the same triple whichever
// thread runs it (splitmix64, Steele et al. 2014).
struct TrialRng {
  std::uint64_t state;
  std::uint64_t next() {
    std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  // Uniform in [0, n) (Lemire's multiply-shift; the bias is below 2^-32 for n < 2^32).
  std::uint32_t below(std::uint32_t n) { return static_cast<std::uint32_t>(((next() >> 32) * std::uint64_t(n)) >> 32); }
};

struct Model {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  std::size_t count = 0;  // inlier matches
  std::size_t hits = 0;   // points of the fitness sample with a target point within the distance
  std::size_t trial = std::numeric_limits<std::size_t>::max();
  // Most sample hits, then most inlier matches, then the earliest trial (so the answer does
  // not depend on the number of threads or on scheduling).
  bool better_than(const Model& o) const {
    if (hits != o.hits) return hits > o.hits;
    if (count != o.count) return count > o.count;
    return trial < o.trial;
  }
};

// Candidates with fewer inlier matches than this are not scored by fitness.
constexpr double kGateShare = 0.5;  // of the most inlier matches so far
constexpr std::size_t kMinCount = 3;
std::size_t gate(std::size_t best_count) {
  return std::max(kMinCount, static_cast<std::size_t>(std::ceil(kGateShare * double(best_count))));
}

// Up to kSampleSize source points spread over the cloud, in the frame centred on `center`:
// the fitness of a candidate is the share of them with a target point within the distance.
constexpr std::size_t kSampleSize = 1000;
constexpr int kPolishRounds = 10;  // point-to-point steps on the sample after RANSAC

class FitnessSample {
public:
  FitnessSample(const PointCloud& source, const Eigen::Vector3d& center, const KdTree& target_tree, double max_distance)
      : center_(center), tree_(target_tree), max_distance_(max_distance) {
    const std::size_t n = source.size(), count = std::min(n, kSampleSize);
    for (std::size_t k = 0; k < count; ++k) points_.push_back(source.positions[k * n / count] - center);
  }
  struct Pair {
    Eigen::Vector3d source, target;  // local frame
    std::uint32_t target_index;
  };
  // Sample points and their nearest target points within the distance.
  void pairs(const Eigen::Matrix3d& r, const Eigen::Vector3d& t, std::vector<Neighbor>& nb, std::vector<Pair>& out) const {
    out.clear();
    each_nearest(r, t, nb, [&](const Eigen::Vector3d& x, const Neighbor* hit) {
      if (hit != nullptr) out.push_back({x, tree_.point(hit->index) - center_, hit->index});
    });
  }
  // The truncated squared distance of the sample (MSAC's cost, Torr and Zisserman 2000):
  // sum of min(d^2, D^2), smaller is better. Unlike the hit count it keeps falling as the
  // pose gets closer, so it ranks the local optimisation's steps.
  double cost(const Eigen::Matrix3d& r, const Eigen::Vector3d& t, std::vector<Neighbor>& nb) const {
    double sum = 0.0;
    each_nearest(r, t, nb, [&](const Eigen::Vector3d&, const Neighbor* hit) {
      sum += hit != nullptr ? hit->squared_distance : max_distance_ * max_distance_;
    });
    return sum;
  }
  std::size_t hits(const Eigen::Matrix3d& r, const Eigen::Vector3d& t, std::vector<Neighbor>& nb) const {
    std::size_t h = 0;
    each_nearest(r, t, nb, [&](const Eigen::Vector3d&, const Neighbor* hit) { h += hit != nullptr ? 1 : 0; });
    return h;
  }

private:
  // visit(x, nearest target point within the distance or nullptr) for every sample point x.
  template <class Visit>
  void each_nearest(const Eigen::Matrix3d& r, const Eigen::Vector3d& t, std::vector<Neighbor>& nb, Visit&& visit) const {
    for (const Eigen::Vector3d& x : points_) {
      tree_.hybrid(Eigen::Vector3d(r * x + t + center_), 1, max_distance_, nb);
      visit(x, nb.empty() ? nullptr : &nb[0]);
    }
  }

  std::vector<Eigen::Vector3d> points_;
  Eigen::Vector3d center_;
  const KdTree& tree_;
  double max_distance_;
};

// One linearised point-to-plane step (Chen and Medioni 1992) from `from` over the pairs: the
// small rotation w and shift v minimising sum ((p + w x p + v - y) . n)^2, p = R x + t.
detail::RigidFit plane_step(const detail::RigidFit& from, const std::vector<FitnessSample::Pair>& pairs,
                            const std::vector<Eigen::Vector3d>& target_normals) {
  Eigen::Matrix<double, 6, 6> a = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Zero();
  for (const FitnessSample::Pair& pair : pairs) {
    const Eigen::Vector3d p = from.rotation * pair.source + from.translation;
    const Eigen::Vector3d& n = target_normals[pair.target_index];
    Eigen::Matrix<double, 6, 1> row;
    row << p.cross(n), n;
    a.noalias() += row * row.transpose();
    b.noalias() += row * (pair.target - p).dot(n);
  }
  const Eigen::Matrix<double, 6, 1> x = a.ldlt().solve(b);
  if (!x.allFinite()) return from;
  const Eigen::Vector3d w = x.head<3>();
  const double angle = w.norm();
  const Eigen::Matrix3d turn =
      angle > 0.0 ? Eigen::AngleAxisd(angle, w / angle).toRotationMatrix() : Eigen::Matrix3d::Identity().eval();
  detail::RigidFit to;
  to.rotation = RigidTransform::nearest_rotation(turn * from.rotation);
  to.translation = turn * from.translation + x.tail<3>();
  return to;
}

// The matched pairs in a frame centred on the target's centroid.
struct MatchFrame {
  std::vector<Eigen::Vector3d> source, target;  // positions, local frame
  std::vector<Eigen::Vector3d> source_normals, target_normals;  // empty when the check is off
  std::size_t size() const { return source.size(); }
};

class Ransac {
public:
  Ransac(const MatchFrame& frame, const AlignParams& params, double max_distance)
      : frame_(frame), params_(params), squared_distance_(max_distance * max_distance),
        cos_normal_(params.max_normal_deg >= 180.0 ? -2.0 : std::cos(params.max_normal_deg * kDegToRad)) {}

  // Trial `trial`: a triple of matches checked for edge lengths, fitted, checked for distance
  // and normals. False when a check rejects it.
  bool propose(std::size_t trial, Model& model) const {
    const std::uint32_t m = static_cast<std::uint32_t>(frame_.size());
    TrialRng rng{params_.seed ^ (0xD1B54A32D192ED03ull * (trial + 1))};
    // Three distinct indices without a rejection loop.
    std::uint32_t idx[3];
    idx[0] = rng.below(m);
    idx[1] = rng.below(m - 1);
    if (idx[1] >= idx[0]) ++idx[1];
    idx[2] = rng.below(m - 2);
    const std::uint32_t lo = std::min(idx[0], idx[1]), hi = std::max(idx[0], idx[1]);
    if (idx[2] >= lo) ++idx[2];
    if (idx[2] >= hi) ++idx[2];

    // Edge lengths of the two triangles agree (Open3D's CorrespondenceCheckerBasedOnEdgeLength).
    const double ratio = params_.edge_length_ratio;
    for (int a = 0; a < 3; ++a) {
      const int b = (a + 1) % 3;
      const double ds = (frame_.source[idx[a]] - frame_.source[idx[b]]).norm();
      const double dt = (frame_.target[idx[a]] - frame_.target[idx[b]]).norm();
      if (!(ds > 0.0) || ds < ratio * dt || dt < ratio * ds) return false;
    }
    // A (nearly) collinear triple leaves the rotation about its line free.
    const Eigen::Vector3d e1 = frame_.source[idx[1]] - frame_.source[idx[0]];
    const Eigen::Vector3d e2 = frame_.source[idx[2]] - frame_.source[idx[0]];
    if (e1.cross(e2).squaredNorm() <= 1e-6 * e1.squaredNorm() * e2.squaredNorm()) return false;

    const detail::RigidFit fit = detail::fit_rigid(3, [&](std::size_t k, Eigen::Vector3d& x, Eigen::Vector3d& y) {
      x = frame_.source[idx[k]];
      y = frame_.target[idx[k]];
    });
    for (const std::uint32_t k : idx) {
      if ((fit.rotation * frame_.source[k] + fit.translation - frame_.target[k]).squaredNorm() > squared_distance_) return false;
      if (!frame_.source_normals.empty() && (fit.rotation * frame_.source_normals[k]).dot(frame_.target_normals[k]) < cos_normal_)
        return false;
    }
    model.rotation = fit.rotation;
    model.translation = fit.translation;
    model.trial = trial;
    return true;
  }

  // Inlier matches of (R, t); gives up (returning 0) once fewer than `needed` are possible.
  // The matches are in random order, so the count over the first k is a sample: a model
  // whose share of inliers reaches needed / m falls more than 4 standard deviations below
  // k * needed / m with a probability under 1e-4, and one that does is dropped early (a bounded
  // variant of Matas and Chum's sequential test; most survivors of the checks are wrong).
  std::size_t score(const Eigen::Matrix3d& r, const Eigen::Vector3d& t, std::size_t needed) const {
    const std::size_t m = frame_.size();
    const double share = double(needed) / double(m);
    std::size_t count = 0;
    for (std::size_t k = 0; k < m; ++k) {
      if ((r * frame_.source[k] + t - frame_.target[k]).squaredNorm() <= squared_distance_) ++count;
      if ((k & 255) == 255) {
        if (count + (m - k - 1) < needed) return 0;
        const double expected = share * double(k + 1);
        if (double(count) < expected - 4.0 * std::sqrt(expected)) return 0;
      }
    }
    return count;
  }

  std::size_t matches() const { return frame_.size(); }
  bool inlier(const Eigen::Matrix3d& r, const Eigen::Vector3d& t, std::size_t k) const {
    return (r * frame_.source[k] + t - frame_.target[k]).squaredNorm() <= squared_distance_;
  }

private:
  const MatchFrame& frame_;
  const AlignParams& params_;
  double squared_distance_;
  double cos_normal_;
};

// Trials needed to draw an all-inlier triple with probability `confidence` when a share
// `inlier_ratio` of the matches are inliers: log(1 - confidence) / log(1 - w^3).
double trials_needed(double inlier_ratio, double confidence) {
  const double w3 = inlier_ratio * inlier_ratio * inlier_ratio;
  if (w3 >= 1.0) return 1.0;
  if (w3 <= 0.0) return std::numeric_limits<double>::infinity();
  return std::ceil(std::log1p(-confidence) / std::log1p(-w3));
}

// Trials per parallel batch: a fixed size, so the trials run (and the answer) do not depend on
// the number of threads.
constexpr std::size_t kBatch = 512;

Eigen::Vector3d centroid(std::span<const Eigen::Vector3d> points) {
  // Offsets from the first point, so a georeferenced cloud's sum keeps its digits.
  const Eigen::Vector3d origin = points.front();
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : points) sum += p - origin;
  return origin + sum / double(points.size());
}

// Fitness and inlier RMSE of `transform` over all source points, by the target's kd-tree.
void score_by_tree(const PointCloud& source, const KdTree& target_tree, const RigidTransform& transform, double max_distance,
                   RegistrationResult& result) {
  struct Sum {
    std::size_t inliers = 0;
    double squared = 0.0;
  };
  const double squared_max = max_distance * max_distance;
  tbb::enumerable_thread_specific<std::vector<Neighbor>> buffers;
  const Sum total = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, source.size(), 1024), Sum{},
      [&](const tbb::blocked_range<std::size_t>& r, Sum s) {
        std::vector<Neighbor>& nb = buffers.local();
        for (std::size_t i = r.begin(); i != r.end(); ++i) {
          target_tree.knn(transform.apply(source.positions[i]), 1, nb);
          if (!nb.empty() && nb[0].squared_distance <= squared_max) {
            ++s.inliers;
            s.squared += nb[0].squared_distance;
          }
        }
        return s;
      },
      [](Sum a, const Sum& b) {
        a.inliers += b.inliers;
        a.squared += b.squared;
        return a;
      });
  result.fitness = double(total.inliers) / double(source.size());
  result.inlier_rmse = total.inliers == 0 ? 0.0 : std::sqrt(total.squared / double(total.inliers));
}

struct Search {
  Model best;           // count 0 when no trial passed the checks
  std::size_t trials = 0;
  double needed = 0.0;  // trials the confidence asks for, from the winner's share of inliers
};

// Trials run in fixed batches. Each candidate that passes the checks is counted against all
// matches; those with at least half the best count so far are then scored by the fitness of
// a fixed sample of the source (as Open3D scores every candidate): with few right matches
// among many, a wrong model can count as many inlier matches as the right one, but it does
// not bring the two surfaces together. The winner: most sample hits, then most inlier
// matches, then the earliest trial; each decision uses whole batches, so the answer does
// not depend on the number of threads.
Search run_trials(const Ransac& ransac, const FitnessSample& sample, const AlignParams& params, detail::ProgressReporter& reporter) {
  const std::size_t m = ransac.matches();
  Model best;
  std::size_t best_count = 0;  // most inlier matches of any candidate so far
  std::size_t done = 0;
  double needed = double(params.max_iterations);
  std::vector<Model> batch(kBatch);
  tbb::enumerable_thread_specific<std::vector<Neighbor>> buffers;
  while (done < params.max_iterations && double(done) < needed) {
    const std::size_t end = std::min(done + kBatch, params.max_iterations);
    const std::size_t gate_before = gate(best_count);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(done, end, 16), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t trial = r.begin(); trial != r.end(); ++trial) {
        Model& candidate = batch[trial - done];
        candidate = Model{};
        if (ransac.propose(trial, candidate)) candidate.count = ransac.score(candidate.rotation, candidate.translation, gate_before);
      }
    });
    for (std::size_t k = 0; k < end - done; ++k) best_count = std::max(best_count, batch[k].count);
    const std::size_t gate_now = gate(best_count);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, end - done, 4), [&](const tbb::blocked_range<std::size_t>& r) {
      std::vector<Neighbor>& nb = buffers.local();
      for (std::size_t k = r.begin(); k != r.end(); ++k)
        if (batch[k].count >= gate_now) batch[k].hits = sample.hits(batch[k].rotation, batch[k].translation, nb);
    });
    for (std::size_t k = 0; k < end - done; ++k)
      if (batch[k].count >= gate_now && batch[k].better_than(best)) best = batch[k];
    done = end;
    if (best.count > 0) needed = trials_needed(double(best.count) / double(m), params.confidence);
    reporter.report(0.95 * std::min(1.0, double(done) / std::min(needed, double(params.max_iterations))));
    reporter.throw_if_cancelled();
  }
  return {best, done, needed};
}

// Local optimisation (Chum, Matas, Kittler 2003) of the winner: a refit on its inlier matches,
// then up to kPolishRounds point-to-plane steps (point-to-point where the target has no
// normals) on the sample's nearest target points within the distance; the pose of least
// truncated squared distance over the sample is kept.
void refine(const MatchFrame& frame, const Ransac& ransac, const FitnessSample& sample, const PointCloud& target, Model& best) {
  std::vector<Neighbor> nb;
  struct Step {
    detail::RigidFit fit;
    double cost = 0.0;
  };
  const auto step = [&](const detail::RigidFit& fit) { return Step{fit, sample.cost(fit.rotation, fit.translation, nb)}; };
  Step kept = step({best.rotation, best.translation});
  std::vector<std::uint32_t> inliers;
  for (std::size_t k = 0; k < frame.size(); ++k)
    if (ransac.inlier(best.rotation, best.translation, k)) inliers.push_back(static_cast<std::uint32_t>(k));
  Step current = step(detail::fit_rigid(inliers.size(), [&](std::size_t k, Eigen::Vector3d& x, Eigen::Vector3d& y) {
    x = frame.source[inliers[k]];
    y = frame.target[inliers[k]];
  }));
  if (current.cost < kept.cost) kept = current;
  std::vector<FitnessSample::Pair> pairs;
  for (int round = 0; round < kPolishRounds; ++round) {
    sample.pairs(current.fit.rotation, current.fit.translation, nb, pairs);
    if (pairs.size() < 6) break;
    const Eigen::Matrix3d before = current.fit.rotation;
    current = step(target.has_normals() ? plane_step(current.fit, pairs, target.normals)
                                        : detail::fit_rigid(pairs.size(), [&](std::size_t k, Eigen::Vector3d& x, Eigen::Vector3d& y) {
                                            x = pairs[k].source;
                                            y = pairs[k].target;
                                          }));
    if (current.cost < kept.cost) kept = current;
    if ((current.fit.rotation - before).norm() < 1e-9) break;
  }
  best.rotation = kept.fit.rotation;
  best.translation = kept.fit.translation;
  best.count = ransac.score(best.rotation, best.translation, 0);
}

}  // namespace

const FieldTable<AlignParams>& AlignParams::fields() {
  static const FieldTable<AlignParams> table = [] {
    using P = AlignParams;
    FieldTable<P> t;
    t.length("ransac_distance", &P::max_distance, "A descriptor match is a RANSAC inlier within this distance (in spacings: of the downsample)")
        .positive()
        .was("ransac_distance_in_spacings");
    t.boolean("mutual", &P::mutual, "Keep only mutual nearest neighbours in descriptor space").internal();
    t.number("edge_length_ratio", &P::edge_length_ratio, "Pruning: the two triangles' edge lengths agree within this ratio")
        .range(0.0, 1.0, true, false)
        .internal();
    t.number("ransac_max_normal_angle_deg", &P::max_normal_deg, "Pruning: matched normals agree within this angle; 180 disables the check")
        .unit("degrees")
        .range(0.0, 180.0, true, false)
        .internal();
    t.integer("ransac_iterations", &P::max_iterations, "RANSAC trials at most").at_least(1);
    t.number("confidence", &P::confidence, "RANSAC stops once a better model would have been found with this probability")
        .range(0.0, 1.0, true, true);
    t.integer("seed", &P::seed, "Random seed of RANSAC");
    return t;
  }();
  return table;
}

void AlignParams::validate() const {
  if (!std::isfinite(max_distance.value))
    throw UsageError(fmt::format("align_global: ransac_distance must be finite, got {}", max_distance.value));
  fields().validate(*this, "align_global");
}

MatchList match_descriptors(const Descriptors& source, const Descriptors& target, bool mutual) {
  if (source.type != target.type || source.dimension != target.dimension)
    throw UsageError(fmt::format("match_descriptors: source descriptors are {} ({} values), target {} ({} values)",
                                 descriptor_type_name(source.type), source.dimension, descriptor_type_name(target.type),
                                 target.dimension));
  if (source.values.size() != source.size() * source.dimension || target.values.size() != target.size() * target.dimension)
    throw UsageError("match_descriptors: descriptor values do not match size() x dimension");
  MatchList matches;
  const DescriptorTree target_tree(target);
  if (target_tree.empty()) return matches;
  const std::size_t n = source.size();
  constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> forward(n, kNone);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i)
      if (source.valid[i]) forward[i] = target_tree.nearest(source.values.data() + i * source.dimension);
  });
  if (mutual) {
    // Back-match only the targets some source point chose.
    std::vector<std::uint32_t> backward(target.size(), kNone);
    std::vector<std::uint32_t> chosen;
    std::vector<std::uint8_t> seen(target.size(), 0);
    for (const std::uint32_t t : forward)
      if (t != kNone && !seen[t]) {
        seen[t] = 1;
        chosen.push_back(t);
      }
    const DescriptorTree source_tree(source);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chosen.size(), 256), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t c = r.begin(); c != r.end(); ++c)
        backward[chosen[c]] = source_tree.nearest(target.values.data() + std::size_t(chosen[c]) * target.dimension);
    });
    for (std::uint32_t i = 0; i < n; ++i)
      if (forward[i] != kNone && backward[forward[i]] == i) matches.emplace_back(i, forward[i]);
  } else {
    for (std::uint32_t i = 0; i < n; ++i)
      if (forward[i] != kNone) matches.emplace_back(i, forward[i]);
  }
  return matches;
}

RegistrationResult align_global(const PointCloud& source, const Descriptors& source_features, const PointCloud& target,
                                const Descriptors& target_features, const KdTree& target_tree, const AlignParams& params,
                                const ProgressCallback& progress) {
  params.validate();
  if (source_features.size() != source.size() || target_features.size() != target.size())
    throw UsageError(fmt::format("align_global: {} source descriptors for {} points, {} target descriptors for {} points",
                                 source_features.size(), source.size(), target_features.size(), target.size()));
  if (target_tree.size() != target.size())
    throw UsageError(fmt::format("align_global: the kd-tree holds {} points but the target has {}", target_tree.size(), target.size()));
  const bool check_normals = params.max_normal_deg < 180.0;
  if (check_normals && (source.normals.size() != source.size() || target.normals.size() != target.size()))
    throw UsageError("align_global: the normal-angle check needs normals on both clouds (or max_normal_deg = 180)");

  RegistrationResult result;
  if (source.size() < 3 || target.size() < 3) {
    result.message = fmt::format("too few points ({} source, {} target; 3 needed)", source.size(), target.size());
    return result;
  }
  const double max_distance =
      params.max_distance.in_spacings() ? params.max_distance.resolve(mean_spacing(source.positions)) : params.max_distance.value;
  if (!(max_distance > 0.0)) {
    result.message = "the source points all coincide";
    return result;
  }
  const MatchList matches = match_descriptors(source_features, target_features, params.mutual);
  if (matches.size() < 3) {
    result.message = fmt::format("too few descriptor matches ({}; 3 needed)", matches.size());
    return result;
  }

  // The matches in a seeded random order (Fisher-Yates), so that any prefix is a random sample
  // for the early exit of the count.
  std::vector<std::uint32_t> order(matches.size());
  for (std::uint32_t k = 0; k < order.size(); ++k) order[k] = k;
  TrialRng shuffle{params.seed};
  for (std::size_t k = order.size() - 1; k > 0; --k) std::swap(order[k], order[shuffle.below(static_cast<std::uint32_t>(k + 1))]);
  const Eigen::Vector3d center = centroid(target.positions);
  MatchFrame frame;
  frame.source.reserve(matches.size());
  frame.target.reserve(matches.size());
  for (const std::uint32_t k : order) {
    const auto [s, t] = matches[k];
    frame.source.push_back(source.positions[s] - center);
    frame.target.push_back(target.positions[t] - center);
    if (check_normals) {
      frame.source_normals.push_back(source.normals[s]);
      frame.target_normals.push_back(target.normals[t]);
    }
  }
  const std::size_t m = frame.size();
  const Ransac ransac(frame, params, max_distance);

  const FitnessSample sample(source, center, target_tree, max_distance);

  detail::ProgressReporter reporter(progress, 0.0, 0.95, params.max_iterations);
  const Search search = run_trials(ransac, sample, params, reporter);
  result.iterations = search.trials;
  Model best = search.best;
  if (best.count == 0) {
    result.message = fmt::format("no triple of the {} matches passed the edge-length, distance and normal checks in {} trials", m,
                                 search.trials);
    return result;
  }
  refine(frame, ransac, sample, target, best);

  result.transform = RigidTransform::about(center, RigidTransform::nearest_rotation(best.rotation), best.translation);
  result.correspondences = best.count;
  score_by_tree(source, target_tree, result.transform, max_distance, result);
  result.converged = double(search.trials) >= search.needed;
  result.message =
      result.converged
          ? fmt::format("confidence {} reached after {} trials: {} of {} matches are inliers", params.confidence, search.trials, best.count, m)
          : fmt::format("iteration cap {} reached before confidence {} ({} of {} matches are inliers; about {:.3g} trials needed)",
                        params.max_iterations, params.confidence, best.count, m, search.needed);
  reporter.report(1.0);
  reporter.throw_if_cancelled();
  return result;
}

}  // namespace pointsurf
