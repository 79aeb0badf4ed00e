// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/spatial/kd_tree.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

#include <fmt/format.h>
#include <nanoflann.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "pointsurf/core/error.h"
#include "pointsurf/core/point_cloud.h"

namespace pointsurf {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// The points as nanoflann reads them: shifted to the tree's centre so that squared distances
// of a georeferenced cloud are computed from small numbers.
struct ShiftedPoints {
  std::vector<Eigen::Vector3d> shifted;

  std::size_t kdtree_get_point_count() const { return shifted.size(); }
  double kdtree_get_pt(std::uint32_t i, std::size_t dim) const { return shifted[i][dim]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};

using Metric = nanoflann::L2_Simple_Adaptor<double, ShiftedPoints, double, std::uint32_t>;
using Index = nanoflann::KDTreeSingleIndexAdaptor<Metric, ShiftedPoints, 3, std::uint32_t>;

// The order every result is reported in: nearest first, ties by index.
bool precedes(double squared_distance, std::uint32_t index, const Neighbor& n) {
  return squared_distance < n.squared_distance || (squared_distance == n.squared_distance && index < n.index);
}

bool by_distance_then_index(const Neighbor& a, const Neighbor& b) { return precedes(a.squared_distance, a.index, b); }

// nanoflann only passes a candidate to addPoint when its distance is strictly below worstDist(),
// so the bound we return is the next double above the value we still accept: that keeps ties
// at the k-th distance (and at the radius, which is inclusive) in play for the index tie-break.
// Squared distances are never negative, so the next double is one more in the bit pattern
// (std::nextafter is an out-of-line call that showed in profiles); infinity stays infinity.
double just_above(double squared_distance) {
  if (!(squared_distance < kInfinity)) return squared_distance;
  return std::bit_cast<double>(std::bit_cast<std::uint64_t>(squared_distance) + 1);
}

// The k best (distance, index) pairs within an optional squared radius, kept sorted in a
// caller-owned buffer by insertion (k is small: the shifting costs less than a heap's
// bookkeeping and leaves the result already in order). Serves knn (no radius) and hybrid.
class BoundedKnnResult {
public:
  using DistanceType = double;
  using IndexType = std::uint32_t;

  BoundedKnnResult(const std::uint32_t* original, Neighbor* buffer, std::size_t k, double max_squared_distance)
      : original_(original), buffer_(buffer), k_(k), max_squared_(max_squared_distance), bound_(just_above(max_squared_distance)),
        worst_(k == 0 ? 0.0 : bound_) {}

  std::size_t size() const { return count_; }
  bool full() const { return count_ == k_; }
  double worstDist() const { return worst_; }

  bool addPoint(double squared_distance, std::uint32_t slot_in_tree) {
    if (k_ == 0 || squared_distance > max_squared_) return true;
    const std::uint32_t index = original_[slot_in_tree];
    if (count_ == k_ && !precedes(squared_distance, index, buffer_[k_ - 1])) return true;
    std::size_t slot = count_ < k_ ? count_++ : k_ - 1;
    while (slot > 0 && precedes(squared_distance, index, buffer_[slot - 1])) {
      buffer_[slot] = buffer_[slot - 1];
      --slot;
    }
    buffer_[slot] = Neighbor{index, squared_distance};
    if (count_ == k_) worst_ = std::min(bound_, just_above(buffer_[k_ - 1].squared_distance));
    return true;
  }

private:
  const std::uint32_t* original_;
  Neighbor* buffer_;
  std::size_t k_;
  std::size_t count_ = 0;
  double max_squared_;
  double bound_;
  double worst_;
};

// Every point within an inclusive squared radius, appended unsorted to a caller-owned vector.
class RadiusResult {
public:
  using DistanceType = double;
  using IndexType = std::uint32_t;

  RadiusResult(const std::uint32_t* original, std::vector<Neighbor>& out, double max_squared_distance)
      : original_(original), out_(out), max_squared_(max_squared_distance), bound_(just_above(max_squared_distance)) {}

