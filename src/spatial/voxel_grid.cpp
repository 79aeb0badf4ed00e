// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/spatial/voxel_grid.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <mutex>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

#include "pointsurf/core/error.h"
#include "pointsurf/core/point_cloud.h"

namespace pointsurf {
namespace {

constexpr double kNoDistance = std::numeric_limits<double>::infinity();
constexpr std::int64_t kMaxCellsPerAxis = std::int64_t(1) << 20;
// Rings of cells searched around a point before its kNN query goes to the kd-tree.
constexpr int kMaxRing = 3;
// kNN: the first squared distance tried is this factor times the previous point's k-th.
constexpr double kGuessFactor = 1.2;
// Cells handed to one task.
constexpr std::size_t kCellGrain = 16;

// Nearest first, ties by index (a function object, so that the sorts inline it).
struct ByDistanceThenIndex {
  bool operator()(const Neighbor& a, const Neighbor& b) const {
    return a.squared_distance < b.squared_distance || (a.squared_distance == b.squared_distance && a.index < b.index);
  }
};

// Candidates of one block of cells, structure of arrays so the distance loop vectorises.
struct Candidates {
  std::vector<double> x, y, z;
  std::vector<std::uint32_t> index;
  std::vector<double> squared;  // scratch: squared distances to the current query
  std::vector<Neighbor> found;  // scratch: the current query's result
  std::vector<std::uint32_t> previous;  // slots of the last result in this candidate list
  void clear() {
    x.clear();
    y.clear();
    z.clear();
    index.clear();
  }
  std::size_t size() const { return x.size(); }
  // Squared distances to (qx, qy, qz), summed as nanoflann's L2_Simple_Adaptor sums them
  // (x, then y, then z), so that they equal the kd-tree's bit for bit.
  void distances_to(double qx, double qy, double qz) {
    const std::size_t m = size();
    squared.resize(m);
    const double* px = x.data();
    const double* py = y.data();
    const double* pz = z.data();
    double* d = squared.data();
    for (std::size_t j = 0; j < m; ++j) {
      const double dx = qx - px[j], dy = qy - py[j], dz = qz - pz[j];
      double s = 0.0;
      s += dx * dx;
      s += dy * dy;
      s += dz * dz;
      d[j] = s;
    }
  }
};

}  // namespace

struct VoxelGrid::Impl {
  std::vector<Eigen::Vector3d> points;  // as given (the fallback tree is built over them)
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  Eigen::Vector3d low = Eigen::Vector3d::Zero();  // lower corner, shifted
  double side = 1.0;
  double slack = 0.0;  // rounding allowance of the cell assignment
  std::array<std::int64_t, 3> dims{1, 1, 1};
  // Points sorted by cell: shifted coordinates and original index.
  std::vector<double> x, y, z;
  std::vector<std::uint32_t> index;
  std::vector<std::uint64_t> cell_key;     // per non-empty cell, ascending
  std::vector<std::uint32_t> cell_start;   // cells + 1
  const KdTree* given_tree = nullptr;
  mutable std::once_flag tree_once;
  mutable std::unique_ptr<KdTree> tree;

  std::uint64_t key(std::int64_t cx, std::int64_t cy, std::int64_t cz) const {
    return std::uint64_t(cx) + std::uint64_t(dims[0]) * (std::uint64_t(cy) + std::uint64_t(dims[1]) * std::uint64_t(cz));
  }
  std::array<std::int64_t, 3> coords_of_key(std::uint64_t k) const {
    const auto cx = std::int64_t(k % std::uint64_t(dims[0]));
    k /= std::uint64_t(dims[0]);
    return {cx, std::int64_t(k % std::uint64_t(dims[1])), std::int64_t(k / std::uint64_t(dims[1]))};
  }
  std::int64_t coord(double v, int axis) const {
    const double c = std::floor((v - low[axis]) / side);
    if (!(c > 0.0)) return 0;  // NaN too
    return c >= double(dims[axis] - 1) ? dims[axis] - 1 : std::int64_t(c);
  }

  const KdTree& fallback_tree() const {
    if (given_tree != nullptr) return *given_tree;
    std::call_once(tree_once, [&] {
      // Isolated: a thread waiting inside the build must not pick up a grid task that
      // asks for the tree again.
      tbb::this_task_arena::isolate([&] { tree = std::make_unique<KdTree>(points); });
    });
    return *tree;
  }

