// SPDX-License-Identifier: GPL-3.0-or-later
// Tensor-product B-spline surfaces: basis functions, evaluation, knot insertion and the closest
// point (surface/bspline_surface.h). The algorithms follow The NURBS Book (Piegl and Tiller).
#include "pointsurf/surface/bspline_surface.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include <Eigen/Geometry>
#include <fmt/format.h>

#include "pointsurf/core/error.h"

namespace pointsurf {
namespace {

using Eigen::Vector3d;

void check_knots(const std::vector<double>& knots, int degree, int count, char direction) {
  if (degree < 1 || degree > kMaxBSplineDegree)
    throw UsageError(fmt::format("BSplineSurface: degree in {} must be in [1, {}], got {}", direction, kMaxBSplineDegree, degree));
  if (count < degree + 1)
    throw UsageError(fmt::format("BSplineSurface: {} control points in {} is fewer than degree + 1 = {}", count, direction, degree + 1));
  if (knots.size() != std::size_t(count + degree + 1))
    throw UsageError(fmt::format("BSplineSurface: knot vector in {} has {} knots, expected {} control points + degree + 1 = {}", direction,
                                 knots.size(), count, count + degree + 1));
  for (std::size_t i = 0; i < knots.size(); ++i) {
    if (!std::isfinite(knots[i])) throw UsageError(fmt::format("BSplineSurface: knot {} in {} is not finite", i, direction));
    if (i > 0 && knots[i] < knots[i - 1]) throw UsageError(fmt::format("BSplineSurface: knots in {} decrease at index {}", direction, i));
  }
  const std::size_t m = knots.size() - 1;
  for (int i = 1; i <= degree; ++i) {
    if (knots[std::size_t(i)] != knots[0] || knots[m - std::size_t(i)] != knots[m])
      throw UsageError(fmt::format("BSplineSurface: knot vector in {} is not clamped (first and last knot repeated degree + 1 = {} times)",
                                   direction, degree + 1));
  }
  if (!(knots[m] > knots[0])) throw UsageError(fmt::format("BSplineSurface: the domain in {} is empty", direction));
}

int multiplicity(const std::vector<double>& knots, double u) {
  return int(std::count(knots.begin(), knots.end(), u));
}

}  // namespace

int bspline_find_span(double u, int p, std::span<const double> knots) {
  const int n = int(knots.size()) - p - 2;  // index of the last control point
  if (u >= knots[std::size_t(n + 1)]) return n;
  if (u <= knots[std::size_t(p)]) {
    // The first non-empty span (a knot vector that is not clamped may repeat its start).
    int i = p;
    while (i < n && knots[std::size_t(i + 1)] <= u) ++i;
    return i;
  }
  // u in (knots[p], knots[n+1]): the last i with knots[i] <= u (upper_bound - 1).
  const auto it = std::upper_bound(knots.begin() + p, knots.begin() + n + 1, u);
  return int(it - knots.begin()) - 1;
}

BSplineBasis bspline_basis(double u, int p, std::span<const double> U, int derivatives) {
  BSplineBasis out;
  const int i = bspline_find_span(u, p, U);
  out.span = i;
  const int nd = std::min(std::max(derivatives, 0), std::min(2, p));
  constexpr int M = kMaxBSplineDegree + 1;
  // A2.3: ndu holds the basis functions (upper triangle) and the knot differences (lower).
  double ndu[M][M];
  double left[M], right[M];
  ndu[0][0] = 1.0;
  for (int j = 1; j <= p; ++j) {
    left[j] = u - U[std::size_t(i + 1 - j)];
    right[j] = U[std::size_t(i + j)] - u;
    double saved = 0.0;
    for (int r = 0; r < j; ++r) {
      ndu[j][r] = right[r + 1] + left[j - r];
      const double temp = ndu[r][j - 1] / ndu[j][r];
      ndu[r][j] = saved + right[r + 1] * temp;
      saved = left[j - r] * temp;
    }
    ndu[j][j] = saved;
  }
  for (int j = 0; j <= p; ++j) out.d[0][std::size_t(j)] = ndu[j][p];
  double a[2][M];
  for (int r = 0; r <= p; ++r) {
    int s1 = 0, s2 = 1;
    a[0][0] = 1.0;
    for (int k = 1; k <= nd; ++k) {
      double d = 0.0;
      const int rk = r - k, pk = p - k;
      if (r >= k) {
        a[s2][0] = a[s1][0] / ndu[pk + 1][rk];
        d = a[s2][0] * ndu[rk][pk];
      }
      const int j1 = rk >= -1 ? 1 : -rk;
      const int j2 = r - 1 <= pk ? k - 1 : p - r;
      for (int j = j1; j <= j2; ++j) {
        a[s2][j] = (a[s1][j] - a[s1][j - 1]) / ndu[pk + 1][rk + j];
        d += a[s2][j] * ndu[rk + j][pk];
      }
      if (r <= pk) {
        a[s2][k] = -a[s1][k - 1] / ndu[pk + 1][r];
        d += a[s2][k] * ndu[r][pk];
      }
      out.d[std::size_t(k)][std::size_t(r)] = d;
      std::swap(s1, s2);
    }
  }
  double factor = p;
  for (int k = 1; k <= nd; ++k) {
    for (int j = 0; j <= p; ++j) out.d[std::size_t(k)][std::size_t(j)] *= factor;
    factor *= p - k;
  }
  return out;
}

BSplineSurface::BSplineSurface(int p, int q, std::vector<double> U, std::vector<double> V, int nu, int nv, std::vector<Vector3d> control,
                               const Vector3d& origin)
    : p_(p), q_(q), nu_(nu), nv_(nv), U_(std::move(U)), V_(std::move(V)), control_(std::move(control)), origin_(origin) {
  check_knots(U_, p_, nu_, 'u');
  check_knots(V_, q_, nv_, 'v');
  if (control_.size() != std::size_t(nu_) * std::size_t(nv_))
    throw UsageError(fmt::format("BSplineSurface: {} control points given, expected {} x {} = {}", control_.size(), nu_, nv_,
                                 std::size_t(nu_) * std::size_t(nv_)));
  for (std::size_t k = 0; k < control_.size(); ++k)
    if (!control_[k].allFinite()) throw UsageError(fmt::format("BSplineSurface: control point {} is not finite", k));
  if (!origin_.allFinite()) throw UsageError("BSplineSurface: the origin is not finite");
}

SurfaceDerivatives BSplineSurface::local_derivatives(double u, double v, int order) const {
  if (empty()) throw UsageError("BSplineSurface: evaluating an empty surface");
  u = std::clamp(u, u_min(), u_max());
  v = std::clamp(v, v_min(), v_max());
  const BSplineBasis bu = bspline_basis(u, p_, U_, order);
  const BSplineBasis bv = bspline_basis(v, q_, V_, order);
  SurfaceDerivatives s;
  // A3.6: first along v for each row of the net, then along u.
  for (int a = 0; a <= p_; ++a) {
    Vector3d t0 = Vector3d::Zero(), t1 = Vector3d::Zero(), t2 = Vector3d::Zero();
    const int i = bu.span - p_ + a;
    for (int b = 0; b <= q_; ++b) {
      const Vector3d& c = control(i, bv.span - q_ + b);
      t0 += bv.d[0][std::size_t(b)] * c;
      if (order >= 1) t1 += bv.d[1][std::size_t(b)] * c;
      if (order >= 2) t2 += bv.d[2][std::size_t(b)] * c;
    }
    const std::size_t sa = std::size_t(a);
    s.point += bu.d[0][sa] * t0;
    if (order >= 1) {
      s.su += bu.d[1][sa] * t0;
      s.sv += bu.d[0][sa] * t1;
    }
    if (order >= 2) {
      s.suu += bu.d[2][sa] * t0;
      s.suv += bu.d[1][sa] * t1;
      s.svv += bu.d[0][sa] * t2;
    }
  }
  return s;
}

Vector3d BSplineSurface::local_point(double u, double v) const { return local_derivatives(u, v, 0).point; }

Vector3d BSplineSurface::point(double u, double v) const { return origin_ + local_point(u, v); }

SurfaceDerivatives BSplineSurface::derivatives(double u, double v) const {
  SurfaceDerivatives s = local_derivatives(u, v, 2);
  s.point += origin_;
  return s;
}

Vector3d BSplineSurface::normal(double u, double v) const {
  const SurfaceDerivatives s = local_derivatives(u, v, 1);
  const Vector3d n = s.su.cross(s.sv);
  const double len = n.norm();
  return len > 0.0 ? Vector3d(n / len) : Vector3d::Zero();
}

void BSplineSurface::insert_knot_u(double u) { insert_knot(true, u); }
void BSplineSurface::insert_knot_v(double v) { insert_knot(false, v); }

// Boehm's insertion (NURBS Book A5.1) along u or v: each row of the net across that direction
// gets one more control point; the surface is unchanged.
void BSplineSurface::insert_knot(bool along_u, double t) {
  const char* name = along_u ? "BSplineSurface::insert_knot_u" : "BSplineSurface::insert_knot_v";
  if (empty()) throw UsageError(fmt::format("{}: the surface is empty", name));
  std::vector<double>& knots = along_u ? U_ : V_;
  const int degree = along_u ? p_ : q_;
  const double lo = along_u ? u_min() : v_min(), hi = along_u ? u_max() : v_max();
  if (!(t > lo && t < hi)) throw UsageError(fmt::format("{}: {} is not inside the domain ({}, {})", name, t, lo, hi));
  const int s = multiplicity(knots, t);
  if (s + 1 > degree) throw UsageError(fmt::format("{}: knot {} already has multiplicity {} (degree {})", name, t, s, degree));
  const int k = bspline_find_span(t, degree, knots);
  const int nu1 = along_u ? nu_ + 1 : nu_, nv1 = along_u ? nv_ : nv_ + 1;
  const int along = along_u ? nu_ : nv_, across = along_u ? nv_ : nu_;
  std::vector<Vector3d> next(std::size_t(nu1) * std::size_t(nv1));
  // Control point `i` along the direction of insertion in row `r` across it, in the old and new nets.
  const auto old_at = [&](int i, int r) -> const Vector3d& { return along_u ? control(i, r) : control(r, i); };
  const auto new_at = [&](int i, int r) -> Vector3d& {
    return along_u ? next[std::size_t(i) * std::size_t(nv1) + std::size_t(r)] : next[std::size_t(r) * std::size_t(nv1) + std::size_t(i)];
  };
  for (int r = 0; r < across; ++r) {
    for (int i = 0; i <= k - degree; ++i) new_at(i, r) = old_at(i, r);
    for (int i = k - s; i < along; ++i) new_at(i + 1, r) = old_at(i, r);
    for (int i = k - degree + 1; i <= k - s; ++i) {
      const double alpha = (t - knots[std::size_t(i)]) / (knots[std::size_t(i + degree)] - knots[std::size_t(i)]);
      new_at(i, r) = alpha * old_at(i, r) + (1.0 - alpha) * old_at(i - 1, r);
    }
  }
  knots.insert(knots.begin() + k + 1, t);
  control_ = std::move(next);
  nu_ = nu1;
  nv_ = nv1;
}

SurfaceFootPoint BSplineSurface::newton(const Vector3d& x, double u, double v, int max_iterations, double tolerance) const {
  const double u0 = u_min(), u1 = u_max(), v0 = v_min(), v1 = v_max();
  const double step_limit_u = tolerance * (u1 - u0), step_limit_v = tolerance * (v1 - v0);
  u = std::clamp(u, u0, u1);
  v = std::clamp(v, v0, v1);
  SurfaceFootPoint out;
  SurfaceDerivatives s = local_derivatives(u, v, 2);
  Vector3d r = s.point - x;
  double f = r.squaredNorm();
  for (int it = 0; it < max_iterations; ++it) {
    out.iterations = it + 1;
    const double gu = s.su.dot(r), gv = s.sv.dot(r);
    const double huu = s.su.squaredNorm() + s.suu.dot(r), huv = s.su.dot(s.sv) + s.suv.dot(r), hvv = s.sv.squaredNorm() + s.svv.dot(r);
    // Coordinates on a border whose gradient points out of the domain stay fixed (active set).
    const bool fix_u = (u <= u0 && gu > 0.0) || (u >= u1 && gu < 0.0);
    const bool fix_v = (v <= v0 && gv > 0.0) || (v >= v1 && gv < 0.0);
    double du = 0.0, dv = 0.0;
    if (fix_u && fix_v) {
      out.converged = true;
      break;
    }
    // Newton where the Hessian is positive definite, else Gauss-Newton (first-order terms only).
    const double gnu = s.su.squaredNorm(), gnv = s.sv.squaredNorm(), gnuv = s.su.dot(s.sv);
    if (fix_u) {
      dv = -gv / (hvv > 0.0 ? hvv : std::max(gnv, std::numeric_limits<double>::min()));
    } else if (fix_v) {
      du = -gu / (huu > 0.0 ? huu : std::max(gnu, std::numeric_limits<double>::min()));
    } else {
      double a = huu, b = huv, c = hvv;
      double det = a * c - b * b;
      if (!(a > 0.0 && det > 1e-14 * a * c)) {
        a = gnu, b = gnuv, c = gnv;
        det = a * c - b * b;
      }
      if (!(det > 0.0)) break;  // degenerate surface at this point: Newton fails
      du = -(c * gu - b * gv) / det;
      dv = -(a * gv - b * gu) / det;
    }
    // Backtracking: the distance never grows.
    double t = 1.0;
    bool moved = false;
    double nu = u, nv = v;
    SurfaceDerivatives ns;
    for (int k = 0; k < 30; ++k, t *= 0.5) {
      nu = std::clamp(u + t * du, u0, u1);
      nv = std::clamp(v + t * dv, v0, v1);
      ns = local_derivatives(nu, nv, 2);
      const Vector3d nr = ns.point - x;
      const double nf = nr.squaredNorm();
      if (nf <= f) {
        moved = true;
        r = nr;
        f = nf;
        break;
      }
    }
    if (!moved) {
      // No decrease along a descent direction: the distance is minimal to rounding.
      out.converged = true;
      break;
    }
    const double step_u = std::abs(nu - u), step_v = std::abs(nv - v);
    u = nu;
    v = nv;
    s = ns;
    if (!std::isfinite(u) || !std::isfinite(v)) break;
    if (step_u <= step_limit_u && step_v <= step_limit_v) {
      out.converged = true;
      break;
    }
  }
  out.u = u;
  out.v = v;
  out.point = s.point;
  out.distance = std::sqrt(f);
  return out;
}

SurfaceFootPoint BSplineSurface::closest_local(const Vector3d& x, double u0, double v0, int max_iterations, double tolerance) const {
  if (empty()) throw UsageError("BSplineSurface::closest: the surface is empty");
  SurfaceFootPoint best = newton(x, u0, v0, max_iterations, tolerance);
  if (best.converged) return best;
  // Fallback: the best of a grid of samples as a new start: 4 per knot span and direction, at
  // most 64 per direction (bounded work on a fine net).
  auto samples = [](const std::vector<double>& knots, int degree) {
    int spans = 0;
    for (std::size_t i = std::size_t(degree); i + std::size_t(degree) + 1 < knots.size(); ++i) spans += knots[i + 1] > knots[i] ? 1 : 0;
    std::vector<double> out;
    const double lo = knots[std::size_t(degree)], hi = knots[knots.size() - std::size_t(degree) - 1];
    if (spans <= 16) {
      for (std::size_t i = std::size_t(degree); i + std::size_t(degree) + 1 < knots.size(); ++i) {
        if (!(knots[i + 1] > knots[i])) continue;
        for (int k = 0; k < 4; ++k) out.push_back(knots[i] + (knots[i + 1] - knots[i]) * (k + 0.5) / 4.0);
      }
    } else {
      for (int k = 0; k < 64; ++k) out.push_back(lo + (hi - lo) * (k + 0.5) / 64.0);
    }
    return out;
  };
  const std::vector<double> us = samples(U_, p_), vs = samples(V_, q_);
  double su = u0, sv = v0, sd = std::numeric_limits<double>::infinity();
  for (double u : us)
    for (double v : vs) {
      const double d = (local_point(u, v) - x).squaredNorm();
      if (d < sd) sd = d, su = u, sv = v;
    }
  SurfaceFootPoint second = newton(x, su, sv, max_iterations, tolerance);
  second.used_fallback = true;
  second.iterations += best.iterations;
  if (second.distance <= best.distance || !std::isfinite(best.distance)) return second;
  best.used_fallback = true;
  best.iterations = second.iterations;
  return best;
}

SurfaceFootPoint BSplineSurface::closest(const Vector3d& x, double u0, double v0, int max_iterations, double tolerance) const {
  SurfaceFootPoint c = closest_local(x - origin_, u0, v0, max_iterations, tolerance);
  c.point += origin_;
  return c;
}

}  // namespace pointsurf
