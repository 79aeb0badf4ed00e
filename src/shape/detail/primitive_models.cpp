// SPDX-License-Identifier: GPL-3.0-or-later
#include "shape/detail/primitive_models.h"

#include <algorithm>
#include <limits>

#include <Eigen/Dense>

#include "core/detail/plane_fit.h"

namespace pointsurf::detail {
namespace {

using Eigen::Vector3d;

Vector3d any_orthogonal(const Vector3d& a) {
  return (std::abs(a.x()) < 0.9 ? Vector3d::UnitX() : Vector3d::UnitY()).cross(a).normalized();
}

// Midpoint of the shortest segment between lines p + t u and q + s v; nullopt when parallel.
std::optional<Vector3d> closest_midpoint(const Vector3d& p, const Vector3d& u, const Vector3d& q, const Vector3d& v) {
  const Vector3d w = p - q;
  const double a = u.dot(u), b = u.dot(v), c = v.dot(v), d = u.dot(w), e = v.dot(w);
  const double den = a * c - b * b;
  if (!(den > 1e-6 * a * c)) return std::nullopt;
  const double t = (b * e - c * d) / den, s = (a * e - b * d) / den;
  return 0.5 * (p + t * u + q + s * v);
}

// Tori through 4 oriented points. Every normal line of a torus meets its axis, so the axis is a
// common transversal of the 4 normal lines: in Pluecker coordinates (d, m) it satisfies
// d . m_i + n_i . m = 0 for each line (n_i, m_i = p_i x n_i), a 2-dimensional null space on
// which d . m = 0 leaves up to two lines. Across each axis the tube's core circle centre is the
// least-squares meeting point of the normal lines in the meridian half-plane (r, h).
// Concurrent (sphere) or parallel (plane) normal lines leave a larger null space: refused.
template <class Fits>
void torus_candidates(const Vector3d* p, const Vector3d* n, double scene, std::vector<Primitive>& out, const Fits& fits) {
  double reach = 0.0;
  for (int i = 1; i < 4; ++i) reach = std::max(reach, (p[i] - p[0]).norm());
  if (!(reach > 0.0)) return;
  Eigen::Matrix<double, 4, 6> lines;
  for (int i = 0; i < 4; ++i) lines.row(i) << ((p[i] - p[0]).cross(n[i]) / reach).transpose(), n[i].transpose();
  const Eigen::JacobiSVD<Eigen::Matrix<double, 4, 6>> svd(lines, Eigen::ComputeFullV);
  if (!(svd.singularValues()[3] > 1e-3 * svd.singularValues()[0])) return;
  const Eigen::Matrix<double, 6, 1> x1 = svd.matrixV().col(4), x2 = svd.matrixV().col(5);
  // (x1 cos t + x2 sin t) on the Klein quadric: A cos^2 + B cos sin + C sin^2 = 0.
  const double a = x1.head<3>().dot(x1.tail<3>()), b = x1.head<3>().dot(x2.tail<3>()) + x2.head<3>().dot(x1.tail<3>()),
               c = x2.head<3>().dot(x2.tail<3>());
  const double disc = b * b - 4.0 * a * c;
  if (disc < 0.0) return;
  double angles[2];
  int roots = 0;
  const double q = -0.5 * (b + std::copysign(std::sqrt(disc), b));  // stable roots of a + b u + c u^2 in u = tan t
  if (q != 0.0) angles[roots++] = std::atan(a / q);
  if (c != 0.0) angles[roots++] = std::atan(q / c);
  else angles[roots++] = 0.5 * M_PI;
  for (int k = 0; k < roots; ++k) {
    const Eigen::Matrix<double, 6, 1> x = std::cos(angles[k]) * x1 + std::sin(angles[k]) * x2;
    const Vector3d d = x.head<3>(), m = x.tail<3>() * reach;
    if (!(d.norm() > 1e-9)) continue;
    const Vector3d axis = d.normalized();
    const Vector3d foot = p[0] + d.cross(m) / d.squaredNorm();
    // Core circle centre (R, h0) in the half-plane: least-squares meeting point of the normals.
    Eigen::Matrix2d ata = Eigen::Matrix2d::Zero();
    Eigen::Vector2d atb = Eigen::Vector2d::Zero();
    Eigen::Vector2d q2[4];
    bool ok = true;
    for (int i = 0; i < 4 && ok; ++i) {
      const Vector3d v = p[i] - foot;
      const double h = axis.dot(v);
      const Vector3d radial = v - h * axis;
      const double r = radial.norm();
      Eigen::Vector2d t(n[i].dot(radial) / std::max(r, 1e-300), n[i].dot(axis));
      ok = r > 0.0 && t.norm() > 0.5;
      t.normalize();
      q2[i] = Eigen::Vector2d(r, h);
      const Eigen::Matrix2d proj = Eigen::Matrix2d::Identity() - t * t.transpose();
      ata += proj;
      atb += proj * q2[i];
    }
    if (!ok || !(std::abs(ata.determinant()) > 1e-6)) continue;
    const Eigen::Vector2d core = ata.inverse() * atb;
    double minor = 0.0;
    for (const Eigen::Vector2d& y : q2) minor += (y - core).norm() / 4.0;
    Primitive s;
    s.type = PrimitiveType::Torus;
    s.point = foot + core.y() * axis;
    s.axis = axis;
    s.radius = core.x();
    s.minor_radius = minor;
    if (s.radius > 0.0 && s.radius < scene && minor > 0.0 && minor < scene && fits(s)) out.push_back(s);
  }
}

// Levenberg-Marquardt on the geometric distance: centre (3), axis (2, tangent to the sphere of
// directions), major and minor radius.
std::optional<Primitive> refit_torus(const Primitive& s, const std::vector<Vector3d>& pts, const std::vector<std::uint32_t>& idx) {
  using Vector7d = Eigen::Matrix<double, 7, 1>;
  auto cost = [&](const Primitive& t) {
    double sum = 0.0;
    for (std::uint32_t i : idx) {
      const double d = residual(t, pts[i], Vector3d::Zero()).distance;
      sum += d * d;
    }
    return sum;
  };
  Primitive f = s;
  double current = cost(f), lambda = 1e-3;
  for (int iteration = 0; iteration < 30; ++iteration) {
    const Vector3d u = any_orthogonal(f.axis), w = f.axis.cross(u);
    Eigen::Matrix<double, 7, 7> jtj = Eigen::Matrix<double, 7, 7>::Zero();
    Vector7d jtr = Vector7d::Zero();
    for (std::uint32_t i : idx) {
      const Vector3d v = pts[i] - f.point;
      const double h = f.axis.dot(v);
      const Vector3d radial = v - h * f.axis;
      const double r = radial.norm(), dr = r - f.radius, core = std::hypot(dr, h);
      if (!(r > 0.0 && core > 0.0)) continue;
      const Vector3d normal = radial * (dr / (r * core)) + f.axis * (h / core);
      const Vector3d tilt = v * (h * f.radius / (r * core));
      Vector7d g;
      g << -normal, tilt.dot(u), tilt.dot(w), -dr / core, -1.0;
      jtj.noalias() += g * g.transpose();
      jtr += g * (core - f.minor_radius);
    }
    bool improved = false;
    for (int attempt = 0; attempt < 8 && !improved; ++attempt) {
      Eigen::Matrix<double, 7, 7> damped = jtj;
      damped.diagonal() *= 1.0 + lambda;
      const Vector7d step = damped.ldlt().solve(-jtr);
      if (!step.allFinite()) return std::nullopt;
      Primitive t = f;
      t.point += step.head<3>();
      t.axis = (f.axis + step[3] * u + step[4] * w).normalized();
      t.radius += step[5];
      t.minor_radius += step[6];
      const double next = t.radius > 0.0 && t.minor_radius > 0.0 ? cost(t) : std::numeric_limits<double>::infinity();
      if (next < current) {
        improved = true;
        const double gain = current - next;
        f = t;
        current = next;
        lambda = std::max(lambda * 0.1, 1e-9);
        if (gain < 1e-12 * (current + 1e-300)) return f;
      } else {
        lambda *= 10.0;
      }
    }
    if (!improved) break;
  }
  return f;
}

}  // namespace

void make_candidates(const Vector3d* p, const Vector3d* n, int count, unsigned types, double eps, double cos_max, double scene,
                     std::vector<Primitive>& out) {
  out.clear();
  auto fits = [&](const Primitive& s, int points = 3) {
    for (int i = 0; i < points; ++i) {
      const Residual r = residual(s, p[i], n[i]);
      if (!(r.distance <= eps && r.cosine >= cos_max)) return false;
    }
    return true;
  };
  if (types & kPlanes) {
    Vector3d normal = (p[1] - p[0]).cross(p[2] - p[0]);
    if (normal.norm() > 1e-12) {
      Primitive s;
      s.type = PrimitiveType::Plane;
      s.axis = normal.normalized();
      s.point = p[0];
      if (fits(s)) out.push_back(s);
    }
  }
  if (types & kSpheres) {
    if (const auto c = closest_midpoint(p[0], n[0], p[1], n[1])) {
      Primitive s;
      s.type = PrimitiveType::Sphere;
      s.point = *c;
      s.radius = 0.5 * ((p[0] - *c).norm() + (p[1] - *c).norm());
      if (s.radius < scene && fits(s)) out.push_back(s);
    }
  }
  if (types & kCylinders) {
    const Vector3d a = n[0].cross(n[1]);
    if (a.norm() > 0.05) {
      Primitive s;
      s.type = PrimitiveType::Cylinder;
      s.axis = a.normalized();
      auto flat = [&](const Vector3d& x) { return Vector3d(x - s.axis.dot(x) * s.axis); };
      if (const auto c = closest_midpoint(flat(p[0]), flat(n[0]), flat(p[1]), flat(n[1]))) {
        s.point = *c;
        s.radius = 0.5 * (residual({PrimitiveType::Cylinder, *c, s.axis, 0.0}, p[0], n[0]).distance +
                          residual({PrimitiveType::Cylinder, *c, s.axis, 0.0}, p[1], n[1]).distance);
        if (s.radius < scene && fits(s)) out.push_back(s);
      }
    }
  }
  if (types & kCones) {
    Eigen::Matrix3d m;
    Vector3d b;
    for (int i = 0; i < 3; ++i) m.row(i) = n[i].transpose(), b[i] = n[i].dot(p[i]);
    if (std::abs(m.determinant()) > 1e-3) {
      const Vector3d apex = m.partialPivLu().solve(b);
      Vector3d u[3];
      bool ok = apex.allFinite();
      for (int i = 0; i < 3 && ok; ++i) {
        const double l = (p[i] - apex).norm();
        ok = l > 0.0;
        if (ok) u[i] = (p[i] - apex) / l;
      }
      if (ok && (apex - p[0]).norm() < scene) {
        Vector3d a = (u[1] - u[0]).cross(u[2] - u[0]);
        if (a.norm() > 1e-9) {
          a.normalize();
          if (a.dot(u[0] + u[1] + u[2]) < 0.0) a = -a;
          double angle = 0.0;
          for (const Vector3d& x : u) angle += std::acos(std::clamp(a.dot(x), -1.0, 1.0)) / 3.0;
          Primitive s;
          s.type = PrimitiveType::Cone;
          s.point = apex;
          s.axis = a;
          s.angle_deg = angle / kDeg;
          if (s.angle_deg > 3.0 && s.angle_deg < 80.0 && fits(s)) out.push_back(s);
        }
      }
    }
  }
  if ((types & kTori) && count >= 4) torus_candidates(p, n, scene, out, [&](const Primitive& s) { return fits(s, 4); });
}

std::optional<Primitive> refit(const Primitive& s, const std::vector<Vector3d>& pts, const std::vector<Vector3d>& nrm,
                               const std::vector<std::uint32_t>& idx) {
  if (idx.size() < 6) return std::nullopt;
  Vector3d mean = Vector3d::Zero();
  for (std::uint32_t i : idx) mean += pts[i];
  mean /= double(idx.size());
  Primitive f = s;
  switch (s.type) {
    case PrimitiveType::Plane: {
      detail::PlaneMoments m;
      for (std::uint32_t i : idx) m.add(pts[i] - mean);
      const auto plane = detail::fit_plane(m, 0.0, std::numeric_limits<double>::infinity());
      if (!plane) return std::nullopt;
      f.axis = plane->normal;
      f.point = mean;
      return f;
    }
    case PrimitiveType::Sphere: {
      // |x|^2 = 2 c.x + k, linear in (c, k); coordinates relative to the mean for conditioning.
      Eigen::Matrix4d ata = Eigen::Matrix4d::Zero();
      Eigen::Vector4d atb = Eigen::Vector4d::Zero();
      for (std::uint32_t i : idx) {
        const Vector3d x = pts[i] - mean;
        const Eigen::Vector4d row(2 * x.x(), 2 * x.y(), 2 * x.z(), 1.0);
        ata.noalias() += row * row.transpose();
        atb += row * x.squaredNorm();
      }
      const Eigen::Vector4d sol = ata.ldlt().solve(atb);
      const Vector3d c = sol.head<3>();
      const double r2 = sol[3] + c.squaredNorm();
      if (!(r2 > 0.0) || !sol.allFinite()) return std::nullopt;
      f.point = mean + c;
      f.radius = std::sqrt(r2);
      return f;
    }
    case PrimitiveType::Cylinder: {
      // The axis is the direction the normals are all orthogonal to; then a circle across it.
      Eigen::Matrix3d nn = Eigen::Matrix3d::Zero();
      for (std::uint32_t i : idx) nn.noalias() += nrm[i] * nrm[i].transpose();
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(nn);
      Vector3d a = eigen.eigenvectors().col(0).normalized();
      if (a.dot(s.axis) < 0.0) a = -a;
      const Vector3d u = any_orthogonal(a), v = a.cross(u);
      Eigen::Matrix3d ata = Eigen::Matrix3d::Zero();
      Vector3d atb = Vector3d::Zero();
      for (std::uint32_t i : idx) {
        const Vector3d x = pts[i] - mean;
        const double px = u.dot(x), py = v.dot(x);
        const Vector3d row(2 * px, 2 * py, 1.0);
        ata.noalias() += row * row.transpose();
        atb += row * (px * px + py * py);
      }
      const Vector3d sol = ata.ldlt().solve(atb);
      const double r2 = sol[2] + sol[0] * sol[0] + sol[1] * sol[1];
      if (!(r2 > 0.0) || !sol.allFinite()) return std::nullopt;
      f.axis = a;
      f.point = mean + sol[0] * u + sol[1] * v;
      f.radius = std::sqrt(r2);
      return f;
    }
    case PrimitiveType::Cone: {
      // The apex lies on every tangent plane: sum n n^T x = sum n n^T p.
      Eigen::Matrix3d nn = Eigen::Matrix3d::Zero();
      Vector3d nb = Vector3d::Zero();
      for (std::uint32_t i : idx) {
        const Eigen::Matrix3d o = nrm[i] * nrm[i].transpose();
        nn += o;
        nb += o * (pts[i] - mean);
      }
      const Vector3d apex = mean + nn.ldlt().solve(nb);
      if (!apex.allFinite()) return std::nullopt;
      // The unit directions from the apex lie on a circle around the axis.
      Vector3d um = Vector3d::Zero();
      Eigen::Matrix3d uu = Eigen::Matrix3d::Zero();
      std::size_t count = 0;
      for (std::uint32_t i : idx) {
        const Vector3d d = pts[i] - apex;
        const double l = d.norm();
        if (!(l > 0.0)) continue;
        um += d / l;
        uu.noalias() += (d / l) * (d / l).transpose();
        ++count;
      }
      if (count < 6) return std::nullopt;
      um /= double(count);
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(uu / double(count) - um * um.transpose());
      Vector3d a = eigen.eigenvectors().col(0).normalized();
      if (a.dot(um) < 0.0) a = -a;
      const double angle = std::acos(std::clamp(a.dot(um), -1.0, 1.0)) / kDeg;
      if (!(angle > 1.0 && angle < 89.0)) return std::nullopt;
      f.point = apex;
      f.axis = a;
      f.angle_deg = angle;
      return f;
    }
    case PrimitiveType::Torus: return refit_torus(s, pts, idx);
  }
  return std::nullopt;
}


}  // namespace pointsurf::detail