  // Appends the points of the cells within `ring` of cell c (own cell first) to `out`.
  void gather(const std::array<std::int64_t, 3>& c, std::int64_t ring, Candidates& out) const {
    out.clear();
    const auto append_range = [&](std::size_t first, std::size_t last) {
      out.x.insert(out.x.end(), x.begin() + std::ptrdiff_t(first), x.begin() + std::ptrdiff_t(last));
      out.y.insert(out.y.end(), y.begin() + std::ptrdiff_t(first), y.begin() + std::ptrdiff_t(last));
      out.z.insert(out.z.end(), z.begin() + std::ptrdiff_t(first), z.begin() + std::ptrdiff_t(last));
      out.index.insert(out.index.end(), index.begin() + std::ptrdiff_t(first), index.begin() + std::ptrdiff_t(last));
    };
    const auto cells_between = [&](std::uint64_t key_low, std::uint64_t key_high) {
      const auto a = std::lower_bound(cell_key.begin(), cell_key.end(), key_low);
      const auto b = std::upper_bound(a, cell_key.end(), key_high);
      return std::pair<std::size_t, std::size_t>(cell_start[std::size_t(a - cell_key.begin())], cell_start[std::size_t(b - cell_key.begin())]);
    };
    const std::uint64_t own = key(c[0], c[1], c[2]);
    const auto [own_first, own_last] = cells_between(own, own);
    append_range(own_first, own_last);
    const std::int64_t x0 = std::max<std::int64_t>(0, c[0] - ring), x1 = std::min(dims[0] - 1, c[0] + ring);
    for (std::int64_t cz = std::max<std::int64_t>(0, c[2] - ring); cz <= std::min(dims[2] - 1, c[2] + ring); ++cz) {
      for (std::int64_t cy = std::max<std::int64_t>(0, c[1] - ring); cy <= std::min(dims[1] - 1, c[1] + ring); ++cy) {
        const auto [first, last] = cells_between(key(x0, cy, cz), key(x1, cy, cz));
        if (cy == c[1] && cz == c[2]) {  // the row of the own cell: skip it, already in
          append_range(first, own_first);
          append_range(own_last, last);
        } else {
          append_range(first, last);
        }
      }
    }
  }

  // Distance from shifted point q to the nearest wall of the block of cells within `ring` of
  // cell c, less the rounding allowance: no point outside the block is closer. Infinite when
  // the block covers the whole grid.
  double margin(const std::array<std::int64_t, 3>& c, std::int64_t ring, double qx, double qy, double qz) const {
    const double q[3] = {qx, qy, qz};
    double m = kNoDistance;
    for (int a = 0; a < 3; ++a) {
      if (c[a] - ring > 0) m = std::min(m, q[a] - (low[a] + double(c[a] - ring) * side));
      if (c[a] + ring < dims[a] - 1) m = std::min(m, (low[a] + double(c[a] + ring + 1) * side) - q[a]);
    }
    return m - slack;
  }

  // The k nearest among `cand` (distances already computed) into cand.found, with entries
  // above `bound` skipped first (a bound known to hold the k nearest); returns how many.
  static std::size_t select(Candidates& cand, std::size_t k, double bound, bool sorted = true, double guess = kNoDistance) {
    std::vector<Neighbor>& found = cand.found;
    const std::size_t m = cand.size();
    if (found.size() < m) found.resize(m);
    // Pass 0 keeps the entries within a guess (which may hold fewer than k), pass 1 within
    // the bound (which holds k when it is right), pass 2 all: the first pass that keeps k or
    // more has the k nearest, since every entry it drops is farther than all it keeps.
    const double limits[3] = {std::min(guess, bound), bound, kNoDistance};
    for (int pass = guess < bound ? 0 : 1; pass < 3; ++pass) {
      const double limit = limits[pass];
      std::size_t kept = 0;
      Neighbor* out = found.data();
      const double* d = cand.squared.data();
      for (std::size_t j = 0; j < m; ++j) {
        out[kept] = Neighbor{static_cast<std::uint32_t>(j), d[j]};  // slot for now
        kept += d[j] <= limit;  // branch-free compaction
      }
      if (kept >= k || limit == kNoDistance) {
        found.resize(kept);
        break;
      }
    }
    const std::size_t count = std::min(k, found.size());
    if (count == 0) return 0;
    // Entries hold candidate slots until the end; ties are broken by the slots' point indices.
    const std::uint32_t* idx = cand.index.data();
    const auto before = [idx](const Neighbor& a, const Neighbor& b) {
      return a.squared_distance < b.squared_distance || (a.squared_distance == b.squared_distance && idx[a.index] < idx[b.index]);
    };
    if (found.size() > count) std::nth_element(found.begin(), found.begin() + std::ptrdiff_t(count - 1), found.end(), before);
    if (sorted) {
      std::sort(found.begin(), found.begin() + std::ptrdiff_t(count), before);
    } else if (found.size() == count && count > 1) {
      // The farthest last (nth_element put it there otherwise): callers read the reach from it.
      std::iter_swap(std::max_element(found.begin(), found.begin() + std::ptrdiff_t(count), before), found.begin() + std::ptrdiff_t(count - 1));
    }
    cand.previous.resize(count);
    for (std::size_t j = 0; j < count; ++j) {
      cand.previous[j] = found[j].index;
      found[j].index = idx[found[j].index];
    }
    return count;
  }

