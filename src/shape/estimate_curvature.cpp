// SPDX-License-Identifier: GPL-3.0-or-later
#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>
#include <utility>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "core/detail/local_pca.h"
#include "core/detail/progress_reporter.h"
#include "pointsurf/core/error.h"
#include "pointsurf/shape/curvature.h"

namespace pointsurf {
namespace {

// The LDLT pivots of the scaled normal equations: a ratio below this is a singular fit (points
// on a conic, too few distinct points).
constexpr double kPivotTolerance = 1e-12;
// The derived zero threshold never goes below a radius of curvature of this many neighbourhood
// radii (noise-free data have a residual of zero on planes).
constexpr double kFloorRadii = 1e4;
// The fit cylinder when the noise widened the neighbourhood (see choose_curvature_scale).
constexpr double kNoiseCylinder = 0.8;
// The scale choice stops at the k where this share of the samples has a curvature beyond
// zero_in_noise standard errors, or where the residual rises by this factor over the noise floor's.
constexpr double kResolvedShare = 0.9;
constexpr double kBiasRise = 1.2;

struct PointShape {
  double k1 = 0.0, k2 = 0.0;
  double variation = 0.0;
  double noise_curvature = 0.0;  // standard error of a principal curvature, 1/cloud units
  double radius = 0.0;           // h, cloud units
  double rms = 0.0;              // RMS residual of the fit, cloud units
  Vector3d d1 = Vector3d::Zero(), d2 = Vector3d::Zero(), normal = Vector3d::Zero();
  bool degenerate = true;
};

// Monomials u^i v^j, i + j <= degree, in the order 1, u, v, u^2, uv, v^2, u^3, u^2 v, u v^2, v^3.
template <int C>
Eigen::Matrix<double, C, 1> monomials(double u, double v) {
  Eigen::Matrix<double, C, 1> m;
  m[0] = 1.0;
  m[1] = u;
  m[2] = v;
  m[3] = u * u;
  m[4] = u * v;
  m[5] = v * v;
  if constexpr (C == 10) {
    m[6] = u * u * u;
    m[7] = u * u * v;
    m[8] = u * v * v;
    m[9] = v * v * v;
  }
  return m;
}

// Jet fit of `neighbors` around `center` with C coefficients (6: degree 2, 10: degree 3).
// `side` is the input normal; the result's sign follows it. With `cylinder` < 1 only the
// neighbours within cylinder * h of the normal axis enter the fit (h: the neighbourhood radius).
template <int C>
PointShape fit_jet(const KdTree& tree, const Vector3d& center, const Vector3d& side, std::span<const Neighbor> neighbors,
                   double cylinder = 1.0) {
  PointShape out;
  if (neighbors.size() < std::size_t(C) || !(side.squaredNorm() > 0.0)) return out;

  // PCA frame, in offsets from the query point (georeferenced coordinates stay small).
  double h2 = 0.0;
  for (const Neighbor& nb : neighbors) h2 = std::max(h2, (tree.point(nb.index) - center).squaredNorm());
  if (!(h2 > 0.0)) return out;
  const detail::LocalPca pca =
      detail::local_pca([&](std::size_t j) { return Vector3d(tree.point(neighbors[j].index) - center); }, neighbors.size());
  if (!pca.valid) return out;
  Vector3d e3 = pca.normal();
  if (e3.dot(side) < 0.0) e3 = -e3;
  const Vector3d e1 = pca.eigenvectors.col(2).normalized();
  const Vector3d e2 = e3.cross(e1);
  out.variation = pca.variation();

  // Least squares in coordinates scaled by the neighbourhood radius h, so the normal equations
  // are well conditioned whatever the cloud's units.
  const double h = std::sqrt(h2);
  const double inv_h = 1.0 / h;
  const double cylinder2 = cylinder * cylinder;
  const auto outside = [&](const Vector3d& d) { return cylinder < 1.0 && d.squaredNorm() - d.dot(e3) * d.dot(e3) > cylinder2; };
  Eigen::Matrix<double, C, C> normal_matrix = Eigen::Matrix<double, C, C>::Zero();
  Eigen::Matrix<double, C, 1> rhs = Eigen::Matrix<double, C, 1>::Zero();
  std::size_t m = 0;
  for (const Neighbor& nb : neighbors) {
    const Vector3d d = (tree.point(nb.index) - center) * inv_h;
    if (outside(d)) continue;
    ++m;
    const Eigen::Matrix<double, C, 1> a = monomials<C>(d.dot(e1), d.dot(e2));
    normal_matrix.template selfadjointView<Eigen::Lower>().rankUpdate(a);
    rhs.noalias() += d.dot(e3) * a;
  }
  // LDLT reads only the lower triangle, the one rankUpdate filled.
  const Eigen::LDLT<Eigen::Matrix<double, C, C>> ldlt(normal_matrix);
  if (ldlt.info() != Eigen::Success) return out;
  const auto pivots = ldlt.vectorD().cwiseAbs();
  if (!(pivots.minCoeff() > kPivotTolerance * pivots.maxCoeff())) return out;
  const Eigen::Matrix<double, C, 1> c = ldlt.solve(rhs);
  if (!c.allFinite()) return out;

  if (m < std::size_t(C)) return out;
  double residual2 = 0.0;
  for (const Neighbor& nb : neighbors) {
    const Vector3d d = (tree.point(nb.index) - center) * inv_h;
    if (outside(d)) continue;
    const double r = d.dot(e3) - monomials<C>(d.dot(e1), d.dot(e2)).dot(c);
    residual2 += r * r;
  }
  out.radius = h;
  out.rms = std::sqrt(residual2 / double(m)) * h;
  // Standard error of the curvature: the residual taken as noise (unbiased variance), carried
  // through the least-squares covariance rms^2 (A^T A)^-1 of the second-order coefficients to
  // the Hessian [2 c3, c4; c4, 2 c5] / h, whose Frobenius error spread over two eigenvalues.
  // It grows with the design's conditioning (one-sided neighbourhoods, degree 3), which the
  // plain residual would miss.
  Eigen::Matrix<double, C, 3> unit = Eigen::Matrix<double, C, 3>::Zero();
  unit(3, 0) = unit(4, 1) = unit(5, 2) = 1.0;
  const Eigen::Matrix<double, C, 3> inverse_columns = ldlt.solve(unit);
  const double hessian_variance =
      4.0 * inverse_columns(3, 0) + 2.0 * inverse_columns(4, 1) + 4.0 * inverse_columns(5, 2);
  const double unbiased = m > std::size_t(C) ? residual2 / double(m - std::size_t(C)) : 0.0;
  out.noise_curvature = std::sqrt(std::max(unbiased * hessian_variance / 2.0, 0.0)) / h;

  // Derivatives of f(x, y) = h g(x / h, y / h) at the origin, in cloud units.
  const double fx = c[1], fy = c[2];
  const double fxx = 2.0 * c[3] * inv_h, fxy = c[4] * inv_h, fyy = 2.0 * c[5] * inv_h;
  // Fundamental forms of the graph (x, y, f): I = [E F; F G], II = [L M; M N] / w.
  const double w = std::sqrt(1.0 + fx * fx + fy * fy);
  Eigen::Matrix2d first;
  first << 1.0 + fx * fx, fx * fy, fx * fy, 1.0 + fy * fy;
  Eigen::Matrix2d second;
  second << fxx / w, fxy / w, fxy / w, fyy / w;
  // Shape operator I^-1 II, through the symmetric form L^-1 II L^-T with I = L L^T.
  const Eigen::LLT<Eigen::Matrix2d> llt(first);
  const Eigen::Matrix2d lower = llt.matrixL();
  const Eigen::Matrix2d lower_inv = lower.inverse();
  const Eigen::Matrix2d symmetric = lower_inv * second * lower_inv.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> shape;
  shape.computeDirect(symmetric);
  if (shape.info() != Eigen::Success) return out;
  // II is taken with the normal on the +z side, where bending away from the normal has
  // negative second derivatives: negate, so the largest curvature comes from the smallest eigenvalue.
  out.k1 = -shape.eigenvalues()[0];
  out.k2 = -shape.eigenvalues()[1];
  if (!std::isfinite(out.k1) || !std::isfinite(out.k2)) return out;

  const Eigen::Matrix2d param_dirs = lower_inv.transpose() * shape.eigenvectors();
  const auto to_world = [&](const Eigen::Vector2d& uv) {
    // Tangent u r_x + v r_y with r_x = (1, 0, fx), r_y = (0, 1, fy).
    const Vector3d t = uv[0] * e1 + uv[1] * e2 + (uv[0] * fx + uv[1] * fy) * e3;
    return Vector3d(t.normalized());
  };
  out.d1 = to_world(param_dirs.col(0));
  out.d2 = to_world(param_dirs.col(1));
  out.normal = ((e3 - fx * e1 - fy * e2) / w).normalized();
  out.degenerate = false;
  return out;
}

}  // namespace

const char* surface_type_name(SurfaceType type) noexcept {
  switch (type) {
    case SurfaceType::Undefined: return "undefined";
    case SurfaceType::Peak: return "peak";
    case SurfaceType::Pit: return "pit";
    case SurfaceType::Ridge: return "ridge";
    case SurfaceType::Valley: return "valley";
    case SurfaceType::SaddleRidge: return "saddle_ridge";
    case SurfaceType::SaddleValley: return "saddle_valley";
    case SurfaceType::Flat: return "flat";
    case SurfaceType::Minimal: return "minimal";
  }
  return "undefined";
}

SurfaceType classify_surface_type(double H, double K, double h_zero, double k_zero) noexcept {
  if (!std::isfinite(H) || !std::isfinite(K)) return SurfaceType::Undefined;
  const int h = H > h_zero ? 1 : (H < -h_zero ? -1 : 0);
  const int g = K > k_zero ? 1 : (K < -k_zero ? -1 : 0);
  if (g > 0) return h > 0 ? SurfaceType::Peak : (h < 0 ? SurfaceType::Pit : SurfaceType::Flat);
  if (g == 0) return h > 0 ? SurfaceType::Ridge : (h < 0 ? SurfaceType::Valley : SurfaceType::Flat);
  return h > 0 ? SurfaceType::SaddleRidge : (h < 0 ? SurfaceType::SaddleValley : SurfaceType::Minimal);
}

const FieldTable<CurvatureParams>& CurvatureParams::fields() {
  static const FieldTable<CurvatureParams> table = [] {
    using P = CurvatureParams;
    FieldTable<P> t;
    t.choice("neighborhood", &P::neighborhood, neighborhood_kind_names(),
             "Neighbourhood: knn (k nearest), radius (all within r) or hybrid (at most k within r); default: radius when only "
             "radius is given, hybrid when k is given too");
    t.integer("k", &P::k, "Neighbours per point; 0: chosen from the noise (knn, from 24 for degree 2, 40 for degree 3), 24 / 40 (hybrid)")
        .at_least(0)
        .unit("points");
    t.length("radius", &P::radius, "Neighbourhood radius (radius, hybrid)")
        .positive()
        .when([](const P& p) { return p.neighborhood != NeighborhoodKind::Knn; })
        .was("radius_in_spacings");
    t.integer("degree", &P::degree, "Jet degree, 2 or 3").range(2, 3);
    t.number("scale_in_noise", &P::scale_in_noise, "k = 0: the neighbourhood radius grows to this many times the noise (the jet's residual)")
        .positive()
        .when([](const P& p) { return p.k == 0 && p.neighborhood == NeighborhoodKind::Knn; });
    t.integer("max_k", &P::max_k, "k = 0: the most neighbours the noise may call for").at_least(6).unit("points");
    t.number("cylinder", &P::cylinder, "Fit only the neighbours within this fraction of the radius of the normal axis; 0: all")
        .range(0.0, 1.0)
        .internal();
    t.number("zero_curvature", &P::zero_curvature, "Curvature below which H or a principal curvature counts as zero; 0: derived from the fit residuals")
        .unit("1/cloud units")
        .non_negative()
        .meta("Z");
    t.number("zero_in_noise", &P::zero_in_noise, "Derived zero threshold in standard errors of the fitted curvature")
        .positive()
        .when([](const P& p) { return p.zero_curvature == 0.0; });
    t.boolean("keep_directions", &P::keep_directions, "Fill the result's principal directions and Monge normals").internal();
    t.boolean("update_normals", &P::update_normals, "Write the jet (Monge) normals instead of the input ones");
    return t;
  }();
  return table;
}

void CurvatureParams::validate() const {
  const CurvatureParams& params = *this;
  if (params.degree != 2 && params.degree != 3)
    throw UsageError(fmt::format("estimate_curvature: degree must be 2 or 3, got {}", params.degree));
  const int coefficients = params.degree == 2 ? 6 : 10;
  const Neighborhood settings = params.neighborhood_settings();
  // k has its own rule here (0: the degree's default), so the shared check skips it.
  if (settings.uses_k() && settings.k < coefficients)
    throw UsageError(fmt::format("estimate_curvature: k must be 0 (default) or >= {} for degree {}, got {}", coefficients,
                                 params.degree, params.k));
  settings.validate("estimate_curvature", 0);
  if (!(params.zero_curvature >= 0.0 && std::isfinite(params.zero_curvature)))
    throw UsageError(fmt::format("estimate_curvature: zero_curvature must be >= 0 (1/cloud units), got {}", params.zero_curvature));
  if (params.k == 0 && params.neighborhood == NeighborhoodKind::Knn) {
    if (!(params.scale_in_noise > 0.0 && std::isfinite(params.scale_in_noise)))
      throw UsageError(fmt::format("estimate_curvature: scale_in_noise must be > 0, got {}", params.scale_in_noise));
    if (params.max_k < settings.k)
      throw UsageError(fmt::format("estimate_curvature: max_k must be at least the starting k {} for degree {}, got {}", settings.k,
                                   params.degree, params.max_k));
  }
  if (!(params.cylinder >= 0.0 && params.cylinder <= 1.0))
    throw UsageError(fmt::format("estimate_curvature: cylinder must be in (0, 1] (0: automatic), got {}", params.cylinder));
  if (params.zero_curvature == 0.0 && !(params.zero_in_noise > 0.0 && std::isfinite(params.zero_in_noise)))
    throw UsageError(fmt::format("estimate_curvature: zero_in_noise must be > 0, got {}", params.zero_in_noise));
  fields().validate(*this, "estimate_curvature");
}

namespace {

void check_point_count(std::size_t n, const CurvatureParams& params) {
  const int coefficients = params.degree == 2 ? 6 : 10;
  if (n < std::size_t(coefficients))
    throw UsageError(fmt::format("estimate_curvature: needs at least {} points for degree {}, got {}", coefficients,
                                 params.degree, n));
}

double median_of(std::vector<double>& v) {
  if (v.empty()) return 0.0;
  auto mid = v.begin() + std::ptrdiff_t(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace

CurvatureScale choose_curvature_scale(const PointCloud& cloud, const CurvatureParams& params, const KdTree& tree) {
  params.validate();
  const std::size_t n = cloud.size();
  check_point_count(n, params);
  if (tree.size() != n)
    throw UsageError(fmt::format("choose_curvature_scale: the kd-tree holds {} points but the cloud has {}", tree.size(), n));
  const std::size_t coefficients = params.degree == 2 ? 6 : 10;
  constexpr std::size_t kMaxSamples = 1000;
  const std::size_t samples = std::min(n, kMaxSamples);
  const std::span<const std::uint32_t> order = tree.spatial_order();

  // One level per k: the medians over the samples of the fit's residual and radius, and the
  // share of samples whose curvature stands out of its own noise.
  struct Level {
    CurvatureScale scale;
    double resolved = 0.0;
  };
  const std::size_t start = std::size_t(params.neighborhood_settings().k);
  const auto level_at = [&](std::size_t k) {
    std::vector<double> residual(samples), radius(samples);
    std::vector<char> resolved(samples);
    tbb::enumerable_thread_specific<std::vector<Neighbor>> buffers;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, samples, 16), [&](const tbb::blocked_range<std::size_t>& r) {
      std::vector<Neighbor>& neighbors = buffers.local();
      for (std::size_t s = r.begin(); s != r.end(); ++s) {
        const Vector3d& p = cloud.positions[order[s * n / samples]];
        tree.knn(p, k, neighbors);
        // The side only sets the sign, which none of these depend on; the cylinder is the one
        // the final fit will use at this k.
        const double cylinder = k > start ? kNoiseCylinder : 1.0;
        const PointShape shape = params.degree == 2 ? fit_jet<6>(tree, p, Vector3d::UnitZ(), neighbors, cylinder)
                                                    : fit_jet<10>(tree, p, Vector3d::UnitZ(), neighbors, cylinder);
        const std::size_t m = neighbors.size();
        const bool fitted = !shape.degenerate && m > coefficients;
        residual[s] = fitted ? shape.rms * std::sqrt(double(m) / double(m - coefficients)) : std::nan("");
        radius[s] = fitted ? shape.radius : std::nan("");
        resolved[s] = fitted && std::max(std::abs(shape.k1), std::abs(shape.k2)) > params.zero_in_noise * shape.noise_curvature;
      }
    });
    std::vector<double> fitted_residual, fitted_radius;
    std::size_t count = 0;
    for (std::size_t s = 0; s < samples; ++s)
      if (!std::isnan(residual[s])) {
        fitted_residual.push_back(residual[s]);
        fitted_radius.push_back(radius[s]);
        count += resolved[s] ? 1 : 0;
      }
    Level level;
    level.scale.k = int(k);
    level.scale.noise = median_of(fitted_residual);
    level.scale.radius = median_of(fitted_radius);
    level.scale.cylinder = k > start ? kNoiseCylinder : 1.0;
    level.resolved = fitted_residual.empty() ? 0.0 : double(count) / double(fitted_residual.size());
    return level;
  };

  // First the noise floor: the smallest k whose radius is scale_in_noise times its residual.
  // Then, while over a tenth of the samples' curvature is within zero_in_noise standard errors of zero, wider
  // until it is not (a noisy curved surface resolves), or the residual rises 20 % above the
  // floor's (the jet no longer fits: planes meeting, a curved surface bending away from the
  // quadric), or max_k: those keep the floor (a flat surface stays flat at any k).
  std::optional<Level> floor;
  Level level;
  for (std::size_t k = start;; k *= 2) {
    level = level_at(std::min(k, n));
    if (!floor && level.scale.radius >= params.scale_in_noise * level.scale.noise) floor = level;
    if (floor) {
      if (level.resolved >= kResolvedShare) return level.scale;
      if (level.scale.noise > kBiasRise * floor->scale.noise) return floor->scale;
    }
    if (std::size_t(level.scale.k) == n || 2 * k > std::size_t(params.max_k)) break;
  }
  if (floor) return floor->scale;
  level.scale.capped = true;
  return level.scale;
}

CurvatureResult estimate_curvature(PointCloud& cloud, const CurvatureParams& params_in, const KdTree* tree,
                                   const ProgressCallback& progress) {
  const std::size_t n = cloud.size();
  params_in.validate();
  check_point_count(n, params_in);
  if (cloud.normals.size() != n)
    throw UsageError(fmt::format("estimate_curvature: needs oriented normals (one per point), the cloud has {} for {} points; "
                                 "estimate and orient them first",
                                 cloud.normals.size(), n));
  if (tree != nullptr && tree->size() != n)
    throw UsageError(
        fmt::format("estimate_curvature: the kd-tree holds {} points but the cloud has {}", tree->size(), n));

  std::optional<KdTree> own_tree;
  if (tree == nullptr) tree = &own_tree.emplace(cloud.positions);

  CurvatureResult result;
  CurvatureParams params = params_in;
  if (params.k == 0 && params.neighborhood == NeighborhoodKind::Knn) {
    const CurvatureScale scale = choose_curvature_scale(cloud, params, *tree);
    params.k = scale.k;
    if (params.cylinder == 0.0) params.cylinder = scale.cylinder;
    result.scale_chosen = true;
    result.noise = scale.noise;
    result.scale_capped = scale.capped;
  }
  const double cylinder = params.cylinder == 0.0 ? 1.0 : params.cylinder;
  const Neighborhood settings = params.neighborhood_settings();
  const int k = settings.k;
  if (settings.uses_k()) result.k_used = k;
  result.radius_used = settings.resolve_radius(*tree);

  std::vector<double> k1(n), k2(n), variation(n);
  std::vector<double> noise(n), radius(n), rms(n);  // per point; NaN where degenerate
  const bool directions = params.keep_directions || params.update_normals;
  std::vector<Vector3d> d1(directions ? n : 0), d2(directions ? n : 0), jet_normals(directions ? n : 0);

  const std::span<const std::uint32_t> order = tree->spatial_order();
  detail::ProgressReporter reporter(progress, 0.0, 0.95, n);
  tbb::enumerable_thread_specific<std::vector<Neighbor>> buffers;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256), [&](const tbb::blocked_range<std::size_t>& r) {
    if (reporter.cancelled()) return;
    std::vector<Neighbor>& neighbors = buffers.local();
    for (std::size_t pos = r.begin(); pos != r.end(); ++pos) {
      const std::uint32_t i = order[pos];
      const Vector3d& p = cloud.positions[i];
      settings.query(*tree, p, std::size_t(k), result.radius_used, neighbors);
      const PointShape s = params.degree == 2 ? fit_jet<6>(*tree, p, cloud.normals[i], neighbors, cylinder)
                                              : fit_jet<10>(*tree, p, cloud.normals[i], neighbors, cylinder);
      k1[i] = s.k1;
      k2[i] = s.k2;
      variation[i] = s.variation;
      noise[i] = s.degenerate ? std::nan("") : s.noise_curvature;
      radius[i] = s.degenerate ? std::nan("") : s.radius;
      rms[i] = s.rms;
      if (directions) {
        d1[i] = s.d1;
        d2[i] = s.d2;
        jet_normals[i] = s.degenerate ? Vector3d::Zero() : s.normal;
      }
    }
    reporter.advance(r.size());
  });
  reporter.throw_if_cancelled();