  std::size_t size() const { return out_.size(); }
  bool full() const { return true; }
  double worstDist() const { return bound_; }

  bool addPoint(double squared_distance, std::uint32_t slot_in_tree) {
    if (squared_distance <= max_squared_) out_.push_back(Neighbor{original_[slot_in_tree], squared_distance});
    return true;
  }

private:
  const std::uint32_t* original_;
  std::vector<Neighbor>& out_;
  double max_squared_;
  double bound_;
};

// The nearest point with another label than the query's, within a strict squared bound.
class NearestOtherResult {
public:
  using DistanceType = double;
  using IndexType = std::uint32_t;

  NearestOtherResult(const std::uint32_t* original, std::span<const std::uint32_t> labels, std::uint32_t label, double bound)
      : original_(original), labels_(labels), label_(label), worst_(bound) {}

  std::size_t size() const { return found_ ? 1 : 0; }
  bool full() const { return true; }
  double worstDist() const { return found_ ? just_above(best_.squared_distance) : worst_; }
  bool found() const { return found_; }
  const Neighbor& best() const { return best_; }

  bool addPoint(double squared_distance, std::uint32_t slot_in_tree) {
    const std::uint32_t index = original_[slot_in_tree];
    if (labels_[index] == label_ || !(squared_distance < worst_)) return true;
    if (found_ && !precedes(squared_distance, index, best_)) return true;
    best_ = Neighbor{index, squared_distance};
    found_ = true;
    return true;
  }

private:
  const std::uint32_t* original_;
  std::span<const std::uint32_t> labels_;
  std::uint32_t label_;
  double worst_;
  Neighbor best_;
  bool found_ = false;
};

double checked_squared_radius(const char* where, double radius) {
  if (!(radius >= 0.0)) throw UsageError(fmt::format("KdTree::{}: radius must be >= 0, got {}", where, radius));
  return radius * radius;
}

// Query positions handed out in parallel chunks: the caller's queries in their order, or the
// tree's own points in leaf order (neighbouring queries then share cache lines).
// `slot(pos)` is the query's index in the output, `query(pos)` its position.
struct QuerySchedule {
  std::span<const Eigen::Vector3d> queries;
  std::span<const std::uint32_t> order;  // empty: queries in their own order

  std::size_t size() const { return queries.size(); }
  std::size_t slot(std::size_t pos) const { return order.empty() ? pos : order[pos]; }
  const Eigen::Vector3d& query(std::size_t pos) const { return queries[slot(pos)]; }
};

constexpr std::size_t kChunk = 512;

}  // namespace

struct KdTree::Impl {
  std::vector<Eigen::Vector3d> points;
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  ShiftedPoints data;            // in leaf order once the tree is built
  std::vector<std::uint32_t> original;  // original index of each slot of `data`
  std::unique_ptr<Index> index;  // refers to `data`, which lives as long as this Impl

  template <class ResultSet>
  void search(const Eigen::Vector3d& query, ResultSet& result) const {
    const Eigen::Vector3d q = query - center;
    index->findNeighbors(result, q.data(), nanoflann::SearchParams());
  }

  void knn(const Eigen::Vector3d& query, std::size_t k, Neighbor* out, std::size_t& count) const {
    BoundedKnnResult result(original.data(), out, k, kInfinity);
    search(query, result);
    count = result.size();
  }

  void hybrid(const Eigen::Vector3d& query, std::size_t k, double squared_radius, Neighbor* out,
              std::size_t& count) const {
    BoundedKnnResult result(original.data(), out, k, squared_radius);
    search(query, result);
    count = result.size();
  }

  // Appends the sorted radius neighbours of `query` to `out`.
  void radius_append(const Eigen::Vector3d& query, double squared_radius, std::vector<Neighbor>& out) const {
    const std::size_t first = out.size();
    RadiusResult result(original.data(), out, squared_radius);
    search(query, result);
    std::sort(out.begin() + static_cast<std::ptrdiff_t>(first), out.end(), by_distance_then_index);
  }