  // Runs body(cell, coords, candidates) over all cells in parallel, with ring-`ring` blocks.
  template <class Body>
  void over_cells(std::int64_t ring, Body body) const {
    tbb::enumerable_thread_specific<Candidates> scratch;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cell_key.size(), kCellGrain), [&](const tbb::blocked_range<std::size_t>& r) {
      Candidates& cand = scratch.local();
      for (std::size_t cell = r.begin(); cell != r.end(); ++cell) {
        const std::array<std::int64_t, 3> c = coords_of_key(cell_key[cell]);
        gather(c, ring, cand);
        body(cell, c, cand);
      }
    });
  }

  std::int64_t ring_for_radius(double radius) const {
    const double r = std::ceil((radius + 2.0 * slack) / side);
    return std::clamp<std::int64_t>(r < 1.0 ? 1 : (r > double(kMaxCellsPerAxis) ? kMaxCellsPerAxis : std::int64_t(r)), 1,
                                    std::max({dims[0], dims[1], dims[2]}));
  }
};

VoxelGrid::VoxelGrid(std::span<const Eigen::Vector3d> points, double cell_size, const KdTree* tree)
    : impl_(std::make_unique<Impl>()) {
  if (points.empty()) throw UsageError("VoxelGrid: cannot build a grid over an empty point set");
  if (points.size() > std::numeric_limits<std::uint32_t>::max())
    throw UsageError(fmt::format("VoxelGrid: {} points exceed the limit of {}", points.size(), std::numeric_limits<std::uint32_t>::max()));
  if (!(cell_size > 0.0 && std::isfinite(cell_size)))
    throw UsageError(fmt::format("VoxelGrid: the cell size must be finite and > 0, got {}", cell_size));
  Impl& g = *impl_;
  const std::size_t n = points.size();
  if (tree != nullptr && tree->size() != n)
    throw UsageError(fmt::format("VoxelGrid: the kd-tree holds {} points but the grid has {}", tree->size(), n));
  g.points.assign(points.begin(), points.end());
  g.given_tree = tree;
  const BoundingBox box = bounding_box(points);
  const Eigen::Vector3d c = box.center();
  g.center = c.allFinite() ? c : Eigen::Vector3d::Zero();  // as KdTree does
  g.low = box.min - g.center;
  const Eigen::Vector3d extent = box.max - box.min;
  g.side = cell_size;
  const double largest = extent.allFinite() ? extent.maxCoeff() : 0.0;
  if (largest / g.side > double(kMaxCellsPerAxis - 2)) g.side = largest / double(kMaxCellsPerAxis - 2);
  for (int a = 0; a < 3; ++a) g.dims[a] = std::min<std::int64_t>(kMaxCellsPerAxis, std::int64_t(extent[a] / g.side) + 1);
  g.slack = 1e-6 * g.side;

  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const Eigen::Vector3d q = points[i] - g.center;
      keyed[i] = {g.key(g.coord(q.x(), 0), g.coord(q.y(), 1), g.coord(q.z(), 2)), static_cast<std::uint32_t>(i)};
    }
  });
  tbb::parallel_sort(keyed.begin(), keyed.end());
  g.x.resize(n);
  g.y.resize(n);
  g.z.resize(n);
  g.index.resize(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const std::uint32_t p = keyed[i].second;
      const Eigen::Vector3d q = points[p] - g.center;
      g.x[i] = q.x();
      g.y[i] = q.y();
      g.z[i] = q.z();
      g.index[i] = p;
    }
  });
  for (std::size_t i = 0; i < n; ++i) {
    if (i == 0 || keyed[i].first != keyed[i - 1].first) {
      g.cell_key.push_back(keyed[i].first);
      g.cell_start.push_back(static_cast<std::uint32_t>(i));
    }
  }
  g.cell_start.push_back(static_cast<std::uint32_t>(n));
}

