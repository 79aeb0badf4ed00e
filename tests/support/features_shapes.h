// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Shapes with sharp edges known by construction, for scoring feature detection: every sample
// carries its exact distance to the nearest sharp edge and to the nearest corner.
#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/triangle_mesh.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf::test {

struct FeatureShape {
  PointCloud cloud;                    // positions (and exact normals when the sampler gives them)
  std::vector<double> edge_distance;   // N: distance from the noiseless sample to the nearest sharp edge
  std::vector<double> corner_distance; // N: distance to the nearest corner (where >= 3 faces meet)
  std::vector<double> edge_turn_deg;   // N or empty: angle between the face normals at the nearest sharp edge
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

/// The sharp edges of a mesh: edges shared by exactly two faces (vertices welded by position:
/// several CAD meshes repeat a vertex per face set) whose normals turn by at least sharp_deg
/// degrees, with exact distances to them.
class SharpEdges {
 public:
  SharpEdges(const TriangleMesh& mesh, double sharp_deg);
  bool empty() const noexcept { return segments_.empty(); }
  /// Distance from p to the nearest sharp edge (+inf without any), and that edge's turn in
  /// degrees through `turn_deg` when given.
  double distance(const Vector3d& p, double* turn_deg = nullptr) const;
  /// Vertices where three or more sharp edges meet.
  const std::vector<Vector3d>& corners() const noexcept { return corners_; }

 private:
  std::vector<std::array<Vector3d, 2>> segments_;
  std::vector<double> turn_deg_;
  std::vector<Vector3d> corners_;
  std::vector<Vector3d> laid_;              // points laid along the segments every step_
  std::vector<std::uint32_t> laid_segment_;
  double step_ = 0.0;
  std::shared_ptr<const KdTree> laid_tree_;
};

/// n points area-uniformly on the triangles of `mesh` (seeded), each with its face normal;
/// edge_distance and edge_turn_deg from SharpEdges(mesh, sharp_deg) (issue 13's truth for CAD
/// parts uses 30 degrees); corner_distance to the nearest of its corners. A mesh without sharp
/// edges gives distances of +inf.
FeatureShape sample_mesh_features(const TriangleMesh& mesh, std::size_t n, double sharp_deg = 30.0, std::uint64_t seed = 1);

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
