// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Sharp-feature points: candidates by surface variation, screened by fitting planes to the
// clusters of a candidate's neighbours grouped by normal angle.
#include <cstddef>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/core/results.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf {

/// Values of the uint8 field "feature" written by detect_feature_points.
enum class FeatureLabel : unsigned char { None = 0, Edge = 1, Corner = 2 };

/// Which normals the screening clusters the neighbours by.
enum class FeatureNormals {
  // Per point, the PCA normal of the flattest k-neighbourhood that contains the point (its own
  // or one of its neighbours', "shifted" neighbourhoods). Near an edge this is the normal of
  // the face the point lies on, where the point's own PCA normal blends both faces. Computed
  // here; the cloud's normals are not used.
  Robust,
  // The cloud's normals as given (oriented or not). Blended PCA normals near edges form
  // intermediate clusters, so this loses recall unless the normals are sharp.
  Input,
};

struct FeatureParams {
  int k = 30;                        // neighbours per point (variation, normals, screening), >= 6
  double variation_threshold = 0.0;  // candidates: surface variation l0/(l0+l1+l2) above this,
                                     // in (0, 1/3); 0: derived from the data (see below)
  double cluster_angle_deg = 20.0;   // normal-angle clustering threshold, degrees, in (0, 90)
  double min_turn_deg = 28.0;        // smallest crease kept: two planes must turn by this, degrees,
                                     // in (0, 90); also sets the candidate floor (below)
  Length plane_distance = Length::spacings(1.0);  // point-to-plane distance of a cluster's plane, > 0
  int min_cluster_points = 5;        // fewest neighbours a cluster needs to give a plane, in [3, k]
  FeatureNormals normals = FeatureNormals::Robust;
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<FeatureParams>& fields();
  /// Throws UsageError naming the first value out of range: the one place the values are
  /// checked (the algorithm and the pipeline call it before any work).
  void validate() const;
};

struct FeatureResult {
  std::size_t candidates = 0;        // points whose variation exceeded the threshold
  std::size_t edges = 0;             // points labelled Edge (one crease through p, see below)
  std::size_t corners = 0;           // points labelled Corner (three planes or more, see below)
  double variation_threshold_used = 0.0;  // the candidate threshold actually used
  double dd_used = 0.0;              // the plane distance actually used, cloud units
  double mean_spacing = 0.0;         // mean spacing of the cloud, cloud units

  /// The reported members (core/results.h).
  static const ResultTable<FeatureResult>& results();
};

/// Labels sharp-feature points (SPEC C7, after the seed paper's feature-point screening):
///  1. Candidates: points whose surface variation s = l0 / (l0 + l1 + l2) of the k-neighbourhood
///     covariance (eigenvalues l0 <= l1 <= l2, Pauly et al. 2002) exceeds the threshold. The
///     default threshold is max(floor, 4 * median(s)), capped at 0.3: on clouds that are mostly
///     smooth the median is the variation that noise and gentle curvature give ordinary points,
///     and four times it is above them. The floor is half the variation a point on a straight
///     crease of min_turn_deg has (0.0042 at 28 degrees; a neighbourhood folded along its
///     diameter): it keeps clean clouds (median near 0) from making every point a candidate
///     without losing the shallow creases. (The floor was 0.01 before: a 30-degree crease has
///     0.0096, so obtuse creases of 150 degrees and more were never candidates.) The
///     screening, not this step, sets the precision. Variation is scale-free: so is the default.
///  2. Screening of each candidate p: its k neighbours (p included) are clustered by normal angle
///     (unoriented: n and -n are the same direction; leader clustering nearest-first, then one
///     reassignment to the nearest cluster mean); each cluster of at least min_cluster_points
///     points gets a least-squares plane (PCA of the cluster's positions); planes within dn of a
///     larger cluster's plane are dropped as duplicates. Of the remaining planes within dd of p,
///     a pair counts when the planes turn by at least min_turn_deg and p lies within dd of their
///     intersection line (near a shallow crease of turn t the plane test alone labels a band
///     1 / sin(t) times as wide as at a right angle). p is an Edge with one such pair (or two
///     planes), a Corner with three or more planes near and two or more pairs.
/// Writes the field "feature" (ScalarType::UInt8, N values, FeatureLabel) into `cloud`, replacing
/// one of that name; positions and normals are not changed. Needs `cloud.normals` (N×3, any sign)
/// only for FeatureNormals::Input.
/// `tree`: reused when given (it must be built over `cloud.positions`), else one is built.
/// Parallel (oneTBB) in the tree's spatial order; the cloud must not be modified concurrently.
/// Fits use offsets from the query point, so georeferenced coordinates keep their precision.
/// Throws UsageError for bad parameters (naming the parameter, its value and the range) or fewer
/// than k + 1 points; CancelledError when `progress` returns false (the cloud is then unchanged).
FeatureResult detect_feature_points(PointCloud& cloud, const FeatureParams& params = {}, const KdTree* tree = nullptr,
                                    const ProgressCallback& progress = {});

}  // namespace pointsurf