VoxelGrid::~VoxelGrid() = default;
VoxelGrid::VoxelGrid(VoxelGrid&&) noexcept = default;
VoxelGrid& VoxelGrid::operator=(VoxelGrid&&) noexcept = default;

std::size_t VoxelGrid::size() const noexcept { return impl_->points.size(); }
double VoxelGrid::cell_size() const noexcept { return impl_->side; }
std::size_t VoxelGrid::cells() const noexcept { return impl_->cell_key.size(); }
std::span<const std::uint32_t> VoxelGrid::grid_order() const noexcept { return impl_->index; }

double VoxelGrid::knn_cell_size(std::span<const Eigen::Vector3d> points, std::size_t k) {
  if (points.empty()) throw UsageError("VoxelGrid::knn_cell_size: empty point set");
  const std::size_t n = points.size();
  const BoundingBox box = bounding_box(points);
  const Eigen::Vector3d extent = box.max - box.min;
  const double largest = extent.allFinite() ? extent.maxCoeff() : 0.0;
  if (!(largest > 0.0)) return 1.0;  // all points coincide: any side
  // A sample spread over the input; occupancy seen by a sampled point, unbiased to the full
  // cloud: 1 + (sample neighbours in its cell) * N / M.
  const std::size_t m = std::min<std::size_t>(n, 32768);
  const double stride = double(n) / double(m);
  const double target = std::max(2.0, double(k) / 2.0);
  double side = largest / std::cbrt(double(n));
  std::vector<std::uint64_t> keys(m);
  for (int iteration = 0; iteration < 8; ++iteration) {
    side = std::max(side, largest / double(kMaxCellsPerAxis - 2));
    const double dx = std::floor(extent.x() / side) + 1, dy = std::floor(extent.y() / side) + 1;
    for (std::size_t s = 0; s < m; ++s) {
      const Eigen::Vector3d q = (points[std::size_t(double(s) * stride)] - box.min) / side;
      keys[s] = std::uint64_t(q.x()) + std::uint64_t(dx) * (std::uint64_t(q.y()) + std::uint64_t(dy) * std::uint64_t(q.z()));
    }
    std::sort(keys.begin(), keys.end());
    double pairs = 0.0;  // sum over sampled points of the other sampled points in their cell
    for (std::size_t a = 0; a < m;) {
      std::size_t b = a;
      while (b < m && keys[b] == keys[a]) ++b;
      pairs += double(b - a) * double(b - a - 1);
      a = b;
    }
    const double occupancy = 1.0 + pairs / double(m) * stride;
    const double ratio = target / occupancy;
    if (ratio > 0.8 && ratio < 1.25) break;
    side *= std::clamp(std::sqrt(ratio), 0.3, 3.0);  // a surface: occupancy grows as side^2
  }
  return side;
}

