// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Feature-aware denoising that moves points along their normals: bilateral filtering, and
// trilateral filtering with normal correction, which keeps sharp creases.
#include <cstddef>

#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf {

struct BilateralParams {
  double radius = 0.0;                  // neighbourhood radius, cloud units, >= 0;
                                        // 0: radius_in_spacings * mean spacing
  double radius_in_spacings = 3.0;      // used when radius == 0, > 0
  int max_neighbours = 48;              // at most this many nearest points within the radius, >= 3
  double height_sigma = 0.0;            // sigma of the range weight on the offset along the
                                        // normal, cloud units, >= 0; 0: height_sigma_in_spacings * spacing
  double height_sigma_in_spacings = 1.0;// used when height_sigma == 0, > 0
  int iterations = 2;                   // passes, >= 1
  /// Throws UsageError naming the first value out of range: the one place the values are
  /// checked (the algorithm and the pipeline call it before any work).
  void validate() const;
};

struct TrilateralParams {
  BilateralParams position = {};        // the position pass, as in smooth_bilateral
  double sharpness_angle_deg = 20.0;    // sigma of the weight on the angle between normals,
                                        // degrees, in (0, 90]: neighbours across a sharper
                                        // crease hardly count
  int normal_iterations = 2;            // passes of normal correction before the positions, >= 1
  bool use_feature_field = true;        // when the cloud has a field "feature" (1 edge, 2
                                        // corner), feature points do not lend their normals
                                        // to others (their PCA normals mix two faces)
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

/// Trilateral filtering with normal correction: first the normal field is corrected, then the
/// positions are moved along it. Normal pass (normal_iterations times), a robust local plane
/// fit in the spirit of Fleishman et al. 2005 (robust moving least squares) and Jones et al.
/// 2004: the candidates are the point's own normal and those of about 16 neighbours spread over
/// 2.5 radii; each candidate c is scored by the support of the plane through p_i with normal c,
/// sum_j w_s(|p_j - p_i|) w_h(<c, p_j - p_i>); the best is refined by weighted PCA of the
/// neighbours with the same weights (two reweighting steps). Near a crease the blended PCA
/// normals lose to the normal of the point's own face, so the corrected field is piecewise
/// smooth with sharp jumps. Position pass: as smooth_bilateral along the corrected normals,
/// each neighbour also weighted by w_a(angle(n_i, n_j)), a Gaussian of sigma
/// sharpness_angle_deg -- the third weight of Choudhury & Tumblin's trilateral filter -- so the
/// far side of a crease does not pull points off their face. Writes `cloud.positions` and
/// `cloud.normals` (corrected, unit, same side as the input). Threading, precision and errors
/// as smooth_bilateral (also UsageError for sharpness_angle_deg outside (0, 90] or
/// normal_iterations < 1). Cost about 5 times a bilateral pass.
SmoothResult smooth_trilateral(PointCloud& cloud, const TrilateralParams& params = {}, const KdTree* tree = nullptr,
                               const ProgressCallback& progress = {});

}  // namespace pointsurf