  // Zero threshold from the medians over the fitted points.
  std::vector<double> fitted_noise, fitted_radius, fitted_rms;
  fitted_noise.reserve(n);
  fitted_radius.reserve(n);
  fitted_rms.reserve(n);
  for (std::size_t i = 0; i < n; ++i)
    if (!std::isnan(noise[i])) {
      fitted_noise.push_back(noise[i]);
      fitted_radius.push_back(radius[i]);
      fitted_rms.push_back(rms[i]);
    }
  result.degenerate = n - fitted_noise.size();
  const double median_noise = median_of(fitted_noise);
  const double median_radius = median_of(fitted_radius);
  result.median_residual = median_of(fitted_rms);
  double zero = params.zero_curvature;
  if (zero == 0.0 && median_radius > 0.0)
    zero = std::max(params.zero_in_noise * median_noise, 1.0 / (kFloorRadii * median_radius));
  result.zero_curvature = zero;

  std::vector<double> mean(n), gauss(n), types(n);
  tbb::enumerable_thread_specific<std::array<std::size_t, kSurfaceTypeCount>> counts(
      std::array<std::size_t, kSurfaceTypeCount>{});
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    std::array<std::size_t, kSurfaceTypeCount>& local = counts.local();
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      mean[i] = 0.5 * (k1[i] + k2[i]);
      gauss[i] = k1[i] * k2[i];
      SurfaceType type = SurfaceType::Undefined;
      if (!std::isnan(noise[i])) {
        const double k_zero = zero * std::max({std::abs(k1[i]), std::abs(k2[i]), zero});
        type = classify_surface_type(mean[i], gauss[i], zero, k_zero);
      }
      types[i] = double(static_cast<std::uint8_t>(type));
      ++local[static_cast<std::size_t>(type)];
    }
  });
  for (const auto& local : counts)
    for (int t = 0; t < kSurfaceTypeCount; ++t) result.type_counts[std::size_t(t)] += local[std::size_t(t)];
  reporter.report(1.0);
  reporter.throw_if_cancelled();

  // Commit. A field already present keeps its values' vector but takes the new type.
  const auto commit = [&](const char* name, std::vector<double>&& values, ScalarType type) {
    ScalarField& field = cloud.fields.add(name, 0, type);
    field.type = type;
    field.values = std::move(values);
  };
  commit("k1", std::move(k1), ScalarType::Float32);
  commit("k2", std::move(k2), ScalarType::Float32);
  commit("mean", std::move(mean), ScalarType::Float32);
  commit("gauss", std::move(gauss), ScalarType::Float32);
  commit("variation", std::move(variation), ScalarType::Float32);
  commit("surface_type", std::move(types), ScalarType::UInt8);
  if (params.update_normals) {
    for (std::size_t i = 0; i < n; ++i)
      if (jet_normals[i].squaredNorm() > 0.0) cloud.normals[i] = jet_normals[i];
  }
  if (params.keep_directions) {
    result.d1 = std::move(d1);
    result.d2 = std::move(d2);
    result.normals = std::move(jet_normals);
  }
  return result;
}

