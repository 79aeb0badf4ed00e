// SPDX-License-Identifier: GPL-3.0-or-later
// Least-squares B-spline surface fit with thin-plate smoothing, parameter correction and knot
// insertion until a tolerance is met (surface/fit_bspline.h).
#include "pointsurf/surface/fit_bspline.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <utility>

#include <Eigen/Geometry>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/detail/local_pca.h"
#include "core/detail/progress_reporter.h"
#include "pointsurf/core/error.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;

constexpr const char* kFunction = "fit_bspline_surface";
constexpr std::size_t kNeighbours = 12;         // local PCA: noise estimate and fold test
constexpr double kFoldShare = 0.02;             // more tilted points than this: folded
// Default tolerance: the largest of N Gaussian deviations is about sqrt(2 ln N) sigma; the
// local-PCA estimate runs about 15 % under sigma, so a margin of 1.5, and at least 6 x the
// estimate (small N), and at least 0.001 spacings (noise-free data).
constexpr double kToleranceMargin = 1.5;
constexpr double kToleranceInNoise = 6.0;
constexpr double kToleranceFloorInSpacings = 1e-3;
constexpr double kSmoothingFloor = 1e-12;       // where a control point has no data (smoothing 0)
constexpr double kFramePhase = 0.1;             // share of the progress before the first fit

// Progress that never goes backwards and turns a refusal into CancelledError at serial points.
// The ProgressReporter of a parallel loop calls it under its own lock, never concurrently.
class MonotoneProgress {
public:
  explicit MonotoneProgress(const ProgressCallback& user) : user_(user) {
    if (user_) callback_ = [this](double f) { return forward(f); };
  }
  const ProgressCallback& callback() const { return callback_; }
  void report(double f) {
    if (user_ && !forward(f)) throw CancelledError();
  }

private:
  bool forward(double f) {
    last_ = std::max(last_, std::min(f, 1.0));
    return user_(last_);
  }
  const ProgressCallback& user_;
  ProgressCallback callback_;
  double last_ = 0.0;
};

// Gauss-Legendre nodes and weights on [-1, 1] (Newton on the Legendre polynomial).
void gauss_legendre(int m, std::vector<double>& x, std::vector<double>& w) {
  x.assign(std::size_t(m), 0.0);
  w.assign(std::size_t(m), 0.0);
  for (int i = 0; i < m; ++i) {
    double z = std::cos(std::numbers::pi * (i + 0.75) / (m + 0.5)), dp = 1.0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1.0, p1 = 0.0;
      for (int j = 1; j <= m; ++j) {
        const double p2 = p1;
        p1 = p0;
        p0 = ((2.0 * j - 1.0) * z * p1 - (j - 1.0) * p2) / j;
      }
      dp = m * (z * p0 - p1) / (z * z - 1.0);
      const double dz = p0 / dp;
      z -= dz;
      if (std::abs(dz) < 1e-15) break;
    }
    x[std::size_t(i)] = z;
    w[std::size_t(i)] = 2.0 / ((1.0 - z * z) * dp * dp);
  }
}

// Banded Gram matrices of one knot vector: g[d][i * (2p + 1) + (k - i + p)] = integral of
// N_i^(d) N_k^(d) over the domain, d = 0, 1, 2; exact (Gauss with p + 1 nodes per span).
struct Gram {
  int p = 0, n = 0;
  std::vector<double> g[3];
  double at(int d, int i, int offset) const { return g[d][std::size_t(i) * std::size_t(2 * p + 1) + std::size_t(offset + p)]; }
};

