// SPDX-License-Identifier: GPL-3.0-or-later
#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "pointsurf/core/error.h"
#include "pointsurf/core/point_cloud.h"
#include "pointsurf/spatial/kd_tree.h"
#include "spatial/detail/morton.h"

namespace pointsurf {
namespace {

constexpr int kBitsPerAxis = 21;  // 3 x 21 = 63 bits: one uint64 key
constexpr double kCells = double((1u << kBitsPerAxis) - 1);

std::uint64_t quantise(double v, double lo, double scale) {
  const double cell = (v - lo) * scale;
  // NaN and out-of-range values (non-finite boxes) land in the first or last cell.
  if (!(cell > 0.0)) return 0;
  if (cell >= kCells) return std::uint64_t(kCells);
  return std::uint64_t(cell);
}

}  // namespace

std::vector<std::uint32_t> morton_order(std::span<const Eigen::Vector3d> points) {
  const std::size_t n = points.size();
  if (n > std::numeric_limits<std::uint32_t>::max())
    throw UsageError(fmt::format("morton_order: {} points exceed the limit of {}", n,
                                 std::numeric_limits<std::uint32_t>::max()));
  const BoundingBox box = bounding_box(points);
  const Eigen::Vector3d extent = box.extent();
  Eigen::Vector3d scale;
  for (int a = 0; a < 3; ++a) scale[a] = (extent[a] > 0.0 && std::isfinite(extent[a])) ? kCells / extent[a] : 0.0;

  std::vector<std::pair<std::uint64_t, std::uint32_t>> keys(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const Eigen::Vector3d& p = points[i];
      const std::uint64_t key = detail::morton_spread(quantise(p.x(), box.min.x(), scale.x())) |
                                (detail::morton_spread(quantise(p.y(), box.min.y(), scale.y())) << 1) |
                                (detail::morton_spread(quantise(p.z(), box.min.z(), scale.z())) << 2);
      keys[i] = {key, static_cast<std::uint32_t>(i)};
    }
  });
  tbb::parallel_sort(keys.begin(), keys.end());

  std::vector<std::uint32_t> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = keys[i].second;
  return order;
}

}  // namespace pointsurf
