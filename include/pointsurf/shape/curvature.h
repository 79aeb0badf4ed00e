// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Local shape: principal curvatures, mean and Gaussian curvature by a jet (Monge form) fit,
// surface variation, and the HK surface type of every point.
//
// Sign convention (the whole project): curvature is positive where the surface bends away from
// the outward normal. A sphere of radius r with outward normals has k1 = k2 = H = +1/r and
// K = 1/r^2; H > 0, K > 0 is a peak.
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/progress.h"
#include "pointsurf/core/results.h"
#include "pointsurf/normals/normals.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf {

/// Surface type from the signs of H and K (Besl and Jain 1988), in the project's sign
/// convention. The integer codes are the values of the "surface_type" field.
enum class SurfaceType : std::uint8_t {
  Undefined = 0,     // no curvature (degenerate neighbourhood or missing normal)
  Peak = 1,          // H > 0, K > 0: bends away from the normal in every direction (convex cap)
  Pit = 2,           // H < 0, K > 0: bends towards the normal in every direction (concave cup)
  Ridge = 3,         // H > 0, K = 0: convex in one direction, straight in the other (outside of a cylinder)
  Valley = 4,        // H < 0, K = 0: concave in one direction, straight in the other (inside of a cylinder)
  SaddleRidge = 5,   // H > 0, K < 0: saddle, mostly convex
  SaddleValley = 6,  // H < 0, K < 0: saddle, mostly concave
  Flat = 7,          // H = 0, K = 0: plane
  Minimal = 8,       // H = 0, K < 0: symmetric saddle (minimal surface)
};
inline constexpr int kSurfaceTypeCount = 9;

/// Name of a surface type in lower case ("peak", "saddle_ridge", ...).
const char* surface_type_name(SurfaceType type) noexcept;

/// Classifies one point from its mean curvature `H` (1/length) and Gaussian curvature `K`
/// (1/length^2): H counts as zero when |H| <= h_zero and K when |K| <= k_zero (both >= 0).
/// K > 0 with H = 0 cannot happen on a surface (H^2 >= K); it is reported as Flat. Non-finite
/// H or K give Undefined. Pure function; thread-safe.
SurfaceType classify_surface_type(double H, double K, double h_zero, double k_zero) noexcept;

struct CurvatureParams {
  NeighborhoodKind neighborhood = NeighborhoodKind::Knn;
  int degree = 2;                   // jet degree, 2 or 3
  int k = 0;                        // neighbours per point (Knn, Hybrid), at least 6 (degree 2) or 10
                                    // (degree 3); 0: Knn chooses it from the noise (choose_curvature_scale),
                                    // starting at 24 for degree 2, 40 for degree 3; Hybrid takes 24 / 40
  Length radius = Length::spacings(6.0);  // (Radius, Hybrid) cloud units or mean spacings, > 0
  double scale_in_noise = 8.0;      // k = 0 (Knn): the neighbourhood radius must reach this many times
                                    // the noise (the jet fit's residual), > 0
  int max_k = 1536;                 // k = 0 (Knn): the most neighbours the choice may reach, >= the start
  double cylinder = 0.0;            // fit only the neighbours within this fraction of the neighbourhood radius
                                    // of the normal axis, in (0, 1]; 0: 1 (all), or the chosen scale's
                                    // (CurvatureScale::cylinder) when k = 0 chose it
  double zero_curvature = 0.0;      // 1/cloud units: a principal curvature, or H, of magnitude at most
                                    // this counts as zero in the surface type; 0: derived from the
                                    // data (see estimate_curvature)
  double zero_in_noise = 3.0;       // derived zero_curvature = zero_in_noise * median over points of
                                    // the standard error of the fitted curvature, > 0
  bool keep_directions = false;     // fill CurvatureResult::d1, d2, normals
  bool update_normals = false;      // replace cloud.normals by the jet (Monge) normals, same side
  /// The neighbourhood fields as the one Neighborhood type (spatial/neighborhood.h), k resolved
  /// (0: 24 for degree 2, 40 for degree 3).
  Neighborhood neighborhood_settings() const noexcept {
    return {neighborhood, k == 0 ? (degree == 2 ? 24 : 40) : k, radius};
  }
  /// Key, unit, range and doc of each field (core/fields.h).
  static const FieldTable<CurvatureParams>& fields();
  /// Throws UsageError naming the first value out of range: the one place the values are
  /// checked (the algorithm and the pipeline call it before any work).
  void validate() const;
};

