// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
#include <cstdint>

#include <Eigen/Core>

#include "pointsurf/surface/bspline_surface.h"

namespace pointsurf::test {

/// A surface over [0, 1]^2 of degree 3 in u (interior knots 0.2, 0.45 twice, 0.7) and degree q in
/// v (interior knots 0.3, 0.6), its net a grid (i, 0.8 j) jittered by a seeded RNG, about
/// `origin`.
BSplineSurface wavy_bspline(int q = 3, const Eigen::Vector3d& origin = Eigen::Vector3d::Zero(), std::uint32_t seed = 7);

}  // namespace pointsurf::test
