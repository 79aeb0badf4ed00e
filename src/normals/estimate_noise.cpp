// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/normals/noise.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <vector>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/detail/local_pca.h"
#include "pointsurf/core/error.h"

namespace pointsurf {

NoiseEstimate estimate_noise(const PointCloud& cloud, const KdTree& tree, std::size_t k, std::size_t max_samples, std::uint64_t seed) {
  if (k < 4) throw UsageError(fmt::format("estimate_noise: k = {}, expected at least 4", k));
  const std::size_t n = cloud.size();
  NoiseEstimate out;
  if (n < k) return out;
  std::vector<std::uint32_t> pick(n);
  std::iota(pick.begin(), pick.end(), 0u);
  if (n > max_samples) {
    std::mt19937_64 rng(seed);
    for (std::size_t i = 0; i < max_samples; ++i) std::swap(pick[i], pick[i + rng() % (n - i)]);
    pick.resize(max_samples);
    std::sort(pick.begin(), pick.end());
  }
  std::vector<double> ratio(pick.size(), -1.0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, pick.size()), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<Neighbor> near;
    for (std::size_t s = r.begin(); s != r.end(); ++s) {
      const Vector3d& x = cloud.positions[pick[s]];
      tree.knn(x, k, near);
      // Local spacing: the 3 nearest other points (exact copies skipped).
      double spacing = 0.0;
      int counted = 0;
      for (const Neighbor& nb : near)
        if (nb.squared_distance > 0.0 && counted < 3) {
          spacing += std::sqrt(nb.squared_distance);
          ++counted;
        }
      if (counted < 3) continue;
      spacing /= 3.0;
      const detail::LocalPca pca = detail::local_pca([&](std::size_t j) { return Vector3d(cloud.positions[near[j].index] - x); }, near.size());
      if (!pca.valid) continue;
      const double l0 = pca.eigenvalues[0];
      ratio[s] = std::sqrt(std::max(l0, 0.0)) / spacing;
    }
  });
  ratio.erase(std::remove(ratio.begin(), ratio.end(), -1.0), ratio.end());
  out.samples = ratio.size();
  if (ratio.empty()) return out;
  const auto at = [&](double q) {
    const std::size_t i = std::min(ratio.size() - 1, std::size_t(q * double(ratio.size() - 1) + 0.5));
    std::nth_element(ratio.begin(), ratio.begin() + std::ptrdiff_t(i), ratio.end());
    return ratio[i];
  };
  out.median_in_spacings = at(0.5);
  out.p90_in_spacings = at(0.9);
  return out;
}

}  // namespace pointsurf
