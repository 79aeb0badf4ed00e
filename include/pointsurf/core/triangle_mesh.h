// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
#include <cstddef>
#include <vector>

#include <Eigen/Core>

#include "pointsurf/core/point_cloud.h"

namespace pointsurf {

using Triangle = Eigen::Vector3i;  // three vertex indices, counter-clockwise seen from outside

/// A triangle mesh: its vertices are a point cloud (double-precision positions with their
/// normals, colours, fields and CRS, one entry per vertex), its faces index them, and each face
/// field holds one value per triangle (a region label, a quality figure) and follows the
/// triangles when faces are removed or reordered. A pipeline holds clouds and meshes alike as
/// this type: a cloud is vertices without triangles.
struct TriangleMesh {
  PointCloud vertices;                    // V points with their attributes, cloud units
  std::vector<Triangle> triangles;        // F, indices into vertices
  FieldSet face_fields;                   // each holds F values, in triangle order

  std::size_t vertex_count() const noexcept { return vertices.size(); }
  std::size_t triangle_count() const noexcept { return triangles.size(); }

  /// Throws InputError when a vertex attribute's size differs from the vertex count, a face
  /// field's size from the triangle count, or an index is out of range.
  void validate() const;
};

}  // namespace pointsurf
