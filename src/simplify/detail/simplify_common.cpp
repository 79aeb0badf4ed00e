// SPDX-License-Identifier: GPL-3.0-or-later
#include "simplify/detail/simplify_common.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <functional>
#include <cmath>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include "pointsurf/core/error.h"
#include "pointsurf/normals/normals.h"

namespace pointsurf::detail {
namespace {

constexpr int kAxisBits = 21;
constexpr std::int64_t kAxisCells = std::int64_t(1) << kAxisBits;

struct KeyIndex {
  std::uint64_t key;
  std::uint32_t index;
};

std::uint64_t cell_key(const Vector3d& p, const Grid& grid) {
  // Offsets from the grid origin are small numbers, so georeferenced clouds keep their cells.
  const Vector3d r = (p - grid.origin) / grid.cell;
  const auto axis = [](double v) {
    return static_cast<std::uint64_t>(std::clamp<std::int64_t>(static_cast<std::int64_t>(std::floor(v)), 0, kAxisCells - 1));
  };
  return (axis(r.z()) << (2 * kAxisBits)) | (axis(r.y()) << kAxisBits) | axis(r.x());
}

// Rank of a cell key in the grid's dense x-fastest numbering: the same order as the key.
std::uint64_t dense_key(std::uint64_t key, const Grid& grid) {
  const std::uint64_t x = key & (kAxisCells - 1), y = (key >> kAxisBits) & (kAxisCells - 1), z = key >> (2 * kAxisBits);
  return x + grid.nx * (y + grid.ny * z);
}

std::uint64_t key_of_dense(std::uint64_t d, const Grid& grid) {
  const std::uint64_t x = d % grid.nx, y = (d / grid.nx) % grid.ny, z = d / (grid.nx * grid.ny);
  return (z << (2 * kAxisBits)) | (y << kAxisBits) | x;
}

// A dense numbering pays (an array over all cells) when the cells are not many more than the points.
bool dense_pays(const Grid& grid, std::size_t points) {
  return grid.cells() <= std::max<std::uint64_t>(4 * std::uint64_t(points), std::uint64_t(1) << 16);
}

// One bit per dense cell rank: set in parallel, then ranks (occupied cells below) by popcount.
class OccupancyBitmap {
 public:
  explicit OccupancyBitmap(std::uint64_t cells) : words_((cells + 63) / 64, 0) {}
  void set(std::uint64_t d) {
    std::uint64_t& word = words_[d >> 6];
    const std::uint64_t bit = std::uint64_t(1) << (d & 63);
    if ((std::atomic_ref<std::uint64_t>(word).load(std::memory_order_relaxed) & bit) == 0)
      std::atomic_ref<std::uint64_t>(word).fetch_or(bit, std::memory_order_relaxed);
  }
  // Prefix counts per word; returns the number of occupied cells.
  std::size_t finish() {
    below_.resize(words_.size());
    std::size_t total = 0;
    for (std::size_t w = 0; w < words_.size(); ++w) {
      below_[w] = total;
      total += static_cast<std::size_t>(std::popcount(words_[w]));
    }
    return total;
  }
  std::size_t rank(std::uint64_t d) const {
    const std::uint64_t below_bits = words_[d >> 6] & ((std::uint64_t(1) << (d & 63)) - 1);
    return below_[d >> 6] + static_cast<std::size_t>(std::popcount(below_bits));
  }
  template <typename Visit>
  void for_each(Visit&& visit) const {  // occupied ranks, ascending
    for (std::size_t w = 0; w < words_.size(); ++w)
      for (std::uint64_t bits = words_[w]; bits != 0; bits &= bits - 1) visit((std::uint64_t(w) << 6) + std::countr_zero(bits));
  }

