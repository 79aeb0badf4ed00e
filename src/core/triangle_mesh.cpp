// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/core/triangle_mesh.h"

#include <fmt/format.h>

#include "pointsurf/core/error.h"

namespace pointsurf {

void TriangleMesh::validate() const {
  const std::size_t n = vertices.size();
  if (!vertices.normals.empty() && vertices.normals.size() != n)
    throw InputError(fmt::format("mesh: {} vertex normals for {} vertices", vertices.normals.size(), n));
  if (!vertices.colors.empty() && vertices.colors.size() != n)
    throw InputError(fmt::format("mesh: {} vertex colours for {} vertices", vertices.colors.size(), n));
  for (const ScalarField& f : vertices.fields)
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

}  // namespace pointsurf
