// SPDX-License-Identifier: GPL-3.0-or-later
#include <cmath>
#include <cstddef>
#include <vector>

#include <fmt/format.h>

#include "pointsurf/core/error.h"
#include "pointsurf/reconstruct/mesh_cleanup.h"
#include "reconstruct/detail/face_edges.h"

namespace pointsurf {

const FieldTable<SmallComponentParams>& SmallComponentParams::fields() {
  static const FieldTable<SmallComponentParams> table = [] {
    FieldTable<SmallComponentParams> t;
    t.number("min_component_share", &SmallComponentParams::min_share, "Remove components with fewer faces than this share of all; 0: keep all")
        .unit("share of faces")
        .range(0, 1);
    return t;
  }();
  return table;
}

void SmallComponentParams::validate() const {
  if (!(min_share >= 0.0 && min_share <= 1.0))
    throw UsageError(fmt::format("remove_small_components: min_share must be in [0, 1], got {}", min_share));
  fields().validate(*this, "remove_small_components");
}

SmallComponentsResult remove_small_components(TriangleMesh& mesh, const SmallComponentParams& params) {
  params.validate();
  mesh.validate();
  SmallComponentsResult result;
  const std::size_t f = mesh.triangles.size();
  const double limit = params.min_share * static_cast<double>(f);
  result.min_faces = static_cast<std::size_t>(std::ceil(limit));
  if (f == 0) return result;
  // Components as analyze_topology counts them: triangles joined by every shared edge,
  // non-manifold ones included.
  const std::vector<detail::FaceEdge> edges = detail::sorted_face_edges(mesh);
  detail::FaceSets sets(f);
  detail::for_each_edge(edges, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin + 1; k < end; ++k) sets.unite(edges[begin].face, edges[k].face);
  });
  std::vector<std::size_t> size(f, 0);
  for (std::size_t t = 0; t < f; ++t) ++size[std::size_t(sets.find(static_cast<int>(t)))];
  for (std::size_t t = 0; t < f; ++t)
    if (size[t] > 0) {
      ++result.components;
      if (static_cast<double>(size[t]) < limit) ++result.components_removed;
    }
  if (result.components_removed == 0) return result;
  std::vector<std::size_t> kept;
  kept.reserve(f);
  for (std::size_t t = 0; t < f; ++t)
    if (!(static_cast<double>(size[std::size_t(sets.find(static_cast<int>(t)))]) < limit)) kept.push_back(t);
  result.faces_removed = f - kept.size();
  for (std::size_t i = 0; i < kept.size(); ++i) mesh.triangles[i] = mesh.triangles[kept[i]];
  mesh.triangles.resize(kept.size());
  for (ScalarField& field : mesh.face_fields) {
    for (std::size_t i = 0; i < kept.size(); ++i) field.values[i] = field.values[kept[i]];
    field.values.resize(kept.size());
  }
  return result;
}

const ResultTable<SmallComponentsResult>& SmallComponentsResult::results() {
  static const ResultTable<SmallComponentsResult> table = [] {
    ResultTable<SmallComponentsResult> t;
    t.count("components_removed", &SmallComponentsResult::components_removed, "Small components removed (min_component_share)").as_count();
    t.count("faces_removed", &SmallComponentsResult::faces_removed, "Faces they had").as_count();
    return t;
  }();
  return table;
}

}  // namespace pointsurf