const ResultTable<CurvatureResult>& CurvatureResult::results() {
  static const ResultTable<CurvatureResult> table = [] {
    using R = CurvatureResult;
    ResultTable<R> t;
    t.count("degenerate", &R::degenerate, "Points with no curvature (zero normal, too few neighbours, singular fit)").lower_is_better().as_count();
    for (int type = 0; type < kSurfaceTypeCount; ++type)
      t.computed(surface_type_name(static_cast<SurfaceType>(type)), ResultType::Integer,
                 [type](const R& r) { return ResultValue(std::int64_t(r.type_counts[std::size_t(type)])); }, "Points of this HK surface type")
          .as_count();
    return t;
  }();
  return table;
}

const ResultTable<CurvatureScale>& CurvatureScale::results() {
  static const ResultTable<CurvatureScale> table = [] {
    using S = CurvatureScale;
    ResultTable<S> t;
    t.number("noise", &S::noise, "Noise: median RMS residual of the jet fits at the chosen k").with_unit("cloud units");
    t.computed("radius_in_noise", ResultType::Number, [](const S& s) { return ResultValue(s.noise > 0.0 ? s.radius / s.noise : 0.0); },
               "Median neighbourhood radius in noise units");
    t.flag("scale_capped", &S::capped, "k stopped at max_k before the radius reached scale_in_noise times the noise").lower_is_better();
    return t;
  }();
  return table;
}

}  // namespace pointsurf
