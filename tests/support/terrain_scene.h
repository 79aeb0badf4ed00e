// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// A generated aerial LiDAR tile with its truth: undulating ground, box buildings with eaves,
// trees (crowns on trunks) and a bridge deck over the ground, seen from above as an airborne
// scanner sees them.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "pointsurf/core/point_cloud.h"

namespace pointsurf::test {

// LAS classes (ASPRS) of the tile's points.
inline constexpr double kLasGround = 2.0;
inline constexpr double kLasVegetation = 5.0;
inline constexpr double kLasBuilding = 6.0;
inline constexpr double kLasBridge = 17.0;

struct TerrainTile {
  PointCloud cloud;             // positions only (normals to be estimated), offset like a georeferenced tile
  std::vector<Vector3d> exact;  // N: the exact normal of the surface each point was hit on, facing the scanner's side
  std::vector<double> truth;    // N: the LAS class of the surface hit (kLasGround, ...)
};

/// `n` returns over a 100 m x 100 m tile (about n / 10^4 per m^2) from a scanner 600 m up
/// sweeping +-20 degrees across track (x): each ray keeps its first hit, except that it passes
/// through a tree crown with probability 0.4 (a return from below) and otherwise returns from
/// a uniform depth of the foliage (0 to half the chord). Ground: a 3 % slope plus waves of 2 m;
/// four buildings 8-16 m tall whose flat roofs overhang the walls by 1 m (eaves); `trees` trees
/// (crowns of radius 2.5-4 m on 0.3 m trunks); a 6 m wide bridge deck 5 m above the ground.
/// Gaussian noise of `sigma` (m) along each ray. Seeded: the same seed gives the same tile.
TerrainTile sample_terrain_tile(std::size_t n, std::uint64_t seed, std::size_t trees = 12, double sigma = 0.03);

/// The share (0..1) of the points of class `cls` on a surface facing up at least `min_exact_z`
/// (the exact normal's z) whose normal in `cloud` (the tile's, oriented) has n_z > 0; 1 when
/// there are none.
double share_up(const TerrainTile& tile, const PointCloud& cloud, double cls, double min_exact_z = -1.0);

}  // namespace pointsurf::test