 private:
  std::vector<std::uint64_t> words_;
  std::vector<std::size_t> below_;
};

// A bitmap over all cells pays when it is not much larger than the points' own arrays.
bool bitmap_pays(const Grid& grid, std::size_t points) {
  return grid.cells() <= std::max<std::uint64_t>(64 * std::uint64_t(points), std::uint64_t(1) << 20) &&
         grid.cells() <= (std::uint64_t(1) << 32);
}

}  // namespace

void check_simplify_input(std::string_view function, const PointCloud& cloud, const SimplifyTarget& target, bool allow_cell,
                          bool allow_growth) {
  if (cloud.empty()) throw UsageError(fmt::format("{}: the cloud is empty", function));
  cloud.validate();
  if (cloud.size() > std::size_t(0xffffffffu))
    throw UsageError(fmt::format("{}: {} points; at most 2^32 - 1 are supported", function, cloud.size()));
  if (!(target.cell >= 0.0) || !std::isfinite(target.cell))
    throw UsageError(fmt::format("{}: target.cell must be >= 0 (cloud units), got {}", function, target.cell));
  if (target.cell > 0.0 && !allow_cell)
    throw UsageError(fmt::format("{}: target.cell {} is not supported by this method; give a ratio or a count", function, target.cell));
  if (target.cell == 0.0 && target.count == 0 && !(target.ratio > 0.0 && target.ratio <= 1.0))
    throw UsageError(fmt::format("{}: target.ratio must be in (0, 1], got {}", function, target.ratio));
  if (target.cell == 0.0 && target.count > cloud.size() && !allow_growth)
    throw UsageError(fmt::format("{}: target.count {} exceeds the {} input points", function, target.count, cloud.size()));
}

const KdTree& tree_or_own(std::string_view function, const PointCloud& cloud, const KdTree* tree, std::optional<KdTree>& own) {
  if (tree == nullptr) return own.emplace(cloud.positions);
  if (tree->size() != cloud.size())
    throw UsageError(fmt::format("{}: the kd-tree holds {} points but the cloud has {}", function, tree->size(), cloud.size()));
  return *tree;
}

ProgressCallback sub_progress(const ProgressCallback& progress, double begin, double end) {
  return pointsurf::sub_progress(progress, begin, end);
}

std::size_t target_count(const SimplifyTarget& target, std::size_t n) {
  if (target.count > 0) return target.count;
  return std::max<std::size_t>(1, static_cast<std::size_t>(std::llround(target.ratio * double(n))));
}

SurfaceProperties surface_properties(const PointCloud& cloud, int k, const KdTree& tree, bool need_normals,
                                     const ProgressCallback& progress) {
  SurfaceProperties out;
  const ScalarField* variation = cloud.fields.find("variation");
  const bool have_variation = variation != nullptr && variation->values.size() == cloud.size();
  if (have_variation && (!need_normals || cloud.has_normals())) {
    out.variation = variation->values;
    if (need_normals) out.normals = cloud.normals;
    return out;
  }
  if (cloud.size() < 3) {  // too few points for PCA: no curvature information
    out.variation.assign(cloud.size(), 0.0);
    out.normals = cloud.has_normals() ? cloud.normals : std::vector<Vector3d>(cloud.size(), Vector3d::Zero());
    return out;
  }
  PointCloud work;
  work.positions = cloud.positions;
  NormalParams params;
  params.k = k;
  estimate_normals(work, params, &tree, progress);
  out.variation = std::move(work.fields.find("variation")->values);
  if (need_normals) {
    out.estimated_normals = !cloud.has_normals();
    out.normals = cloud.has_normals() ? cloud.normals : std::move(work.normals);
  }
  return out;
}

Grid make_grid(std::string_view function, const BoundingBox& box, double cell) {
  if (!(cell > 0.0) || !std::isfinite(cell)) throw UsageError(fmt::format("{}: cell must be > 0 (cloud units), got {}", function, cell));
  Grid grid;
  grid.cell = cell;
  grid.origin = box.min - Vector3d::Constant(0.5 * cell);
  const double cells = (box.extent().maxCoeff() + cell) / cell;
  if (!(cells < double(kAxisCells)))
    throw UsageError(fmt::format("{}: cell {} is too small for the cloud's extent {} (more than 2^21 cells along an axis)", function,
                                 cell, box.extent().maxCoeff()));
  const std::uint64_t corner = cell_key(box.max, grid);  // the largest key on every axis
  grid.nx = (corner & (kAxisCells - 1)) + 1;
  grid.ny = ((corner >> kAxisBits) & (kAxisCells - 1)) + 1;
  grid.nz = (corner >> (2 * kAxisBits)) + 1;
  return grid;
}

GridCells sort_into_cells(std::span<const Vector3d> points, std::span<const std::uint32_t> subset, bool all, const Grid& grid) {
  const std::size_t m = all ? points.size() : subset.size();
  const auto index_of = [&](std::size_t q) { return all ? static_cast<std::uint32_t>(q) : subset[q]; };
  GridCells cells;
  cells.order.resize(m);
  if (dense_pays(grid, m)) {
    // Few cells for the points: a stable counting sort over the dense cell rank, O(N + cells);
    // ties stay in index order as the comparison sort would leave them.
    std::vector<std::uint32_t> dense(m);
    std::vector<std::uint32_t> count(grid.cells() + 1, 0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t q = r.begin(); q != r.end(); ++q) {
        dense[q] = static_cast<std::uint32_t>(dense_key(cell_key(points[index_of(q)], grid), grid));
        std::atomic_ref<std::uint32_t>(count[dense[q] + 1]).fetch_add(1, std::memory_order_relaxed);
      }
    });
    for (std::size_t d = 0; d + 1 < count.size(); ++d) {
      if (count[d + 1] != 0) {
        cells.keys.push_back(key_of_dense(d, grid));
        cells.starts.push_back(count[d]);
      }
      count[d + 1] += count[d];
    }
    cells.starts.push_back(m);
    for (std::size_t q = 0; q < m; ++q) cells.order[count[dense[q]]++] = index_of(q);
    return cells;
  }
  if (grid.cells() <= (std::uint64_t(1) << 32)) {
    // Sparse occupation: sort packed (cell rank, index) words.
    std::vector<std::uint64_t> packed(m);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t q = r.begin(); q != r.end(); ++q) packed[q] = (dense_key(cell_key(points[index_of(q)], grid), grid) << 32) | index_of(q);
    });
    tbb::parallel_sort(packed.begin(), packed.end());
    for (std::size_t q = 0; q < m; ++q) {
      cells.order[q] = static_cast<std::uint32_t>(packed[q] & 0xffffffffu);
      if (q == 0 || (packed[q] >> 32) != (packed[q - 1] >> 32)) {
        cells.keys.push_back(key_of_dense(packed[q] >> 32, grid));
        cells.starts.push_back(q);
      }
    }
    cells.starts.push_back(m);
    return cells;
  }
  std::vector<KeyIndex> sorted(m);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t q = r.begin(); q != r.end(); ++q) sorted[q] = {cell_key(points[index_of(q)], grid), index_of(q)};
  });
  tbb::parallel_sort(sorted.begin(), sorted.end(),
                     [](const KeyIndex& a, const KeyIndex& b) { return a.key < b.key || (a.key == b.key && a.index < b.index); });
  for (std::size_t q = 0; q < m; ++q) {
    cells.order[q] = sorted[q].index;
    if (q == 0 || sorted[q].key != sorted[q - 1].key) {
      cells.keys.push_back(sorted[q].key);
      cells.starts.push_back(q);
    }
  }
  cells.starts.push_back(m);
  return cells;
}

