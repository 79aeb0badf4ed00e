// SPDX-License-Identifier: GPL-3.0-or-later
#include "support/crust_sampling.h"

#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <vector>

namespace pointsurf::test {

PointCloud thin_poisson(const PointCloud& cloud, double min_distance) {
  // Hash grid with cell size min_distance: a conflict can only be in the 27 cells around.
  auto cell_of = [&](const Vector3d& p) {
    return Eigen::Vector3i(int(std::floor(p.x() / min_distance)), int(std::floor(p.y() / min_distance)),
                           int(std::floor(p.z() / min_distance)));
  };
  auto key = [](const Eigen::Vector3i& c) {
    return (std::uint64_t(std::uint32_t(c.x()) & 0x1fffff) << 42) | (std::uint64_t(std::uint32_t(c.y()) & 0x1fffff) << 21) |
           std::uint64_t(std::uint32_t(c.z()) & 0x1fffff);
  };
  std::unordered_map<std::uint64_t, std::vector<std::size_t>> grid;
  std::vector<std::size_t> kept;
  const double d2 = min_distance * min_distance;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Vector3d& p = cloud.positions[i];
    const Eigen::Vector3i c = cell_of(p);
    bool ok = true;
    for (int dx = -1; dx <= 1 && ok; ++dx)
      for (int dy = -1; dy <= 1 && ok; ++dy)
        for (int dz = -1; dz <= 1 && ok; ++dz) {
          const auto it = grid.find(key(c + Eigen::Vector3i(dx, dy, dz)));
          if (it == grid.end()) continue;
          for (std::size_t j : it->second)
            if ((cloud.positions[j] - p).squaredNorm() < d2) {
              ok = false;
              break;
            }
        }
    if (!ok) continue;
    grid[key(c)].push_back(i);
    kept.push_back(i);
  }
  return cloud.select(kept);
}

PointCloud spaced(PointCloud dense, double min_distance, bool keep_normals) {
  PointCloud c = thin_poisson(dense, min_distance);
  if (!keep_normals) c.normals.clear();
  return c;
}

}  // namespace pointsurf::test
