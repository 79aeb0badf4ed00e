// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Geometric primitives (planes, spheres, cylinders, cones, tori) found in an oriented point cloud by
// efficient RANSAC (Schnabel, Wahl, Klein 2007).
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/core/results.h"

namespace pointsurf {

enum class PrimitiveType : std::uint8_t { Plane = 0, Sphere = 1, Cylinder = 2, Cone = 3, Torus = 4 };

/// "plane", "sphere", "cylinder", "cone", "torus".
const EnumNames<PrimitiveType>& primitive_type_names();
/// The type's name in primitive_type_names().
const char* primitive_type_name(PrimitiveType type) noexcept;

/// Bit flags of the primitive types to look for (the library's internal form of
/// PrimitiveParams::types).
enum PrimitiveMask : unsigned {
  kPlanes = 1u,
  kSpheres = 2u,
  kCylinders = 4u,
  kCones = 8u,
  kTori = 16u,
  kAllPrimitives = 31u,
  kDefaultPrimitives = 15u,  // planes, spheres, cylinders, cones: tori on request
};

/// The PrimitiveMask bits of a list of types (duplicates allowed).
unsigned primitive_mask(const std::vector<PrimitiveType>& types) noexcept;

struct PrimitiveParams {
  // The types to look for, at least one (default: planes, spheres, cylinders, cones; tori on
  // request).
  std::vector<PrimitiveType> types = {PrimitiveType::Plane, PrimitiveType::Sphere, PrimitiveType::Cylinder, PrimitiveType::Cone};
  Length epsilon = Length::spacings(1.0);  // a candidate's score counts the compatible points this
                                        // close to it, cloud units or mean spacings, > 0
  Length cluster_epsilon = Length::spacings(3.0);  // cell size of the connectivity grid, cloud
                                        // units or mean spacings, > 0
  double band_in_epsilons = 3.0;        // extraction: the refitted primitive takes the points within
                                        // band_in_epsilons x epsilon (normal within max_normal_angle_deg),
                                        // as CGAL's Efficient_RANSAC does with 3; candidates are
                                        // scored within epsilon. >= 1
  double max_normal_angle_deg = 25.0;   // largest angle between a point's normal and the
                                        // primitive's normal there, degrees, in (0, 90)
  std::size_t min_points = 0;           // fewest inliers of a primitive; 0: max(30, N / 200)
  double probability = 0.01;            // accepted chance of missing a primitive of min_points,
                                        // in (0, 1)
  std::uint64_t seed = 42;              // random seed
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<PrimitiveParams>& fields();
  /// Throws UsageError naming the first value out of range.
  void validate() const;
};

/// One primitive in the cloud's coordinates.
struct Primitive {
  PrimitiveType type = PrimitiveType::Plane;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  // plane: inliers' centroid; sphere, torus:
                                                    // centre; cylinder: axis point nearest the
                                                    // inliers' centroid; cone: apex
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  // plane: unit normal; cylinder, cone, torus:
                                                    // unit axis (cone: from the apex into the cone)
  double radius = 0.0;                              // sphere, cylinder: radius; torus: major
                                                    // radius (centre to tube centre), cloud units
  double angle_deg = 0.0;                           // cone: half opening angle, degrees
  std::size_t inliers = 0;                          // points assigned to it
  double rms = 0.0;                                 // RMS distance of those to it, cloud units
  double minor_radius = 0.0;                        // torus: tube radius, cloud units
  /// Distance of `p` to the primitive's surface, cloud units.
  double distance(const Eigen::Vector3d& p) const;
  /// The reported members (core/results.h), all of them metrics (a report lists each primitive
  /// as a block of its own).
  static const ResultTable<Primitive>& results();
};

struct PrimitiveResult {
  std::vector<Primitive> primitives;  // in the order found (largest support first, roughly)
  std::vector<std::int32_t> labels;   // N: index into primitives, -1 unassigned
  std::size_t unassigned = 0;         // points in no primitive
  std::size_t candidates = 0;         // candidate primitives drawn
  double epsilon_used = 0.0;          // cloud units
  double cluster_epsilon_used = 0.0;  // cloud units
  std::size_t min_points_used = 0;

  /// The reported members (core/results.h); each primitive is reported through its own table.
  static const ResultTable<PrimitiveResult>& results();
};

/// Efficient RANSAC (Schnabel, Wahl, Klein 2007, "Efficient RANSAC for point-cloud shape
/// detection"): candidates are built from minimal sets of points with their normals (plane 3,
/// sphere 2, cylinder 2, cone 3, torus 4) drawn locally, the first point uniformly and the
/// others from the same cell of an octree at a random level (levels chosen in proportion to the
/// primitives they gave). Each candidate is scored lazily on random subsets of growing size
/// (points within `epsilon` whose normal deviates less than `max_normal_angle_deg`), each subset
/// held in an octree whose cells out of the candidate's epsilon band are skipped; only the
/// best candidate and those whose score interval (about two standard deviations) overlaps
/// its are refined. The best is extracted once the chance of having missed a larger one falls
/// below `probability`: its compatible points are cut to their largest connected component on
/// a grid of `cluster_epsilon`, the primitive is refitted by least squares to them (plane:
/// PCA; sphere: algebraic; cylinder: axis from the normals, circle fit across it; cone: apex
/// from the tangent planes, axis from the unit directions; torus: Levenberg-Marquardt on the
/// geometric distance), twice, taking the compatible points within `band_in_epsilons` x
/// `epsilon` of the refit, and the points are assigned. A candidate whose component is below
/// `min_points` is dropped with the candidates describing the same shape, and later draws of
/// it too. Candidates and the draws made so far are kept across extractions. Extraction
/// repeats until no primitive of `min_points` is left. Torus candidates: the axis is a common
/// transversal of the four normal lines, the tube's core circle the normals' meeting point in
/// the meridian half-plane.
/// The cloud needs normals (sign free). Coordinates are taken relative to the box centre, so a
/// georeferenced cloud keeps its precision; sampling follows a Morton order of the points, so
/// the result does not depend on their order. Parallel (oneTBB); the result is the same for a
/// seed whatever the number of threads. `progress` gets the assigned fraction after each
/// extraction and batch of draws; returning false cancels (CancelledError). Throws UsageError
/// for a bad parameter or a cloud without normals. Thread-safe (reads `cloud`).
PrimitiveResult detect_primitives(const PointCloud& cloud, const PrimitiveParams& params = {}, const ProgressCallback& progress = {});

}  // namespace pointsurf
