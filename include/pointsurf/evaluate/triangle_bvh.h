// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// A bounding-volume hierarchy over the triangles of a mesh: exact closest points (double
// precision about a local origin, so 1e6 m coordinates lose nothing), the generalized winding
// number (Barill, Dickson, Schmidt, Levin, Jacobson 2018, "Fast winding numbers for soups and
// clouds") and box-overlap queries for the self-intersection pass.
#include <array>
#include <cstddef>
#include <functional>
#include <limits>
#include <mutex>
#include <optional>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/core/triangle_mesh.h"

namespace pointsurf {

/// Which part of a triangle the closest point lies on.
enum class TriangleFeature : unsigned char { Face, Edge, Vertex };

/// The closest point of a mesh to a query.
struct ClosestPoint {
  double squared_distance = std::numeric_limits<double>::infinity();  // squared cloud units
  Vector3d point = Vector3d::Zero();   // on the mesh, cloud units (absolute coordinates)
  int triangle = -1;                   // index into the mesh's triangles; -1: none found
  TriangleFeature feature = TriangleFeature::Face;
  int local_index = 0;                 // Vertex: corner 0..2; Edge: edge i from corner i to i+1
  bool found() const noexcept { return triangle >= 0; }
};

/// The hierarchy. Built once (parallel, O(F log F)); every query is const and thread-safe.
/// The triangles' corners are held relative to the centre of the mesh's bounding box.
/// Closest points walk a 4-wide hierarchy with float boxes rounded outward (the binary one
/// collapsed), so a box never excludes a triangle that its corners put inside it.
/// Among triangles at the same distance the one of smallest index answers, whatever the walk.
/// Triangles with a vertex index out of range throw InputError at construction; degenerate
/// triangles (repeated or collinear corners) are kept and answered as segments.
class TriangleBvh {
public:
  /// `progress` hears fractions of the build (subtrees finished); its false answer throws
  /// CancelledError.
  TriangleBvh(std::span<const Vector3d> vertices, std::span<const Triangle> triangles, const ProgressCallback& progress = {});
  explicit TriangleBvh(const TriangleMesh& mesh, const ProgressCallback& progress = {})
      : TriangleBvh(mesh.vertices.positions, mesh.triangles, progress) {}

  std::size_t triangle_count() const noexcept { return corners_.size(); }
  const Vector3d& origin() const noexcept { return origin_; }

  /// The closest point of the mesh to `query`, among points closer than `max_distance`
  /// (cloud units); `found()` is false when none is, or the mesh has no triangle.
  ClosestPoint closest(const Vector3d& query, double max_distance = std::numeric_limits<double>::infinity()) const;

  /// The same answer as closest(query, max_distance), the same triangle included, found faster
  /// when `on_mesh` is a point of the mesh near the query (the previous query's closest point,
  /// in spatial order): its distance bounds the walk from the start. Absolute coordinates.
  ClosestPoint closest_near(const Vector3d& query, const std::optional<Vector3d>& on_mesh,
                            double max_distance = std::numeric_limits<double>::infinity()) const;

  /// The same answer as closest(query, max_distance), found faster when `hint` (the mesh's
  /// index) is a triangle near the query: the previous query's, in spatial order. Its distance
  /// bounds the walk from the start; -1 or an index out of range: no hint.
  ClosestPoint closest_near(const Vector3d& query, int hint, double max_distance = std::numeric_limits<double>::infinity()) const;

  /// Generalized winding number of the mesh at `query`: 1 inside and 0 outside a closed,
  /// outward-oriented surface, a smooth value in between near cracks and holes, and a sum over
  /// pieces where they overlap. Far clusters are replaced by their dipole (first-order)
  /// expansion when farther than `accuracy` times their radius (Barill et al. use 2).
  double winding_number(const Vector3d& query, double accuracy = 2.0) const;

  /// Calls `visit(t)` for every triangle whose bounding box overlaps [lo, hi] (absolute
  /// coordinates).
  void overlapping(const Vector3d& lo, const Vector3d& hi, const std::function<void(int)>& visit) const;

