// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/core/triangle_mesh.h"

#include <fmt/format.h>

#include "pointsurf/core/error.h"

namespace pointsurf {

void TriangleMesh::validate() const {
  const std::size_t n = vertices.size();
  if (!vertex_normals.empty() && vertex_normals.size() != n)
    throw InputError(fmt::format("mesh: {} vertex normals for {} vertices", vertex_normals.size(), n));
  if (!vertex_colors.empty() && vertex_colors.size() != n)
    throw InputError(fmt::format("mesh: {} vertex colours for {} vertices", vertex_colors.size(), n));
  for (const ScalarField& f : vertex_fields)
    if (f.values.size() != n)
      throw InputError(fmt::format("mesh: field '{}' has {} values for {} vertices", f.name, f.values.size(), n));
  for (const ScalarField& f : face_fields)
    if (f.values.size() != triangles.size())
      throw InputError(fmt::format("mesh: face field '{}' has {} values for {} triangles", f.name, f.values.size(), triangles.size()));
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (int c = 0; c < 3; ++c)
      if (triangles[t][c] < 0 || static_cast<std::size_t>(triangles[t][c]) >= n)
        throw InputError(fmt::format("mesh: triangle {}: vertex index {} out of range [0, {})", t, triangles[t][c], n));
}

PointCloud TriangleMesh::vertex_cloud() const {
  PointCloud cloud;
  cloud.positions = vertices;
  cloud.normals = vertex_normals;
  cloud.colors = vertex_colors;
  cloud.fields = vertex_fields;
  cloud.crs = crs;
  return cloud;
}

TriangleMesh TriangleMesh::from_cloud(PointCloud cloud, std::vector<Triangle> triangles, FieldSet face_fields) {
  TriangleMesh mesh;
  mesh.vertices = std::move(cloud.positions);
  mesh.vertex_normals = std::move(cloud.normals);
  mesh.vertex_colors = std::move(cloud.colors);
  mesh.vertex_fields = std::move(cloud.fields);
  mesh.crs = std::move(cloud.crs);
  mesh.triangles = std::move(triangles);
  mesh.face_fields = std::move(face_fields);
  return mesh;
}

}  // namespace pointsurf
