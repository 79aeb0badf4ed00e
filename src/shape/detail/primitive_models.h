// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The primitive models of detect_primitives: distance and normal deviation of a point, the
// candidates of a minimal set of oriented points, and the least-squares refit.
#include <cmath>
#include <cstdint>
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
Residual residual(const Primitive& s, const Eigen::Vector3d& p, const Eigen::Vector3d& n);

/// The candidates of the enabled `types` through the minimal set p[0..count), n[0..count)
/// (count 3, or 4 when tori are enabled: the fourth point serves the torus only), each checked
/// on the points it was built from (within `eps`, normal cosine >= `cos_max`); radii and apex
/// distances beyond `scene` are refused. Replaces `out`.
void make_candidates(const Eigen::Vector3d* p, const Eigen::Vector3d* n, int count, unsigned types, double eps, double cos_max,
                     double scene, std::vector<Primitive>& out);

/// Least-squares refit of `s` to the points `idx` of `pts` / `nrm` (plane: PCA; sphere:
/// algebraic; cylinder: axis from the normals, circle across it; cone: apex from the tangent
/// planes, axis from the unit directions; torus: Gauss-Newton on the geometric distance from
/// `s`). nullopt when degenerate.
std::optional<Primitive> refit(const Primitive& s, const std::vector<Eigen::Vector3d>& pts, const std::vector<Eigen::Vector3d>& nrm,
                               const std::vector<std::uint32_t>& idx);

}  // namespace pointsurf::detail
