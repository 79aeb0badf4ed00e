// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "pointsurf/core/point_cloud.h"

namespace pointsurf {

using Triangle = Eigen::Vector3i;  // three vertex indices, counter-clockwise seen from outside

/// A triangle mesh with double-precision vertices. Optional per-vertex attributes are either
/// empty or hold one entry per vertex; each face field holds one value per triangle (a region
/// label, a quality figure) and follows the triangles when faces are removed or reordered.
struct TriangleMesh {
  std::vector<Vector3d> vertices;         // V, cloud units
  std::vector<Triangle> triangles;        // F, indices into vertices
  std::vector<Vector3d> vertex_normals;   // 0 or V
  std::vector<Vector3f> vertex_colors;    // 0 or V, RGB in [0, 1]
  FieldSet vertex_fields;                 // each holds V values
  FieldSet face_fields;                   // each holds F values, in triangle order
  CoordinateSystem crs;                   // empty when unknown

  std::size_t vertex_count() const noexcept { return vertices.size(); }
  std::size_t triangle_count() const noexcept { return triangles.size(); }

  /// Throws InputError when an attribute size differs from the vertex count, a face field's size
  /// from the triangle count, or an index is out of range.
  void validate() const;
  /// The vertices with their attributes as a point cloud (normals, colours, fields copied).
  PointCloud vertex_cloud() const;
  /// A mesh whose vertices and attributes come from `cloud` (face fields: `face_fields`, one
  /// value per triangle each, or none).
  static TriangleMesh from_cloud(PointCloud cloud, std::vector<Triangle> triangles, FieldSet face_fields = {});
};

}  // namespace pointsurf
