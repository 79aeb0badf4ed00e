// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Analytic surfaces with known curvature, sampled with seeded RNGs, for the shape tests.
#include <cstdint>

#include "pointsurf/core/point_cloud.h"

namespace pointsurf::test {

/// n points area-uniformly on the side of the cylinder x^2 + y^2 = radius^2, |z| <= half_height,
/// outward normals. Exact curvature (project convention): k1 = 1/radius, k2 = 0.
PointCloud sample_cylinder(std::size_t n, double radius = 1.0, double half_height = 1.0, std::uint64_t seed = 1);

/// n points of the graph z = a x^2 + b y^2 over (x, y) uniform in [-half, half]^2, with unit
/// normals facing +z. a = 1, b = -1 is the saddle z = x^2 - y^2.
PointCloud sample_quadric_graph(std::size_t n, double a, double b, double half = 1.0, std::uint64_t seed = 1);

/// Exact mean and Gaussian curvature of the graph z = a x^2 + b y^2 at (x, y) with the normal
/// facing +z, in the project convention (positive where the surface bends away from the normal).
struct GraphCurvature {
  double k1 = 0.0, k2 = 0.0, mean = 0.0, gauss = 0.0;
};
GraphCurvature quadric_graph_curvature(double a, double b, double x, double y);

}  // namespace pointsurf::test