Gram gram(const std::vector<double>& knots, int p) {
  Gram out;
  out.p = p;
  out.n = int(knots.size()) - p - 1;
  const std::size_t width = std::size_t(2 * p + 1);
  for (auto& g : out.g) g.assign(std::size_t(out.n) * width, 0.0);
  std::vector<double> x, w;
  gauss_legendre(p + 1, x, w);
  for (int s = p; s < out.n; ++s) {
    const double a = knots[std::size_t(s)], b = knots[std::size_t(s + 1)];
    if (!(b > a)) continue;
    const double half = 0.5 * (b - a), mid = 0.5 * (a + b);
    for (std::size_t t = 0; t < x.size(); ++t) {
      const BSplineBasis basis = bspline_basis(mid + half * x[t], p, knots, 2);
      const double weight = w[t] * half;
      for (int d = 0; d < 3; ++d)
        for (int r = 0; r <= p; ++r)
          for (int c = 0; c <= p; ++c) {
            const int i = basis.span - p + r, k = basis.span - p + c;
            out.g[d][std::size_t(i) * width + std::size_t(k - i + p)] +=
                weight * basis.d[std::size_t(d)][std::size_t(r)] * basis.d[std::size_t(d)][std::size_t(c)];
          }
    }
  }
  return out;
}

std::vector<double> uniform_knots(int spans, int p) {
  std::vector<double> k(std::size_t(p + 1), 0.0);
  for (int s = 1; s < spans; ++s) k.push_back(double(s) / spans);
  k.insert(k.end(), std::size_t(p + 1), 1.0);
  return k;
}

// The least-squares system over one net, its solution as the control points.
struct Fitter {
  std::span<const Vector3d> q;  // points relative to the centroid
  int p = 3;
  double aspect = 1.0;          // H / W of the bounding rectangle
  double smoothing = 0.0;       // as given
  double smoothing_used = 0.0;  // after the floor

