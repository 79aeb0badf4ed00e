// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The primitive models of detect_primitives: distance and normal deviation of a point, the
// candidates of a minimal set of oriented points, and the least-squares refit.
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "pointsurf/shape/primitives.h"

namespace pointsurf::detail {

constexpr double kDeg = M_PI / 180.0;

/// Distance to the surface and |cos| of the angle between a normal and the surface normal there.
struct Residual {
  double distance;
  double cosine;
};

/// The distance of `p` to `s` (1-Lipschitz in `p`, so a ball of radius rho around `p` holds no
/// point closer than distance - rho) and the deviation of the normal `n` (unit, sign free).
/// Inline: the scoring loops call it once per point.
inline Residual residual(const Primitive& s, const Eigen::Vector3d& p, const Eigen::Vector3d& n) {
  using Eigen::Vector3d;
  switch (s.type) {
    case PrimitiveType::Plane: return {std::abs(s.axis.dot(p - s.point)), std::abs(s.axis.dot(n))};
    case PrimitiveType::Sphere: {
      const Vector3d v = p - s.point;
      const double l = v.norm();
      return {std::abs(l - s.radius), l > 0.0 ? std::abs(v.dot(n)) / l : 0.0};
    }
    case PrimitiveType::Cylinder: {
      const Vector3d v = p - s.point;
      const Vector3d radial = v - s.axis.dot(v) * s.axis;
      const double r = radial.norm();
      return {std::abs(r - s.radius), r > 0.0 ? std::abs(radial.dot(n)) / r : 0.0};
    }
    case PrimitiveType::Cone: {
      const Vector3d v = p - s.point;
      const double h = s.axis.dot(v);
      const Vector3d radial = v - h * s.axis;
      const double r = radial.norm();
      const double c = std::cos(s.angle_deg * kDeg), sn = std::sin(s.angle_deg * kDeg);
      if (h * c + r * sn < 0.0) return {v.norm(), 0.0};  // behind the apex
      const Vector3d normal = (r > 0.0 ? Vector3d(radial / r) : Vector3d::Zero()) * c - s.axis * sn;
      return {std::abs(r * c - h * sn), std::abs(normal.dot(n))};
    }
    case PrimitiveType::Torus: {
      // Distance to the tube's core circle in the meridian half-plane, less the tube radius.
      const Vector3d v = p - s.point;
      const double h = s.axis.dot(v);
      const Vector3d radial = v - h * s.axis;
      const double r = radial.norm();
      const double dr = r - s.radius, core = std::hypot(dr, h);
      if (!(core > 0.0)) return {s.minor_radius, 0.0};
      const Vector3d normal = (r > 0.0 ? Vector3d(radial * (dr / (r * core))) : Vector3d::Zero()) + s.axis * (h / core);
      return {std::abs(core - s.minor_radius), std::abs(normal.dot(n))};
    }
  }
  return {std::numeric_limits<double>::infinity(), 0.0};
}

/// The candidates of the enabled `types` through the minimal set p[0..count), n[0..count)
/// (count 3, or 4 when tori are enabled: the fourth point serves the torus only), each checked
/// on the points it was built from (within `eps`, normal cosine >= `cos_max`); radii and apex
/// distances beyond `scene` are refused. Replaces `out`.
void make_candidates(const Eigen::Vector3d* p, const Eigen::Vector3d* n, int count, unsigned types, double eps, double cos_max,
                     double scene, std::vector<Primitive>& out);

/// Least-squares refit of `s` to the points `idx` of `pts` / `nrm` (plane: PCA; sphere:
/// algebraic; cylinder: axis from the normals, circle across it; cone: apex from the tangent
/// planes, axis from the unit directions; torus: Levenberg-Marquardt on the geometric distance from
/// `s`). nullopt when degenerate.
std::optional<Primitive> refit(const Primitive& s, const std::vector<Eigen::Vector3d>& pts, const std::vector<Eigen::Vector3d>& nrm,
                               const std::vector<std::uint32_t>& idx);

}  // namespace pointsurf::detail
