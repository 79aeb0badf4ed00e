// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Flat regions of a triangle mesh (SPEC C10: "the normal angle between adjacent triangles also
// separates flat regions"): a region label per face, for segmenting a reconstructed CAD part
// into its faces or a scan into roughly planar patches.
#include <cstddef>
#include <vector>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/core/results.h"
#include "pointsurf/core/triangle_mesh.h"

namespace pointsurf {

struct FlatRegionParams {
  double max_normal_angle_deg = 15.0;  // two faces sharing a manifold edge join when their
                                       // normals differ by at most this, (0, 180]. 15: above
                                       // the few degrees that scan noise and sampling put
                                       // between neighbouring triangles of a flat part, below
                                       // the 30 degrees and more of the edges of machined parts
  double max_seed_angle_deg = 30.0;    // and when the face's normal is within this of its
                                       // region's seed face normal, (0, 180]; 180: off. Without
                                       // it a slowly curving surface chains into one region (a
                                       // sphere would be one); with 30 each region is at most a
                                       // cap of half-angle 30 degrees, so a sphere gets at least
                                       // 1 / ((1 - cos 30) / 2) = 15 regions. The seed normal,
                                       // unlike a running mean, makes a region independent of
                                       // the order in which it grows
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<FlatRegionParams>& fields();
  /// Throws UsageError naming the first value outside the ranges above.
  void validate() const;
};

struct FlatRegionResult {
  std::vector<int> region;  // F: region of each face, 0 .. regions - 1, numbered in order of
                            // each region's smallest face index
  std::size_t regions = 0;  // number of regions (fewer is flatter); small regions are kept
  std::size_t largest_region = 0;  // faces of the largest region

  /// The reported members (core/results.h).
  static const ResultTable<FlatRegionResult>& results();
};

/// Labels the flat regions of `mesh`: regions grow across edges that exactly two faces share
/// (boundary and non-manifold edges separate), between faces whose normals differ by at most
/// `max_normal_angle_deg` and whose normal is within `max_seed_angle_deg` of the region's seed.
/// Seeds are taken flattest first (smallest largest angle to an edge neighbour, then largest
/// area, then smallest centroid in x, y, z), so the partition depends on the geometry only:
/// permuting the faces, or shifting the mesh, permutes the labels and nothing else; the labels
/// are then renumbered by smallest face index, so they are deterministic. A region is the
/// edge-connected set of still unlabelled faces within the seed's cone that the seed reaches,
/// which does not depend on the growing order. Faces of zero area (no normal), and faces whose
/// neighbour is inconsistently oriented (normals opposite), stay apart.
///
/// Normals come from edge vectors (differences of vertex positions), so coordinates far from
/// the origin (1e6 m) lose nothing. O(F log F) time (parallel sorts), O(F) memory. Throws
/// UsageError for a parameter out of range and InputError for an invalid mesh (see
/// TriangleMesh::validate). Thread-safe (reads `mesh` only). `progress` hears the finished
/// fraction (the growing by faces labelled); returning false throws CancelledError.
FlatRegionResult label_flat_regions(const TriangleMesh& mesh, const FlatRegionParams& params = {}, const ProgressCallback& progress = {});

}  // namespace pointsurf
