// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Shapes with sharp edges known by construction, for scoring feature detection: every sample
// carries its exact distance to the nearest sharp edge and to the nearest corner.
#include <cstdint>
#include <vector>

#include "pointsurf/core/point_cloud.h"

namespace pointsurf::test {

struct FeatureShape {
  PointCloud cloud;                    // positions (and exact normals when the sampler gives them)
  std::vector<double> edge_distance;   // N: distance from the noiseless sample to the nearest sharp edge
  std::vector<double> corner_distance; // N: distance to the nearest corner (where >= 3 faces meet)
};

/// n points area-uniformly on the cube [-half, half]^3 (as test::sample_cube), exact normals; its
/// 12 edges and 8 corners are the sharp features.
FeatureShape sample_cube_features(std::size_t n, double half = 1.0, std::uint64_t seed = 1);

/// n points area-uniformly on a CAD-like part (fandisk-like mix of edge angles), exact normals:
/// a plate [-2, 2] x [-1.5, 1.5] x [0, 0.5] whose top edge at x = -2 is chamfered at 45 degrees
/// (width 0.25: two 135-degree edges), a step block [1, 2] x [-1.5, 1.5] x [0.5, 0.9] on top
/// (convex and concave right-angled edges), and a cylinder of radius 0.5, height 0.6 standing
/// at (-0.5, 0) on the plate (concave circle at its foot, convex circle at its top).
FeatureShape sample_cad_part(std::size_t n, std::uint64_t seed = 1);

/// Adds Gaussian noise of standard deviation sigma to the positions (seeded); the distances
/// keep describing the noiseless samples.
void add_feature_noise(FeatureShape& shape, double sigma, std::uint64_t seed = 7);

struct FeatureScore {
  double precision = 0.0;  // labelled points within `tolerance` of an edge / labelled points (higher is better)
  double recall = 0.0;     // labelled points within `truth` of an edge / points within `truth` (higher is better)
  std::size_t labelled = 0, truth = 0;
};
/// Scores a "feature" field (non-zero = labelled) against edge distances: a labelled point is
/// correct when within `tolerance`, a point within `truth` must be labelled.
FeatureScore score_features(const std::vector<double>& labels, const std::vector<double>& edge_distance, double truth,
                            double tolerance);

}  // namespace pointsurf::test
