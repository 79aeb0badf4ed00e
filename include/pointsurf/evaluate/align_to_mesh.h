// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Best-fit alignment of a scan to a reference mesh before it is measured, as inspection software
// does (Geomagic Control's and PolyWorks' "best fit"): point-to-plane ICP from where the scan
// lies, against area-uniform samples of the mesh with their triangles' normals, so a coarse CAD
// mesh (a box of 12 triangles) is as good a target as a dense one.
#include <cstddef>
#include <cstdint>
#include <span>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/length.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/core/triangle_mesh.h"
#include "pointsurf/register/icp.h"
#include "pointsurf/register/result.h"

namespace pointsurf {

struct MeshAlignParams {
  std::size_t samples = 100000;        // points sampled on the mesh as ICP's target; 0: the mesh's
                                       // vertices (with area-weighted vertex normals)
  std::uint64_t seed = 3;              // seed of the sampling
  Length max_distance = Length::spacings(10.0);  // pairs farther apart are ignored, > 0; in
                                       // spacings: of the points' mean spacing, wider than ICP's
                                       // default, since a best fit starts from wherever the scan
                                       // was placed
  std::size_t max_iterations = IcpParams{}.max_iterations;
  double relative_rmse = IcpParams{}.relative_rmse;  // converged when the RMSE changes less
  /// Key, unit, range and doc of each field (core/fields.h). The keys are the evaluate stage's
  /// (align_max_distance, align_iterations); samples and seed are internal there (the stage
  /// sets them from its own samples and seed).
  static const FieldTable<MeshAlignParams>& fields();
  /// Throws UsageError naming the first value out of range.
  void validate() const;
};

/// The rigid transform that moves `points` (N, cloud units) onto `mesh` (point-to-plane ICP, no
/// normal-angle check: a scan's normals may face either way), with fitness and inlier RMSE at the
/// max distance used. Not converging is an answer (converged = false); a mesh without area or
/// fewer than 6 points give converged = false too. Throws UsageError for bad parameters,
/// InputError for a mesh that cannot be measured. Parallel; thread-safe.
RegistrationResult align_to_mesh(std::span<const Vector3d> points, const TriangleMesh& mesh, const MeshAlignParams& params = {},
                                 const ProgressCallback& progress = {});
/// The reported members of align_to_mesh's answer (core/results.h): RegistrationResult told as
/// a best fit of a reference onto a mesh, the transform with its rotation and translation, then
/// how well it fits and how it ended.
const ResultTable<RegistrationResult>& mesh_alignment_results();

}  // namespace pointsurf