void VoxelGrid::for_each_knn(std::size_t k, const Visit& visit, bool sorted) const {
  const Impl& g = *impl_;
  k = std::min(k, size());
  if (k == 0) {
    for (const std::uint32_t i : g.index) visit(i, {});
    return;
  }
  tbb::enumerable_thread_specific<Candidates> wide;
  tbb::enumerable_thread_specific<std::vector<Neighbor>> from_tree;
  g.over_cells(1, [&](std::size_t cell, const std::array<std::int64_t, 3>& c, Candidates& cand) {
    bool have_previous = false;  // cand.previous holds the previous point's k nearest
    double previous_kth = kNoDistance;  // and its k-th squared distance
    for (std::size_t p = g.cell_start[cell]; p < g.cell_start[cell + 1]; ++p) {
      const double qx = g.x[p], qy = g.y[p], qz = g.z[p];
      cand.distances_to(qx, qy, qz);
      // The previous point's k nearest are k candidates: the farthest of them from this point
      // bounds its k-th distance, and entries beyond it need no ordering.
      // A guess: a little beyond the previous point's own k-th distance (neighbouring points
      // have similar ones), tried first; select() checks it.
      double bound = kNoDistance, guess = kNoDistance;
      if (have_previous) {
        bound = 0.0;
        for (const std::uint32_t slot : cand.previous) bound = std::max(bound, cand.squared[slot]);
        guess = kGuessFactor * previous_kth;
      }
      std::size_t count = Impl::select(cand, k, bound, sorted, guess);
      if (count > 0) previous_kth = cand.found[count - 1].squared_distance;
      have_previous = count == k;  // k candidates: a bound for the next point either way
      const double m1 = g.margin(c, 1, qx, qy, qz);
      std::span<const Neighbor> result(cand.found.data(), count);
      const bool sure = count == k ? (m1 == kNoDistance || (m1 > 0.0 && result.back().squared_distance < m1 * m1)) : m1 == kNoDistance;
      if (!sure) {
        // Wider rings, then the kd-tree.
        Candidates& w = wide.local();
        bool done = false;
        for (std::int64_t ring = 2; ring <= kMaxRing && !done; ++ring) {
          g.gather(c, ring, w);
          w.distances_to(qx, qy, qz);
          count = Impl::select(w, k, kNoDistance, sorted);
          const double mr = g.margin(c, ring, qx, qy, qz);
          done = count == k ? (mr == kNoDistance || (mr > 0.0 && w.found[count - 1].squared_distance < mr * mr)) : mr == kNoDistance;
          result = std::span<const Neighbor>(w.found.data(), count);
        }
        if (!done) {
          std::vector<Neighbor>& out = from_tree.local();
          g.fallback_tree().knn(g.points[g.index[p]], k, out);
          result = out;
        }
      }
      visit(g.index[p], result);
    }
  });
}

void VoxelGrid::for_each_radius(double radius, const Visit& visit) const {
  if (!(radius >= 0.0)) throw UsageError(fmt::format("VoxelGrid::for_each_radius: radius must be >= 0, got {}", radius));
  const Impl& g = *impl_;
  const double squared_radius = radius * radius;
  g.over_cells(g.ring_for_radius(radius), [&](std::size_t cell, const std::array<std::int64_t, 3>&, Candidates& cand) {
    for (std::size_t p = g.cell_start[cell]; p < g.cell_start[cell + 1]; ++p) {
      cand.distances_to(g.x[p], g.y[p], g.z[p]);
      const std::size_t count = Impl::select(cand, cand.size(), squared_radius);
      // select() falls back to every candidate when fewer than asked pass the bound: keep
      // only those within the radius.
      std::size_t within = 0;
      while (within < count && cand.found[within].squared_distance <= squared_radius) ++within;
      visit(g.index[p], std::span<const Neighbor>(cand.found.data(), within));
    }
  });
}

std::vector<std::uint32_t> VoxelGrid::count_within(double radius, std::uint32_t cap) const {
  if (!(radius >= 0.0)) throw UsageError(fmt::format("VoxelGrid::count_within: radius must be >= 0, got {}", radius));
  const Impl& g = *impl_;
  const double squared_radius = radius * radius;
  std::vector<std::uint32_t> counts(size(), 0);
  g.over_cells(g.ring_for_radius(radius), [&](std::size_t cell, const std::array<std::int64_t, 3>&, Candidates& cand) {
    const std::size_t m = cand.size();
    for (std::size_t p = g.cell_start[cell]; p < g.cell_start[cell + 1]; ++p) {
      const double qx = g.x[p], qy = g.y[p], qz = g.z[p];
      std::uint32_t count = 0;
      // Own cell first (gather puts it there): dense clouds reach the cap without leaving it.
      for (std::size_t j = 0; j < m && count < cap; ++j) {
        const double dx = qx - cand.x[j], dy = qy - cand.y[j], dz = qz - cand.z[j];
        double s = 0.0;
        s += dx * dx;
        s += dy * dy;
        s += dz * dz;
        count += s <= squared_radius;
      }
      counts[g.index[p]] = count;
    }
  });
  return counts;
}

}  // namespace pointsurf