struct CurvatureResult {
  std::array<std::size_t, kSurfaceTypeCount> type_counts{};  // points per SurfaceType code
  std::size_t degenerate = 0;          // points with no curvature: zero normal, too few neighbours for
                                       // the jet or a singular fit; fields 0, type Undefined (smaller is better)
  double scale_in_noise = 8.0;      // k = 0 (Knn): the neighbourhood radius must reach this many times
                                    // the noise (the jet fit's residual), > 0
  int max_k = 1536;                 // k = 0 (Knn): the most neighbours the choice may reach, >= the start
  double cylinder = 0.0;            // fit only the neighbours within this fraction of the neighbourhood radius
                                    // of the normal axis, in (0, 1]; 0: 1 (all), or the chosen scale's
                                    // (CurvatureScale::cylinder) when k = 0 chose it
  double zero_curvature = 0.0;         // zero threshold used for the surface type, 1/cloud units
  double radius_used = 0.0;            // search radius used (Radius, Hybrid), cloud units
  double median_residual = 0.0;        // median over points of the RMS distance of the neighbours to the
                                       // fitted jet, cloud units (smaller: the jet fits better)
  int k_used = 0;                      // neighbours per point (Knn, Hybrid)
  bool scale_chosen = false;           // k came from choose_curvature_scale (Knn, k = 0); the next two are set
  double noise = 0.0;                  // the noise the scale followed, cloud units (see CurvatureScale)
  bool scale_capped = false;           // max_k or the cloud's size stopped the choice short of scale_in_noise
  std::vector<Vector3d> d1, d2;        // N unit principal directions of k1 and k2 (empty unless keep_directions;
                                       // zero where degenerate)
  std::vector<Vector3d> normals;       // N unit jet normals on the side of the input normals (same condition)

  /// The reported members (core/results.h): the degenerate points and the points of each
  /// surface type, counts.
  static const ResultTable<CurvatureResult>& results();
};

/// The neighbourhood size the default curvature (Knn, k = 0) uses.
struct CurvatureScale {
  int k = 0;               // neighbours per point chosen
  double noise = 0.0;      // median over the sampled points of the jet fit's RMS residual at k (unbiased:
                           // divided by k - coefficients), cloud units: the noise once the fit is wide enough
  double radius = 0.0;     // median neighbourhood radius at k, cloud units (larger than scale_in_noise * noise
                           // unless capped)
  double cylinder = 1.0;   // the fit cylinder that goes with it (CurvatureParams::cylinder): 0.8 when k grew,
                           // 1 (the whole ball) when the start sufficed
  bool capped = false;     // the radius never reached scale_in_noise * noise: k is max_k or the largest power
                           // of two times the start that the cloud holds; the curvature may be noise-dominated

  /// The reported members (core/results.h).
  static const ResultTable<CurvatureScale>& results();
};