  std::vector<Vector3d> solve(const std::vector<double>& U, const std::vector<double>& V, const std::vector<Vector2d>& uv) {
    const int nu = int(U.size()) - p - 1, nv = int(V.size()) - p - 1;
    const std::size_t nctrl = std::size_t(nu) * std::size_t(nv);
    const int bw = 2 * p + 1;
    const std::size_t width = std::size_t(bw * bw);
    auto slot = [&](int di, int dj) { return std::size_t((di + p) * bw + (dj + p)); };
    // Data term B^T B and B^T P, row by row: the points sorted by knot-span cell, each row of
    // the band summed by one task over the cells under its basis function, in a fixed order, so
    // that the result does not depend on the threads.
    const int cells_u = nu - p, cells_v = nv - p;
    const std::size_t stride = std::size_t(p + 1);
    std::vector<double> nu_of(q.size() * stride), nv_of(q.size() * stride);
    std::vector<std::uint32_t> cell_of(q.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, q.size(), 1024), [&](const tbb::blocked_range<std::size_t>& range) {
      for (std::size_t k = range.begin(); k < range.end(); ++k) {
        const BSplineBasis bu = bspline_basis(uv[k].x(), p, U, 0), bv = bspline_basis(uv[k].y(), p, V, 0);
        for (std::size_t a = 0; a < stride; ++a) nu_of[k * stride + a] = bu.d[0][a], nv_of[k * stride + a] = bv.d[0][a];
        cell_of[k] = std::uint32_t((bu.span - p) * cells_v + (bv.span - p));
      }
    });
    std::vector<std::uint32_t> cell_start(std::size_t(cells_u) * std::size_t(cells_v) + 1, 0), sorted(q.size());
    for (std::uint32_t c : cell_of) ++cell_start[c + 1];
    for (std::size_t c = 1; c < cell_start.size(); ++c) cell_start[c] += cell_start[c - 1];
    {
      std::vector<std::uint32_t> fill(cell_start.begin(), cell_start.end() - 1);
      for (std::size_t k = 0; k < q.size(); ++k) sorted[fill[cell_of[k]]++] = std::uint32_t(k);
    }
    std::vector<double> band(nctrl * width, 0.0), rhs(nctrl * 3, 0.0);
    tbb::parallel_for(tbb::blocked_range<int>(0, nu), [&](const tbb::blocked_range<int>& range) {
      for (int i = range.begin(); i < range.end(); ++i)
        for (int j = 0; j < nv; ++j) {
          const std::size_t row = std::size_t(i) * std::size_t(nv) + std::size_t(j);
          double* out = band.data() + row * width;
          for (int cu = std::max(0, i - p); cu <= std::min(i, cells_u - 1); ++cu)
            for (int cv = std::max(0, j - p); cv <= std::min(j, cells_v - 1); ++cv) {
              const std::size_t cell = std::size_t(cu) * std::size_t(cells_v) + std::size_t(cv);
              for (std::uint32_t m = cell_start[cell]; m < cell_start[cell + 1]; ++m) {
                const std::size_t k = sorted[m];
                const double* bu = nu_of.data() + k * stride;
                const double* bv = nv_of.data() + k * stride;
                const double wr = bu[i - cu] * bv[j - cv];
                for (int c = 0; c <= p; ++c) {
                  const double wc = wr * bu[c];
                  for (int d = 0; d <= p; ++d) out[slot(cu + c - i, cv + d - j)] += wc * bv[d];
                }
                for (int e = 0; e < 3; ++e) rhs[row * 3 + std::size_t(e)] += wr * q[k][e];
              }
            }
        }
    });
    // Smoothing floor: without smoothing, a control point with no point under it leaves the
    // system singular.
    smoothing_used = smoothing;
    if (smoothing_used < kSmoothingFloor) {
      double largest = 0.0, smallest = std::numeric_limits<double>::infinity();
      for (std::size_t r = 0; r < nctrl; ++r) {
        const double d = band[r * width + slot(0, 0)];
        largest = std::max(largest, d);
        smallest = std::min(smallest, d);
      }
      if (!(smallest > 1e-10 * largest)) smoothing_used = kSmoothingFloor;
    }
    // Thin-plate energy rho^2 Suu^2 + 2 Suv^2 + rho^-2 Svv^2 over [0, 1]^2 (fit_bspline.h),
    // from the 1D Gram matrices (the energy of a tensor product separates).
    if (smoothing_used > 0.0) {
      const Gram gu = gram(U, p), gv = gram(V, p);
      const double scale = smoothing_used * double(q.size());
      const double cu = scale * aspect * aspect, cuv = 2.0 * scale, cv = scale / (aspect * aspect);
      for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
          double* row = band.data() + (std::size_t(i) * std::size_t(nv) + std::size_t(j)) * width;
          for (int di = -p; di <= p; ++di) {
            if (i + di < 0 || i + di >= nu) continue;
            for (int dj = -p; dj <= p; ++dj) {
              if (j + dj < 0 || j + dj >= nv) continue;
              row[slot(di, dj)] += cu * gu.at(2, i, di) * gv.at(0, j, dj) + cuv * gu.at(1, i, di) * gv.at(1, j, dj) +
                                   cv * gu.at(0, i, di) * gv.at(2, j, dj);
            }
          }
        }
    }
    std::vector<Eigen::Triplet<double>> triplets;
    triplets.reserve(nctrl * width);
    for (int i = 0; i < nu; ++i)
      for (int j = 0; j < nv; ++j) {
        const std::size_t r = std::size_t(i) * std::size_t(nv) + std::size_t(j);
        for (int di = -p; di <= p; ++di) {
          if (i + di < 0 || i + di >= nu) continue;
          for (int dj = -p; dj <= p; ++dj) {
            if (j + dj < 0 || j + dj >= nv) continue;
            const double value = band[r * width + slot(di, dj)];
            if (value != 0.0) triplets.emplace_back(int(r), (i + di) * nv + (j + dj), value);
          }
        }
      }
    const int size = int(nctrl);
    Eigen::SparseMatrix<double> matrix(size, size);
    matrix.setFromTriplets(triplets.begin(), triplets.end());
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(matrix);
    if (solver.info() != Eigen::Success)
      throw ComputeError(fmt::format("{}: the normal equations of a {} x {} control net are singular", kFunction, nu, nv));
    Eigen::MatrixXd b(int(nctrl), 3);
    for (std::size_t r = 0; r < nctrl; ++r)
      for (int e = 0; e < 3; ++e) b(int(r), e) = rhs[r * 3 + std::size_t(e)];
    const Eigen::MatrixXd x = solver.solve(b);
    if (solver.info() != Eigen::Success || !x.allFinite())
      throw ComputeError(fmt::format("{}: solving the normal equations of a {} x {} control net failed", kFunction, nu, nv));
    std::vector<Vector3d> control(nctrl);
    for (std::size_t r = 0; r < nctrl; ++r) control[r] = x.row(int(r)).transpose();
    return control;
  }
};