CellLabels label_cells(std::span<const Vector3d> points, const Grid& grid) {
  const std::size_t m = points.size();
  CellLabels labels;
  labels.cell_of.resize(m);
  if (!bitmap_pays(grid, m)) {
    GridCells cells = sort_into_cells(points, {}, true, grid);
    labels.count.resize(cells.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cells.size(), 1024), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t s = r.begin(); s != r.end(); ++s) {
        labels.count[s] = static_cast<std::uint32_t>(cells.starts[s + 1] - cells.starts[s]);
        for (std::size_t q = cells.starts[s]; q != cells.starts[s + 1]; ++q) labels.cell_of[cells.order[q]] = static_cast<std::uint32_t>(s);
      }
    });
    labels.keys = std::move(cells.keys);
    return labels;
  }
  // Dense rank per point and a bitmap of occupied ranks (one bit per cell: small enough to
  // stay in cache); a cell's number is the count of occupied ranks below its own.
  OccupancyBitmap occupied(grid.cells());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t q = r.begin(); q != r.end(); ++q) {
      const std::uint64_t d = dense_key(cell_key(points[q], grid), grid);
      labels.cell_of[q] = static_cast<std::uint32_t>(d);
      occupied.set(d);
    }
  });
  const std::size_t cells = occupied.finish();
  labels.keys.reserve(cells);
  occupied.for_each([&](std::uint64_t d) { labels.keys.push_back(key_of_dense(d, grid)); });
  labels.count.assign(cells, 0);
  for (std::uint32_t& c : labels.cell_of) {
    c = static_cast<std::uint32_t>(occupied.rank(c));
    ++labels.count[c];
  }
  return labels;
}

