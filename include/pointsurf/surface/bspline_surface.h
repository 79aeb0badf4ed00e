// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Tensor-product B-spline surfaces (non-rational): evaluation with derivatives, Boehm knot
// insertion and the closest point by Newton's method (The NURBS Book, Piegl and Tiller 1997,
// algorithms A2.1-A2.3, A3.6/A3.7 and A5.1/A5.3).
//
//   BSplineSurface s(3, 3, U, V, nu, nv, control, origin);  // control[i * nv + j], relative to origin
//   Eigen::Vector3d x = s.point(0.5, 0.25);                  // in the input's coordinates
//   const SurfaceFootPoint c = s.closest(y, 0.5, 0.5);           // foot point of y, started at (0.5, 0.5)
//
// Control points are stored relative to `origin()` so that surfaces in georeferenced
// coordinates (1e6..1e7 m) keep their precision: everything is computed on the small relative
// coordinates and the origin is added last.
#include <array>
#include <cstddef>
#include <span>
#include <vector>

#include <Eigen/Core>

namespace pointsurf {

/// The highest degree the evaluators support (their work arrays are fixed-size).
inline constexpr int kMaxBSplineDegree = 7;

/// The non-zero basis functions N_{span-p..span, p} at one parameter and their first two
/// derivatives: d[k][j] is the k-th derivative of N_{span-p+j, p}.
struct BSplineBasis {
  int span = 0;
  std::array<std::array<double, kMaxBSplineDegree + 1>, 3> d{};
};

/// The knot span index of `u` (A2.1): the i with knots[i] <= u < knots[i+1] and
/// p <= i <= n, where n + 1 = knots.size() - p - 1 is the number of control points; u at or
/// beyond the domain's end gives n, u at or before its start gives p. `knots` is clamped or not,
/// non-decreasing. O(log n).
int bspline_find_span(double u, int p, std::span<const double> knots);

/// The basis functions of degree `p` at `u` and their derivatives up to order `derivatives`
/// (0..2; the rest are left 0), on the span bspline_find_span() gives (A2.2 and A2.3).
/// The functions sum to 1 over the domain (partition of unity). Thread-safe.
BSplineBasis bspline_basis(double u, int p, std::span<const double> knots, int derivatives = 2);

/// The surface and its partial derivatives at (u, v). `point` is in the input's coordinates.
struct SurfaceDerivatives {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d su = Eigen::Vector3d::Zero(), sv = Eigen::Vector3d::Zero();
  Eigen::Vector3d suu = Eigen::Vector3d::Zero(), suv = Eigen::Vector3d::Zero(), svv = Eigen::Vector3d::Zero();
};

/// The closest point of a surface to a query point.
struct SurfaceFootPoint {
  double u = 0.0, v = 0.0;                       // parameters of the foot point (in the domain)
  Eigen::Vector3d point = Eigen::Vector3d::Zero();  // the foot point, input coordinates
  double distance = 0.0;                         // |query - point|, cloud units
  int iterations = 0;                            // Newton iterations, fallback included
  bool converged = false;                        // Newton met its stopping test (a local minimum
                                                 // of the distance, on the border where clamped)
  bool used_fallback = false;                    // Newton from the start failed and a search over
                                                 // the whole domain gave a new start
};

class BSplineSurface {
public:
  /// The empty surface (no control points); evaluating it is an error.
  BSplineSurface() = default;
  /// A surface of degrees p (in u) and q (in v), knot vectors U and V (clamped: the first and
  /// last knot repeated degree + 1 times, non-decreasing), nu x nv control points, control[i * nv
  /// + j] the point of index i in u and j in v, relative to `origin`. Throws UsageError when a
  /// degree is outside [1, kMaxBSplineDegree], a knot vector is not clamped, decreasing, or of
  /// the wrong length (nu + p + 1, nv + q + 1), or the control net's size differs from nu * nv.
  BSplineSurface(int p, int q, std::vector<double> U, std::vector<double> V, int nu, int nv, std::vector<Eigen::Vector3d> control,
                 const Eigen::Vector3d& origin = Eigen::Vector3d::Zero());

  int degree_u() const noexcept { return p_; }
  int degree_v() const noexcept { return q_; }
  const std::vector<double>& knots_u() const noexcept { return U_; }
  const std::vector<double>& knots_v() const noexcept { return V_; }
  int count_u() const noexcept { return nu_; }  // control points in u
  int count_v() const noexcept { return nv_; }  // control points in v
  bool empty() const noexcept { return control_.empty(); }
  /// Control point (i, j) relative to origin(); control_points()[i * count_v() + j].
  const Eigen::Vector3d& control(int i, int j) const { return control_[std::size_t(i) * std::size_t(nv_) + std::size_t(j)]; }
  const std::vector<Eigen::Vector3d>& control_points() const noexcept { return control_; }
  const Eigen::Vector3d& origin() const noexcept { return origin_; }
  /// The parameter domain [u_min, u_max] x [v_min, v_max].
  double u_min() const { return U_[std::size_t(p_)]; }
  double u_max() const { return U_[U_.size() - std::size_t(p_) - 1]; }
  double v_min() const { return V_[std::size_t(q_)]; }
  double v_max() const { return V_[V_.size() - std::size_t(q_) - 1]; }

  /// S(u, v) in the input's coordinates; (u, v) outside the domain is clamped to it.
  Eigen::Vector3d point(double u, double v) const;
  /// S(u, v) relative to origin() (full precision far from the coordinate origin).
  Eigen::Vector3d local_point(double u, double v) const;
  /// S and its first and second partial derivatives (A3.6 with the basis derivatives of A2.3).
  SurfaceDerivatives derivatives(double u, double v) const;
  /// The unit normal Su x Sv / |Su x Sv|; zero where the surface is degenerate (Su || Sv).
  Eigen::Vector3d normal(double u, double v) const;

  /// Inserts the knot u (strictly inside the u-domain) once by Boehm's algorithm (A5.1 applied
  /// to each column of the net, A5.3): one more control point in u, the surface unchanged.
  /// Throws UsageError when u is outside the open domain or its multiplicity would exceed the
  /// degree.
  void insert_knot_u(double u);
  /// The same in v.
  void insert_knot_v(double v);

  /// The point of the surface closest to x, by Newton's method on the squared distance from
  /// (u0, v0), steps clamped to the domain with a backtracking line search (the distance never
  /// grows). When Newton fails (no convergence in `max_iterations`), the best point of a grid
  /// of 4 x 4 samples per knot span (at most 64 x 64 in all) is a second start, and the closer
  /// answer is returned.
  /// `tolerance` is the step in parameter space (relative to the domain's size) below which
  /// Newton stops. Thread-safe (const).
  SurfaceFootPoint closest(const Eigen::Vector3d& x, double u0, double v0, int max_iterations = 30, double tolerance = 1e-12) const;
  /// The same relative to origin(): `x_local` = x - origin(); the point returned is relative too.
  SurfaceFootPoint closest_local(const Eigen::Vector3d& x_local, double u0, double v0, int max_iterations = 30, double tolerance = 1e-12) const;

private:
  // Derivatives relative to the origin, up to order `order` (0: the point only).
  SurfaceDerivatives local_derivatives(double u, double v, int order) const;
  SurfaceFootPoint newton(const Eigen::Vector3d& x, double u0, double v0, int max_iterations, double tolerance) const;
  void insert_knot(bool along_u, double t);

  int p_ = 0, q_ = 0, nu_ = 0, nv_ = 0;
  std::vector<double> U_, V_;
  std::vector<Eigen::Vector3d> control_;
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
};

}  // namespace pointsurf
