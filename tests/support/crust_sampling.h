// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Well-spaced (blue-noise) samples for the crust tests: the Crust's guarantees hold for
// epsilon-samples, which dense random samples thinned to a minimum distance approximate.
#include "pointsurf/core/point_cloud.h"

namespace pointsurf::test {

/// Greedy Poisson-disk thinning: visits the points in input order and keeps each one farther than
/// `min_distance` from every point kept so far (all attributes kept). Deterministic.
PointCloud thin_poisson(const PointCloud& cloud, double min_distance);
/// Well-spaced samples of `dense` (thin_poisson), normals removed unless `keep_normals`.
PointCloud spaced(PointCloud dense, double min_distance, bool keep_normals = false);

}  // namespace pointsurf::test