/// Chooses the jet neighbourhood from the noise. Fitting a jet over a neighbourhood narrower than
/// a few noise amplitudes fits the noise: on a noisy sphere the curvature comes out as noise about
/// zero and every point flat. Starting at k = 24 (degree 2) or 40 (degree 3), k doubles
///  1. until the median neighbourhood radius is at least `scale_in_noise` times the median fit
///     residual (the noise floor: the residual is the noise once the neighbourhood is wider than it);
///  2. then on while fewer than 90 % of the samples have a principal curvature beyond
///     `zero_in_noise` of its standard errors, unless the median residual rises 20 % above the
///     floor's (the jet no longer fits: planes meeting, clean curved data) or max_k comes first,
///     which keep the floor's k (a flat surface stays flat at any k).
/// A clean scan keeps the start (its curvature stands out, or widening raises the residual);
/// at most `max_k` (and the cloud's size). The curvature's standard error
/// then falls as noise / radius^2 / sqrt(k): at 8 times the noise and k ~ 800 it is about 0.1 / r on
/// a sphere of radius r = 25 noise amplitudes. A ball around a noisy point truncates the noise at its rim, where
/// only points near the ball's equator are inside: that pulls the rim towards the tangent plane
/// and the curvature towards zero (measured: H 11 % low on sphere_20k.xyz at k = 768). So when k
/// grew, the fit keeps the cylinder of radius 0.8 h about the normal axis, whose height inside
/// the ball (+-0.6 h, about 5 noise amplitudes) holds the noise whole. Medians over up to 1000 points spread evenly in the
/// tree's spatial order (deterministic). `tree` is built over cloud.positions; normals are not needed.
/// Parallel (oneTBB). Throws UsageError for bad parameters or fewer points than the jet needs.
CurvatureScale choose_curvature_scale(const PointCloud& cloud, const CurvatureParams& params, const KdTree& tree);

/// Estimates curvature by fitting a jet (a polynomial height function of degree 2 or 3, the
/// Monge form) to each point's neighbourhood in a local frame, after Cazals and Pouget,
/// "Estimating differential quantities using polynomial fitting of osculating jets" (2005).
/// For each point p: the frame is centred at p (georeferenced clouds keep precision) with its
/// z axis the PCA normal of the neighbourhood, turned to the side of p's input normal; the jet
/// z = f(x, y) is fitted by unweighted least squares (coordinates scaled by the neighbourhood
/// radius); the first and second fundamental forms of the graph at the origin give the shape
/// operator, whose eigenvalues, negated so that bending away from the normal is positive,
/// are k1 >= k2 (1/cloud units), with H = (k1 + k2) / 2 and K = k1 k2.
///
/// Writes float32 fields "k1", "k2", "mean", "gauss", "variation" (l0 / (l0 + l1 + l2) of the
/// neighbourhood covariance, in [0, 1/3]) and the uint8 field "surface_type" (SurfaceType
/// codes), each of N values. The surface type uses h_zero = z and k_zero = z * max(|k1|, |k2|, z)
/// with z = params.zero_curvature, or, when that is 0, z derived from the data:
///   z = max(zero_in_noise * median_i(sigma_i), 1e-4 / median_i(h_i)),
/// where h_i is point i's neighbourhood radius and sigma_i the standard error of its principal
/// curvatures: the fit residual taken as noise (unbiased variance s^2), carried through the
/// least-squares covariance s^2 (A^T A)^-1 to the Hessian of the jet,
///   sigma_i = sqrt((4 G33 + 2 G44 + 4 G55) s^2 / 2) / h_i  (G = (A^T A)^-1 in scaled units),
/// i.e. the curvature the fit cannot tell from noise, with a floor at a radius of curvature of
/// 10^4 neighbourhood radii for noise-free data. So K counts as zero when the smaller principal
/// curvature is below z in magnitude.
///
/// With neighborhood Knn and k = 0 the neighbourhood size comes from choose_curvature_scale.
///
/// Requires oriented normals (`cloud.normals`, N×3): they give the sign. Reuses `tree` if given
/// (built over `cloud.positions`). Parallel (oneTBB) in the tree's spatial order; no per-point
/// allocation. Throws UsageError for a bad parameter, missing normals or fewer points than
/// the jet needs; CancelledError when `progress` returns false (the cloud is then unchanged).
/// Not safe to call concurrently on the same cloud.
CurvatureResult estimate_curvature(PointCloud& cloud, const CurvatureParams& params = {}, const KdTree* tree = nullptr,
                                   const ProgressCallback& progress = {});

}  // namespace pointsurf
