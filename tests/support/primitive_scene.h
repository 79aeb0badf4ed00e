// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// A synthetic scene of known primitives for segmentation and primitive detection tests.
#include <cstdint>
#include <vector>

#include "pointsurf/core/point_cloud.h"
#include "pointsurf/shape/primitives.h"

namespace pointsurf::test {

struct PrimitiveScene {
  PointCloud cloud;                 // points with exact normals; field "truth": primitive index
  std::vector<Primitive> truth;     // ground plane, back wall, sphere, cylinder, cone
  double size = 10.0;               // scene size (box side)
};

/// Ground plane z = 0 over [-5, 5]^2, wall y = 5, a sphere, a tilted cylinder and a cone
/// (apex up, axis down), each sampled uniformly by area (`per_unit_area` points per unit^2),
/// with Gaussian noise of `sigma` along the normal.
PrimitiveScene make_primitive_scene(double per_unit_area = 300.0, double sigma = 0.005, std::uint64_t seed = 1);

}  // namespace pointsurf::test
