// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Least-squares fit of one tensor-product B-spline surface to a patch of points, refined until
// a deviation tolerance is met (SPEC C14, issue 29 items 1, 2 and 7).
//
//   BSplineFitParams params;            // bicubic; tolerance 0: from the noise estimate
//   params.tolerance = 0.002;           // cloud units (max |deviation|)
//   const BSplineFitResult r = fit_bspline_surface(points, params);
//   // r.tolerance_met, r.max_deviation, r.rounds; r.surface.point(u, v) anywhere on [0, 1]^2
//
// The patch must be a height field over its least-squares plane (no folds); a quadric base
// surface for patches that fold over their plane is not implemented yet.
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/core/results.h"
#include "pointsurf/surface/bspline_surface.h"

namespace pointsurf {

struct BSplineFitParams {
  int degree = 3;                     // [1, 7]: degree in u and in v
  double tolerance = 0.0;             // >= 0, cloud units: the largest |deviation| wanted; 0:
                                      // max(6, 1.5 sqrt(2 ln N)) x the noise estimate
                                      // (BSplineFitResult::noise; the largest of N Gaussian
                                      // deviations is about sqrt(2 ln N) sigma), at least 0.001 x
                                      // the mean spacing
  double smoothing = 1e-9;            // >= 0: weight of the thin-plate energy (see below), the
                                      // same for any size and point count of the patch; 0: none
                                      // (a floor of 1e-12 is used where a control point has no
                                      // point under it, and reported). It flattens the surface
                                      // near the patch's border by about sqrt(smoothing) x
                                      // curvature x area: 1e-9 keeps that near 3e-5 x curvature x
                                      // area while the system stays well posed where points are
                                      // sparse
  double points_per_span = 100.0;     // > 0: the first control net has about N / points_per_span
                                      // knot-span cells, split between u and v by the patch's
                                      // aspect ratio
  int max_rounds = 8;                 // >= 0: knot-insertion rounds at most
  int max_control_points = 10000;     // >= (degree + 1)^2: the net never grows beyond this,
                                      // nor beyond the number of points
  int parameter_corrections = 2;      // >= 0: re-projections (and refits) of the points per round
  double max_tilt_deg = 80.0;         // (0, 90], degrees: a point whose local normal (PCA of its
                                      // 12 nearest neighbours) is further than this from the base
                                      // plane's normal is on a fold; more than 2 % such points and
                                      // the fit refuses the patch

  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<BSplineFitParams>& fields();
  /// Throws UsageError naming the first value out of range.
  void validate() const;
};

/// Why the refinement stopped.
enum class BSplineFitStop { ToleranceMet, RoundLimit, ControlPointLimit };
/// "tolerance met", "round limit", "control point limit".
const char* bspline_fit_stop_name(BSplineFitStop stop) noexcept;

/// The base plane of the parameterization: a point x has (u, v) = (((x - origin) . axis_u -
/// a_min) / (a_max - a_min), ((x - origin) . axis_v - b_min) / (b_max - b_min)) before the
/// parameter correction.
struct BSplineFitFrame {
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // the centroid of the points
  Eigen::Vector3d axis_u = Eigen::Vector3d::UnitX();  // largest principal direction
  Eigen::Vector3d axis_v = Eigen::Vector3d::UnitY();  // normal x axis_u
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // smallest principal direction; positive
                                                      // deviations lie on its side
  double a_min = 0.0, a_max = 1.0, b_min = 0.0, b_max = 1.0;  // bounding rectangle, cloud units
};

struct BSplineFitResult {
  BSplineSurface surface;                    // domain [0, 1]^2, origin = frame.origin
  BSplineFitFrame frame;
  std::vector<Eigen::Vector2d> parameters;   // N: (u, v) of each point's foot on the surface
  std::vector<double> deviations;            // N, cloud units: signed distance of each point to
                                             // its foot, positive on the side of frame.normal
  double max_deviation = 0.0;                // max |deviation|, cloud units (lower is better)
  double rms_deviation = 0.0;                // cloud units (lower is better)
  double tolerance = 0.0;                    // the tolerance used, cloud units
  bool tolerance_met = false;                // max_deviation <= tolerance
  BSplineFitStop stop = BSplineFitStop::ToleranceMet;
  std::string stop_reason;                   // bspline_fit_stop_name(stop)
  int rounds = 0;                            // knot-insertion rounds done
  std::size_t control_points = 0;            // of the final net
  double smoothing = 0.0;                    // the smoothing weight used
  double noise = 0.0;                        // estimate, cloud units: square root of the median
                                             // smallest eigenvalue of the 12-neighbour covariances
  double spacing = 0.0;                      // mean spacing, cloud units

  /// The reported members (core/results.h).
  static const ResultTable<BSplineFitResult>& results();
};

/// Fits a tensor-product B-spline surface of degree params.degree to `points` (N x 3, cloud
/// units, any offset: the fit works relative to the centroid, so 1e6 m coordinates keep their
/// precision) and refines it until the largest |deviation| is at most the tolerance.
///
/// Parameterization: the points are projected onto their least-squares plane (PCA about the
/// centroid) and (u, v) are the coordinates in it scaled to [0, 1] over the bounding rectangle,
/// so the surface covers the whole patch. A patch that folds over that plane (a closed
/// cylinder, a hemisphere's rim) is refused (see max_tilt_deg).
/// Fit: the three coordinates of the control points minimize
///   sum_k |S(u_k, v_k) - p_k|^2 + N * smoothing * A * integral (S_aa^2 + 2 S_ab^2 + S_bb^2) da db
/// where (a, b) are the plane's coordinates in cloud units over the rectangle and A its area
/// (the thin-plate energy, exact by Gauss quadrature per knot span; the scaling makes the
/// smoothing independent of the patch's size and point count). Sparse normal equations,
/// assembled in parallel, solved by sparse LDL^T.
/// Refinement (Weiss et al. 2002 style): after each fit the parameters are corrected by
/// projecting each point onto the surface (Newton, BSplineSurface::closest) and the surface is
/// refitted, params.parameter_corrections times; the signed deviations are then measured. While
/// the largest exceeds the tolerance, knots are inserted at the midpoints of the u- and v-spans
/// holding the points whose |deviation| is above max(tolerance, half the largest), up to
/// max_rounds rounds and min(max_control_points, N) control points; the result says which limit
/// stopped it. Never loops without bound.
///
/// Progress: monotone fractions ending at 1; a callback returning false throws CancelledError.
/// Throws UsageError for parameters out of range; InputError for no points, a non-finite
/// point, fewer than (degree + 1)^2 points, points on a line, and a folded patch.
/// Thread-safe (parallel inside with oneTBB).
BSplineFitResult fit_bspline_surface(std::span<const Eigen::Vector3d> points, const BSplineFitParams& params = {},
                                     const ProgressCallback& progress = {});

}  // namespace pointsurf
