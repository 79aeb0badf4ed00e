// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Feature-aware denoising that moves points along their normals: bilateral filtering, and
// trilateral filtering with normal correction, which keeps sharp creases.
#include <cstddef>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/core/results.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf {

struct BilateralParams {
  Length radius = Length::spacings(3.0);  // neighbourhood radius, cloud units or mean spacings, > 0
  int max_neighbours = 48;              // at most this many nearest points within the radius, >= 3
  Length height_sigma = Length::spacings(1.0);  // sigma of the range weight on the offset along
                                                // the normal, cloud units or mean spacings, > 0
  int iterations = 2;                   // passes, >= 1
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<BilateralParams>& fields();
  /// Throws UsageError naming the first value out of range: the one place the values are
  /// checked (the algorithm and the pipeline call it before any work).
  void validate() const;
};

struct TrilateralParams {
  BilateralParams position = {};        // the position pass, as in smooth_bilateral
  double sharpness_angle_deg = 20.0;    // sigma of the weight on the angle between normals,
                                        // degrees, in (0, 90]: neighbours across a sharper
                                        // crease hardly count
  int normal_iterations = 2;            // passes of the normal filter before the positions, >= 1
  double height_sigma_scale = 1.5;      // the position pass's range sigma is this times the
                                        // height sigma, > 0: the angle weight, not the range
                                        // weight, keeps the other face out, so the range can be
                                        // wider and average more noise
  bool use_feature_field = true;        // when the cloud has a field "feature" (1 edge, 2
                                        // corner), feature points do not lend their normals
                                        // to others (their PCA normals mix two faces)
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<TrilateralParams>& fields();
  /// Throws UsageError naming the first value out of range: the one place the values are
  /// checked (the algorithm and the pipeline call it before any work).
  void validate() const;
};

/// What a smoothing pass did. Displacements are between input and output positions.
struct SmoothResult {
  std::size_t moved = 0;            // points that moved (displacement > 0)
  double mean_displacement = 0.0;   // cloud units
  double rms_displacement = 0.0;    // cloud units
  double max_displacement = 0.0;    // cloud units
  double radius_used = 0.0;         // neighbourhood radius, cloud units
  double height_sigma_used = 0.0;   // cloud units
  std::size_t normals_changed = 0;  // trilateral: normals turned by more than 1 degree
  double mean_normal_change_deg = 0.0;  // trilateral: mean angle between input and corrected normals

  /// The reported members (core/results.h): the moves; with `normals`, the trilateral pass's
  /// normal changes after them.
  static const ResultTable<SmoothResult>& results(bool normals = false);
};

/// Bilateral point filtering (Fleishman et al. 2003, "Bilateral mesh denoising", applied to
/// points as in Jones et al. 2003): each point moves along its own unit normal n_i by
///   d_i = sum_j w_s(|p_j - p_i|) w_h(h_ij) h_ij / sum_j w_s w_h,   h_ij = <n_i, p_j - p_i>,
/// with Gaussians w_s (sigma = radius / 2) and w_h (sigma = height_sigma) over the neighbours
/// within `radius` (the point included, at most max_neighbours). Repeated `iterations` times
/// with the neighbourhoods of the input positions. Needs `cloud.normals` (N×3, any sign);
/// writes `cloud.positions`. Noise along the normal shrinks; creases get rounded because the
/// PCA normals near them are blended. Georeferenced coordinates keep precision (only offsets
/// p_j - p_i are used). Parallel (oneTBB) in the tree's spatial order; `tree` (optional) must
/// be built over the input positions. Throws UsageError on missing normals or bad parameters;
/// CancelledError when `progress` returns false (the cloud is then unchanged).
SmoothResult smooth_bilateral(PointCloud& cloud, const BilateralParams& params = {}, const KdTree* tree = nullptr,
                              const ProgressCallback& progress = {});

/// Trilateral filtering: first the normal field is filtered, then the positions are moved
/// along it. Normal pass (normal_iterations times), a bilateral filter in normal space (Jones
/// et al. 2004; Zheng et al. 2011 on meshes): n_i becomes the normalised sum of its neighbours'
/// normals (sign-aligned) weighted by w_s(|p_j - p_i|) and w_a(angle(n_i, n_j)), so normals
/// average within a face and not across a crease. Position pass: as smooth_bilateral along the
/// filtered normals, each neighbour also weighted by w_a(angle(n_i, n_j)) -- the third weight of
/// Choudhury & Tumblin's trilateral filter -- so the far side of a crease does not pull points
/// off their face, with the range sigma widened by height_sigma_scale (the angle weight does
/// the range weight's job of keeping faces apart). w_a is a Gaussian of sigma
/// sharpness_angle_deg. Measured on noisy libcgal-demo CAD parts (bench/clean/run_clean_bench.sh):
/// lower RMS to the true surface than smooth_bilateral both within 2 spacings of the creases and
/// on the rest. Writes `cloud.positions` and `cloud.normals` (filtered, unit, same side as the
/// input). Threading, precision and errors as smooth_bilateral (also UsageError for
/// sharpness_angle_deg outside (0, 90], normal_iterations < 1 or height_sigma_scale <= 0).
/// Cost about twice a bilateral pass.
SmoothResult smooth_trilateral(PointCloud& cloud, const TrilateralParams& params = {}, const KdTree* tree = nullptr,
                               const ProgressCallback& progress = {});

}  // namespace pointsurf