// Projects every point onto the surface from its current parameters (the parameter
// correction); with `deviations`, also the signed distances.
void project(const BSplineSurface& s, std::span<const Vector3d> q, const Vector3d& normal, std::vector<Vector2d>& uv,
             std::vector<double>* deviations, const ProgressCallback& progress, double begin, double end) {
  detail::ProgressReporter reporter(progress, begin, end, q.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, q.size(), 256), [&](const tbb::blocked_range<std::size_t>& range) {
    if (reporter.cancelled()) return;
    for (std::size_t k = range.begin(); k < range.end(); ++k) {
      const SurfaceFootPoint c = s.closest_local(q[k], uv[k].x(), uv[k].y());
      uv[k] = Vector2d(c.u, c.v);
      if (deviations) {
        Vector3d n = s.normal(c.u, c.v);
        if (n.dot(normal) < 0.0) n = -n;
        (*deviations)[k] = (q[k] - c.point).dot(n) >= 0.0 ? c.distance : -c.distance;
      }
    }
    reporter.advance(range.size());
  });
  reporter.throw_if_cancelled();
}

// Sign of an axis fixed by its largest component, so that the frame does not flip with
// rounding (a permuted or shifted input gives the same frame).
Vector3d canonical(Vector3d axis) {
  Eigen::Index largest = 0;
  axis.cwiseAbs().maxCoeff(&largest);
  return axis[largest] < 0.0 ? Vector3d(-axis) : axis;
}

}  // namespace

const char* bspline_fit_stop_name(BSplineFitStop stop) noexcept {
  switch (stop) {
    case BSplineFitStop::ToleranceMet: return "tolerance met";
    case BSplineFitStop::RoundLimit: return "round limit";
    case BSplineFitStop::ControlPointLimit: return "control point limit";
  }
  return "";
}

const FieldTable<BSplineFitParams>& BSplineFitParams::fields() {
  static const FieldTable<BSplineFitParams> table = [] {
    using P = BSplineFitParams;
    FieldTable<P> t;
    t.integer("degree", &P::degree, "Degree of the B-spline in u and in v").range(1, kMaxBSplineDegree);
    t.number("tolerance", &P::tolerance, "Largest |deviation| wanted; 0: max(6, 1.5 sqrt(2 ln N)) x the noise estimate, at least 0.001 x the mean spacing")
        .unit("cloud units")
        .non_negative();
    t.number("smoothing", &P::smoothing, "Weight of the thin-plate energy, independent of the patch's size and point count; 0: none")
        .non_negative();
    t.number("points_per_span", &P::points_per_span, "The first control net has about N / this many knot-span cells")
        .unit("points")
        .positive();
    t.integer("max_rounds", &P::max_rounds, "Knot-insertion rounds at most").at_least(0);
    t.integer("max_control_points", &P::max_control_points, "The control net never grows beyond this many points, nor beyond the number of input points").at_least(4);
    t.integer("parameter_corrections", &P::parameter_corrections, "Re-projections of the points onto the surface (and refits) per round")
        .at_least(0);
    t.number("max_tilt_deg", &P::max_tilt_deg, "Points whose local normal is further than this from the base plane's are on a fold")
        .unit("degrees")
        .range(0.0, 90.0, true, false);
    return t;
  }();
  return table;
}

void BSplineFitParams::validate() const {
  for (double v : {tolerance, smoothing, points_per_span, max_tilt_deg})
    if (!std::isfinite(v)) throw UsageError(fmt::format("{}: parameters must be finite, got {}", kFunction, v));
  fields().validate(*this, kFunction);
  const long needed = long(degree + 1) * long(degree + 1);
  if (max_control_points < needed)
    throw UsageError(fmt::format("{}: max_control_points must be >= (degree + 1)^2 = {}, got {}", kFunction, needed, max_control_points));
}