  QuerySchedule schedule(std::span<const Eigen::Vector3d> queries) const {
    if (queries.empty()) return {points, original};
    return {queries, {}};
  }

  // Variable-length results: each chunk of queries appends to its own buffer, then the lists are
  // copied to their final place once every count is known. That searches once (a count pass
  // followed by a fill pass would search twice) at the price of holding the results twice
  // while they are copied, chunk buffers being released as soon as they are copied.
  template <class AppendOne>
  NeighborLists gather(const QuerySchedule& schedule, AppendOne append_one) const {
    const std::size_t q = schedule.size();
    NeighborLists lists;
    lists.offsets.assign(q + 1, 0);
    const std::size_t chunks = (q + kChunk - 1) / kChunk;
    std::vector<std::vector<Neighbor>> buffers(chunks);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks, 1), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t c = r.begin(); c != r.end(); ++c) {
        std::vector<Neighbor>& buffer = buffers[c];
        const std::size_t end = std::min(q, (c + 1) * kChunk);
        for (std::size_t pos = c * kChunk; pos < end; ++pos) {
          const std::size_t before = buffer.size();
          append_one(schedule.query(pos), buffer);
          lists.offsets[schedule.slot(pos) + 1] = buffer.size() - before;
        }
      }
    });
    for (std::size_t i = 0; i < q; ++i) lists.offsets[i + 1] += lists.offsets[i];
    lists.neighbors.resize(lists.offsets[q]);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks, 1), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t c = r.begin(); c != r.end(); ++c) {
        const Neighbor* src = buffers[c].data();
        const std::size_t end = std::min(q, (c + 1) * kChunk);
        for (std::size_t pos = c * kChunk; pos < end; ++pos) {
          const std::size_t s = schedule.slot(pos);
          const std::size_t n = lists.offsets[s + 1] - lists.offsets[s];
          std::copy(src, src + n, lists.neighbors.begin() + static_cast<std::ptrdiff_t>(lists.offsets[s]));
          src += n;
        }
        std::vector<Neighbor>().swap(buffers[c]);
      }
    });
    return lists;
  }
};

KdTree::KdTree(std::span<const Eigen::Vector3d> points, int leaf_size) : impl_(std::make_unique<Impl>()) {
  if (points.empty()) throw UsageError("KdTree: cannot build a tree over an empty point set");
  if (points.size() > std::numeric_limits<std::uint32_t>::max())
    throw UsageError(fmt::format("KdTree: {} points exceed the limit of {}", points.size(),
                                 std::numeric_limits<std::uint32_t>::max()));
  if (leaf_size < 1) throw UsageError(fmt::format("KdTree: leaf_size must be >= 1, got {}", leaf_size));
  impl_->points.assign(points.begin(), points.end());
  const BoundingBox box = bounding_box(points);
  // A non-finite coordinate would make the centre NaN and poison every distance; such clouds
  // (which io never produces) then keep the unshifted coordinates.
  const Eigen::Vector3d c = box.center();
  impl_->center = c.allFinite() ? c : Eigen::Vector3d::Zero();
  impl_->data.shifted.resize(points.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) impl_->data.shifted[i] = points[i] - impl_->center;
  });
  impl_->index = std::make_unique<Index>(3, impl_->data, nanoflann::KDTreeSingleIndexAdaptorParams(leaf_size));
  // Store the points in the order the tree's leaves list them, and make the tree's index
  // array the identity: a leaf scan then reads consecutive memory instead of jumping through
  // the whole cloud (the search is most of the time of every neighbourhood stage). Results
  // are mapped back to the caller's indices through `original`.
  std::vector<std::uint32_t>& slots = impl_->index->vAcc;
  impl_->original.assign(slots.begin(), slots.end());
  std::vector<Eigen::Vector3d> leaf_order(points.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      leaf_order[i] = impl_->data.shifted[impl_->original[i]];
      slots[i] = static_cast<std::uint32_t>(i);
    }
  });
  impl_->data.shifted = std::move(leaf_order);
}