std::size_t count_cells(std::span<const Vector3d> points, std::span<const std::uint32_t> subset, bool all, const Grid& grid) {
  const std::size_t m = all ? points.size() : subset.size();
  if (bitmap_pays(grid, m)) {
    OccupancyBitmap occupied(grid.cells());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
      for (std::size_t q = r.begin(); q != r.end(); ++q) occupied.set(dense_key(cell_key(points[all ? q : subset[q]], grid), grid));
    });
    return occupied.finish();
  }
  std::vector<std::uint64_t> keys(m);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, m, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t q = r.begin(); q != r.end(); ++q) keys[q] = cell_key(points[all ? q : subset[q]], grid);
  });
  tbb::parallel_sort(keys.begin(), keys.end());
  return static_cast<std::size_t>(std::unique(keys.begin(), keys.end()) - keys.begin());
}

std::uint32_t nearest_to_centroid(std::span<const Vector3d> points, std::span<const std::uint32_t> members) {
  const Vector3d& base = points[members[0]];
  Vector3d sum = Vector3d::Zero();
  for (std::uint32_t i : members) sum += points[i] - base;
  const Vector3d mean = sum / double(members.size());
  std::uint32_t best = members[0];
  double best_d = (points[best] - base - mean).squaredNorm();
  for (std::uint32_t i : members) {
    const double d = (points[i] - base - mean).squaredNorm();
    if (d < best_d) best = i, best_d = d;
  }
  return best;
}

}  // namespace pointsurf::detail

namespace pointsurf {

const FieldTable<SimplifyTarget>& SimplifyTarget::fields() {
  static const FieldTable<SimplifyTarget> table = [] {
    using P = SimplifyTarget;
    FieldTable<P> t;
    t.number("ratio", &P::ratio, "Kept fraction of the points")
        .range(0.0, 1.0, true, false)
        .meta("F")
        .when([](const P& p) { return p.count == 0 && p.cell == 0.0; });
    t.integer("count", &P::count, "Number of output points instead of ratio; 0: use ratio").unit("points");
    t.number("cell", &P::cell,
             "Length instead of a count: grid cell; Poisson-disk distance of flat points (regional, curvature-distance); "
             "spacing at the median feature size (lfs)")
        .unit("cloud units")
        .non_negative()
        .meta("S");
    return t;
  }();
  return table;
}

void SimplifyTarget::validate() const { fields().validate(*this, "simplify"); }

}  // namespace pointsurf
