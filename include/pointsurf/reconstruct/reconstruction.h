// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// What every surface reconstruction returns: the mesh and its topology, so that each method
// reports holes, manifoldness and components the same way.
#include <cstddef>

#include "pointsurf/core/mesh_topology.h"
#include "pointsurf/core/triangle_mesh.h"

namespace pointsurf {

struct ReconstructionResult {
  TriangleMesh mesh;           // interpolating methods: the input points (with their normals,
                               // colours and fields) as vertices; triangles counter-clockwise
                               // seen from the side the normals point to
  MeshTopology topology;       // analyze_topology(mesh): holes, non-manifold edges, components
  std::size_t unused_points = 0;  // input points that no triangle uses (smaller is better)
  double mean_spacing = 0.0;   // the cloud's mean spacing, from which the defaults were derived
};

}  // namespace pointsurf
