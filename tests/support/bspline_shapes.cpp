// SPDX-License-Identifier: GPL-3.0-or-later
#include "support/bspline_shapes.h"

#include <random>
#include <vector>

namespace pointsurf::test {

BSplineSurface wavy_bspline(int q, const Eigen::Vector3d& origin, std::uint32_t seed) {
  const std::vector<double> U = {0, 0, 0, 0, 0.2, 0.45, 0.45, 0.7, 1, 1, 1, 1};
  std::vector<double> V(std::size_t(q + 1), 0.0);
  V.push_back(0.3);
  V.push_back(0.6);
  V.insert(V.end(), std::size_t(q + 1), 1.0);
  const int nu = int(U.size()) - 4, nv = int(V.size()) - q - 1;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  std::vector<Eigen::Vector3d> net;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) net.emplace_back(double(i) + 0.2 * jitter(rng), 0.8 * double(j) + 0.2 * jitter(rng), jitter(rng));
  return BSplineSurface(3, q, U, V, nu, nv, net, origin);
}

}  // namespace pointsurf::test