  /// The mesh's triangle indices in the order of the hierarchy's leaves: neighbours in space lie
  /// side by side, so queries made in this order walk the same nodes one after the other.
  std::span<const int> leaf_order() const noexcept { return order_; }

  /// Corner `c` (0..2) of triangle `t` (the mesh's index), relative to origin().
  const Vector3d& corner(std::size_t t, int c) const noexcept { return corners_[static_cast<std::size_t>(slot_[t])][static_cast<std::size_t>(c)]; }

private:
  // The binary hierarchy: what the winding number walks (with its dipoles).
  struct Node {
    Vector3d lo, hi;                 // box, relative to origin
    int first = 0, count = 0;        // leaf: range of leaf-order slots; inner: count == 0
    int right = 0;                   // inner: right child index (left child is index + 1)
  };
  // What only the winding number reads, made on its first call.
  struct Dipole {
    Vector3d area_centroid = Vector3d::Zero();  // area-weighted centroid
    Vector3d area_normal = Vector3d::Zero();    // sum of area vectors (half the cross products)
    double area = 0.0;
    double radius = 0.0;             // farthest box corner from area_centroid
  };
  // What the closest-point and overlap walks read: the boxes of up to 4 children side by side
  // (float, rounded outward), two cache lines. count[k] > 0: a leaf of that many slots from
  // child[k]; 0: wide node child[k]; -1: no child (its box empty).
  struct alignas(64) WideNode {
    float lo[3][4], hi[3][4];
    int child[4], count[4];
  };
  // A triangle's corners, left uninitialized by construction (a vector of them is filled at once).
  struct Corners {
    Vector3d c[3];
    Corners() {}  // NOLINT(modernize-use-equals-default): = default would zero them in a vector
    const Vector3d& operator[](std::size_t i) const noexcept { return c[i]; }
  };
  // Four triangles (one leaf) in float lanes for a lower bound of their distance: corner a,
  // edges ab and ac, unit normal, the in-plane dual vectors giving the barycentric coordinates
  // of b and c (with their lengths), the inverse squared lengths of ab, ac and bc, and the sum
  // of the squared edge lengths. A degenerate triangle has zero normal and duals: bound 0.
  struct alignas(64) LeafLanes {
    float a[3][4], ab[3][4], ac[3][4], n[3][4], gb[3][4], gc[3][4];
    float gb_norm[4], gc_norm[4], inv_ab2[4], inv_ac2[4], inv_bc2[4], edges2[4];
  };
  struct BuildItem;
  struct BuildInput;
  void build(int node, int begin, int end, std::vector<BuildItem>& items, const BuildInput& in, int depth);
  int collapse(int node);
  void make_lanes();
  void make_dipoles(int node, int depth) const;
  const Vector3d& slot_corner(std::size_t slot, int c) const noexcept { return corners_[slot][static_cast<std::size_t>(c)]; }
  Vector3d origin_ = Vector3d::Zero();
  std::vector<Corners> corners_;     // per leaf-order slot, relative to origin
  std::vector<int> order_;           // leaf-order slot -> the mesh's triangle index
  std::vector<int> slot_;            // the mesh's triangle index -> leaf-order slot
  std::vector<Node> nodes_;
  std::vector<WideNode> wide_;       // root first
  std::vector<LeafLanes> lanes_;     // per 4 leaf-order slots (a leaf's)
  double corner_extent_ = 0.0;       // largest |coordinate| of a corner about the origin
  mutable std::vector<Dipole> dipoles_;  // one per node
  mutable std::once_flag dipoles_once_;
};

/// Closest point of triangle (a, b, c) to p (Ericson, Real-Time Collision Detection 5.1.5), in
/// the caller's frame. Degenerate triangles are answered through their edges.
ClosestPoint closest_point_on_triangle(const Vector3d& p, const Vector3d& a, const Vector3d& b, const Vector3d& c);

}  // namespace pointsurf