const ResultTable<BSplineFitResult>& BSplineFitResult::results() {
  static const ResultTable<BSplineFitResult> table = [] {
    using R = BSplineFitResult;
    ResultTable<R> t;
    t.number("max_deviation", &R::max_deviation, "Largest |distance| of a point to the surface").with_unit("cloud units").lower_is_better().in_headline();
    t.number("rms_deviation", &R::rms_deviation, "Root mean square distance of the points to the surface").with_unit("cloud units").lower_is_better();
    t.number("tolerance", &R::tolerance, "The tolerance used").with_unit("cloud units");
    t.flag("tolerance_met", &R::tolerance_met, "max_deviation <= tolerance").higher_is_better().in_headline();
    t.text("stop_reason", &R::stop_reason, "Why the refinement stopped: tolerance met, round limit, control point limit");
    t.count("rounds", &R::rounds, "Knot-insertion rounds done").as_count();
    t.count("control_points", &R::control_points, "Control points of the final net").as_count();
    t.computed("control_net", ResultType::Text,
               [](const R& r) { return ResultValue(fmt::format("{}x{}", r.surface.count_u(), r.surface.count_v())); },
               "Control points in u x in v");
    t.number("smoothing", &R::smoothing, "The thin-plate weight used");
    t.number("noise", &R::noise, "Noise estimate (local plane residual)").with_unit("cloud units");
    t.number("spacing", &R::spacing, "Mean spacing of the points").with_unit("cloud units");
    return t;
  }();
  return table;
}