KdTree::~KdTree() = default;
KdTree::KdTree(KdTree&&) noexcept = default;
KdTree& KdTree::operator=(KdTree&&) noexcept = default;

std::size_t KdTree::size() const noexcept { return impl_->points.size(); }

const Eigen::Vector3d& KdTree::point(std::size_t i) const noexcept { return impl_->points[i]; }

std::span<const std::uint32_t> KdTree::spatial_order() const noexcept { return impl_->original; }

void KdTree::knn(const Eigen::Vector3d& query, std::size_t k, std::vector<Neighbor>& out) const {
  out.resize(std::min(k, size()));
  std::size_t count = 0;
  impl_->knn(query, out.size(), out.data(), count);
  out.resize(count);
}

void KdTree::radius(const Eigen::Vector3d& query, double radius, std::vector<Neighbor>& out) const {
  const double squared_radius = checked_squared_radius("radius", radius);
  out.clear();
  impl_->radius_append(query, squared_radius, out);
}

void KdTree::hybrid(const Eigen::Vector3d& query, std::size_t k, double radius, std::vector<Neighbor>& out) const {
  const double squared_radius = checked_squared_radius("hybrid", radius);
  out.resize(std::min(k, size()));
  std::size_t count = 0;
  impl_->hybrid(query, out.size(), squared_radius, out.data(), count);
  out.resize(count);
}

bool KdTree::nearest_other(const Eigen::Vector3d& query, std::span<const std::uint32_t> labels, std::uint32_t label,
                           double max_squared_distance, Neighbor& out) const {
  if (labels.size() != size())
    throw UsageError(fmt::format("KdTree::nearest_other: {} labels for {} points", labels.size(), size()));
  NearestOtherResult result(impl_->original.data(), labels, label, max_squared_distance);
  impl_->search(query, result);
  if (!result.found()) return false;
  out = result.best();
  return true;
}

NeighborLists KdTree::knn_all(std::span<const Eigen::Vector3d> queries, std::size_t k) const {
  const QuerySchedule schedule = impl_->schedule(queries);
  const std::size_t q = schedule.size();
  const std::size_t m = std::min(k, size());
  // Every list has exactly m entries (N >= 1), so each query writes straight into its place.
  NeighborLists lists;
  lists.offsets.resize(q + 1);
  for (std::size_t i = 0; i <= q; ++i) lists.offsets[i] = i * m;
  lists.neighbors.resize(q * m);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, q, kChunk), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t pos = r.begin(); pos != r.end(); ++pos) {
      std::size_t count = 0;
      impl_->knn(schedule.query(pos), m, lists.neighbors.data() + schedule.slot(pos) * m, count);
    }
  });
  return lists;
}

NeighborLists KdTree::radius_all(std::span<const Eigen::Vector3d> queries, double radius) const {
  const double squared_radius = checked_squared_radius("radius_all", radius);
  return impl_->gather(impl_->schedule(queries), [&](const Eigen::Vector3d& query, std::vector<Neighbor>& buffer) {
    impl_->radius_append(query, squared_radius, buffer);
  });
}

NeighborLists KdTree::hybrid_all(std::span<const Eigen::Vector3d> queries, std::size_t k, double radius) const {
  const double squared_radius = checked_squared_radius("hybrid_all", radius);
  const std::size_t m = std::min(k, size());
  return impl_->gather(impl_->schedule(queries), [&](const Eigen::Vector3d& query, std::vector<Neighbor>& buffer) {
    const std::size_t before = buffer.size();
    buffer.resize(before + m);
    std::size_t count = 0;
    impl_->hybrid(query, m, squared_radius, buffer.data() + before, count);
    buffer.resize(before + count);
  });
}

}  // namespace pointsurf
