// SPDX-License-Identifier: GPL-3.0-or-later
#include "support/shape_samplers.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

namespace pointsurf::test {

PointCloud sample_cylinder(std::size_t n, double radius, double half_height, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> angle(0.0, 2.0 * std::numbers::pi);
  std::uniform_real_distribution<double> height(-half_height, half_height);
  PointCloud cloud;
  cloud.positions.reserve(n);
  cloud.normals.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double a = angle(rng);  // sequenced: the order of RNG draws is fixed
    const double z = height(rng);
    const Vector3d radial(std::cos(a), std::sin(a), 0.0);
    cloud.positions.push_back(radius * radial + Vector3d(0.0, 0.0, z));
    cloud.normals.push_back(radial);
  }
  return cloud;
}

PointCloud sample_quadric_graph(std::size_t n, double a, double b, double half, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-half, half);
  PointCloud cloud;
  cloud.positions.reserve(n);
  cloud.normals.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double x = u(rng);
    const double y = u(rng);
    cloud.positions.emplace_back(x, y, a * x * x + b * y * y);
    cloud.normals.push_back(Vector3d(-2.0 * a * x, -2.0 * b * y, 1.0).normalized());
  }
  return cloud;
}

GraphCurvature quadric_graph_curvature(double a, double b, double x, double y) {
  const double fx = 2.0 * a * x, fy = 2.0 * b * y, fxx = 2.0 * a, fyy = 2.0 * b;
  const double w2 = 1.0 + fx * fx + fy * fy;
  const double w = std::sqrt(w2);
  GraphCurvature c;
  // With the normal facing +z the surface bends away from it where f is concave: minus the
  // usual graph formulas for H; K keeps its sign.
  c.mean = -((1.0 + fy * fy) * fxx + (1.0 + fx * fx) * fyy) / (2.0 * w2 * w);
  c.gauss = fxx * fyy / (w2 * w2);
  const double disc = std::sqrt(std::max(c.mean * c.mean - c.gauss, 0.0));
  c.k1 = c.mean + disc;
  c.k2 = c.mean - disc;
  return c;
}

}  // namespace pointsurf::test