BSplineFitResult fit_bspline_surface(std::span<const Vector3d> points, const BSplineFitParams& params, const ProgressCallback& progress) {
  params.validate();
  MonotoneProgress monitor(progress);
  const std::size_t n = points.size();
  const int p = params.degree;
  if (n == 0) throw InputError(fmt::format("{}: no points", kFunction));
  for (std::size_t k = 0; k < n; ++k)
    if (!points[k].allFinite())
      throw InputError(fmt::format("{}: point {} is not finite ({}, {}, {})", kFunction, k, points[k].x(), points[k].y(), points[k].z()));
  const std::size_t needed = std::size_t(p + 1) * std::size_t(p + 1);
  if (n < needed)
    throw InputError(fmt::format("{}: {} points, a surface of degree {} needs at least (degree + 1)^2 = {}", kFunction, n, p, needed));
  report_phase(progress, "base plane");

  // The least-squares plane: PCA of the offsets from the first point, so that 1e6 m offsets
  // cancel before any sum; its centroid is the origin of everything after.
  BSplineFitResult result;
  BSplineFitFrame& frame = result.frame;
  const detail::LocalPca plane = detail::local_pca([&](std::size_t k) { return Vector3d(points[k] - points[0]); }, n);
  if (!plane.valid) throw InputError(fmt::format("{}: the {} points coincide or lie on a line; a surface needs a patch", kFunction, n));
  frame.origin = points[0] + plane.mean;
  frame.normal = canonical(plane.eigenvectors.col(0));
  frame.axis_u = canonical(plane.eigenvectors.col(2));
  frame.axis_v = frame.normal.cross(frame.axis_u).normalized();
  std::vector<Vector3d> q(n);
  for (std::size_t k = 0; k < n; ++k) q[k] = points[k] - frame.origin;
  monitor.report(0.02);

  // Local planes of the 12 nearest neighbours: the noise estimate and the fold test.
  {
    const KdTree tree(q);
    result.spacing = mean_spacing(tree);
    const NeighborLists lists = tree.knn_all({}, std::min(kNeighbours, n));
    monitor.report(0.05);
    std::vector<double> smallest(n, -1.0);  // -1: no plane
    std::vector<std::uint8_t> tilted(n, 0);
    const double cos_tilt = std::cos(params.max_tilt_deg * std::numbers::pi / 180.0);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& range) {
      for (std::size_t k = range.begin(); k < range.end(); ++k) {
        const auto nb = lists[k];
        const detail::LocalPca local = detail::local_pca([&](std::size_t i) { return Vector3d(q[nb[i].index] - q[k]); }, nb.size());
        if (!local.valid) continue;  // fewer than 3 distinct points: no plane, nothing to tell
        smallest[k] = std::max(local.eigenvalues[0], 0.0);
        tilted[k] = std::abs(local.normal().dot(frame.normal)) < cos_tilt;
      }
    });
    const std::size_t folded = std::size_t(std::count(tilted.begin(), tilted.end(), std::uint8_t{1}));
    if (double(folded) > kFoldShare * double(n))
      throw InputError(fmt::format(
          "{}: the patch folds over its base plane: {} of {} points ({:.1f} %) have a local normal more than {} degrees from the plane's "
          "normal, so projecting onto the plane is not one-to-one; split the patch into height fields over a plane (quadric base "
          "surfaces are not implemented yet)",
          kFunction, folded, n, 100.0 * double(folded) / double(n), params.max_tilt_deg));
    std::erase(smallest, -1.0);
    if (!smallest.empty()) {
      const auto middle = smallest.begin() + std::ptrdiff_t(smallest.size() / 2);
      std::nth_element(smallest.begin(), middle, smallest.end());
      result.noise = std::sqrt(*middle);
    }
  }
  const double noise_factor = std::max(kToleranceInNoise, kToleranceMargin * std::sqrt(2.0 * std::log(double(n))));
  result.tolerance =
      params.tolerance > 0.0 ? params.tolerance : std::max(noise_factor * result.noise, kToleranceFloorInSpacings * result.spacing);
  monitor.report(0.08);

  // Parameterization by projection onto the plane, scaled to [0, 1]^2 over the bounding rectangle.
  frame.a_min = frame.b_min = std::numeric_limits<double>::infinity();
  frame.a_max = frame.b_max = -std::numeric_limits<double>::infinity();
  for (const Vector3d& x : q) {
    const double a = x.dot(frame.axis_u), b = x.dot(frame.axis_v);
    frame.a_min = std::min(frame.a_min, a), frame.a_max = std::max(frame.a_max, a);
    frame.b_min = std::min(frame.b_min, b), frame.b_max = std::max(frame.b_max, b);
  }
  const double width = frame.a_max - frame.a_min, height = frame.b_max - frame.b_min;
  if (!(width > 0.0) || !(height > 0.0)) throw InputError(fmt::format("{}: the points lie on a line; a surface needs a patch", kFunction));
  std::vector<Vector2d> uv(n);
  for (std::size_t k = 0; k < n; ++k)
    uv[k] = Vector2d(std::clamp((q[k].dot(frame.axis_u) - frame.a_min) / width, 0.0, 1.0),
                     std::clamp((q[k].dot(frame.axis_v) - frame.b_min) / height, 0.0, 1.0));

  // The net never has more control points than there are points: beyond that it would only
  // interpolate the noise.
  const long max_control = std::min<long>(params.max_control_points, std::max<long>(long(n), long(needed)));
  // The first net: about N / points_per_span cells, shaped like the rectangle.
  const double cells = std::max(1.0, double(n) / params.points_per_span);
  int su = std::max(1, int(std::lround(std::sqrt(cells * width / height))));
  int sv = std::max(1, int(std::lround(std::sqrt(cells * height / width))));
  su = int(std::min<long>(su, max_control));
  sv = int(std::min<long>(sv, max_control));
  while (long(su + p) * long(sv + p) > max_control) (su >= sv ? su : sv) = std::max(1, (su >= sv ? su : sv) - 1);
  std::vector<double> U = uniform_knots(su, p), V = uniform_knots(sv, p);

  Fitter fitter{q, p, height / width, params.smoothing};
  std::vector<double> deviations(n, 0.0);
  const int steps = params.parameter_corrections + 1;
  const double round_share = (1.0 - kFramePhase) / double(params.max_rounds + 1);
  for (int round = 0;; ++round) {
    report_phase(progress, fmt::format("fit round {}", round));
    const double round_begin = kFramePhase + round_share * round;
    for (int step = 0; step < steps; ++step) {
      const double begin = round_begin + round_share * step / steps, end = round_begin + round_share * (step + 1) / steps;
      monitor.report(begin);
      const std::vector<Vector3d> control = fitter.solve(U, V, uv);
      result.surface = BSplineSurface(p, p, U, V, int(U.size()) - p - 1, int(V.size()) - p - 1, control, frame.origin);
      monitor.report(begin + 0.3 * (end - begin));
      project(result.surface, q, frame.normal, uv, step + 1 == steps ? &deviations : nullptr, monitor.callback(), begin + 0.3 * (end - begin),
              end);
    }
    double worst = 0.0, squares = 0.0;
    for (double d : deviations) worst = std::max(worst, std::abs(d)), squares += d * d;
    result.max_deviation = worst;
    result.rms_deviation = std::sqrt(squares / double(n));
    result.rounds = round;
    if (worst <= result.tolerance) {
      result.stop = BSplineFitStop::ToleranceMet;
      break;
    }
    if (round >= params.max_rounds) {
      result.stop = BSplineFitStop::RoundLimit;
      break;
    }
    // Refinement: midpoints of the spans holding the worst points, the worst spans first.
    const double threshold = std::max(result.tolerance, 0.5 * worst);
    std::vector<double> worst_u(U.size(), 0.0), worst_v(V.size(), 0.0);
    for (std::size_t k = 0; k < n; ++k) {
      const double d = std::abs(deviations[k]);
      if (d < threshold) continue;
      const int iu = bspline_find_span(uv[k].x(), p, U), iv = bspline_find_span(uv[k].y(), p, V);
      worst_u[std::size_t(iu)] = std::max(worst_u[std::size_t(iu)], d);
      worst_v[std::size_t(iv)] = std::max(worst_v[std::size_t(iv)], d);
    }
    struct Candidate {
      double deviation;
      bool in_u;
      double knot;
    };
    std::vector<Candidate> candidates;
    auto collect = [&](const std::vector<double>& knots, const std::vector<double>& worst_in, bool in_u) {
      for (std::size_t s = 0; s + 1 < knots.size(); ++s) {
        const double a = knots[s], b = knots[s + 1];
        if (worst_in[s] > 0.0 && b - a > 1e-9) candidates.push_back({worst_in[s], in_u, 0.5 * (a + b)});
      }
    };
    collect(U, worst_u, true);
    collect(V, worst_v, false);
    std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
      return a.deviation != b.deviation ? a.deviation > b.deviation : (a.in_u != b.in_u ? a.in_u : a.knot < b.knot);
    });
    long nu = long(U.size()) - p - 1, nv = long(V.size()) - p - 1;
    std::vector<double> add_u, add_v;
    for (const Candidate& c : candidates) {
      if ((nu + (c.in_u ? 1 : 0)) * (nv + (c.in_u ? 0 : 1)) > max_control) continue;
      (c.in_u ? add_u : add_v).push_back(c.knot);
      (c.in_u ? nu : nv) += 1;
    }
    if (add_u.empty() && add_v.empty()) {
      result.stop = BSplineFitStop::ControlPointLimit;
      break;
    }
    for (double k : add_u) U.insert(std::upper_bound(U.begin(), U.end(), k), k);
    for (double k : add_v) V.insert(std::upper_bound(V.begin(), V.end(), k), k);
  }
  result.tolerance_met = result.stop == BSplineFitStop::ToleranceMet;
  result.stop_reason = bspline_fit_stop_name(result.stop);
  result.control_points = result.surface.control_points().size();
  result.smoothing = fitter.smoothing_used;
  result.parameters = std::move(uv);
  result.deviations = std::move(deviations);
  monitor.report(1.0);
  return result;
}

}  // namespace pointsurf
