// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/shape/primitives.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <unordered_map>
#include <vector>

#include <Eigen/Dense>
#include <fmt/format.h>

#include "core/detail/plane_fit.h"
#include "core/detail/progress_reporter.h"
#include "pointsurf/core/error.h"
#include "pointsurf/spatial/kd_tree.h"
#include "spatial/detail/morton.h"

namespace pointsurf {
namespace {

using Eigen::Vector3d;
constexpr double kDeg = M_PI / 180.0;
constexpr int kMortonBits = 21;         // per axis
constexpr std::size_t kSmallestSubset = 500;  // points in the first scoring subset, about
constexpr std::size_t kBatch = 20;      // minimal sets drawn between extraction tests
constexpr std::size_t kMaxDraws = 400000;  // per extraction: a cap that ends hopeless searches
constexpr int kMaxFailures = 2000;      // extractions in a row that fall below min_points (a cap)

struct Candidate {
  Primitive shape;             // in the shifted frame
  int level = 0;               // octree level its minimal set came from
  int subsets = 0;             // scoring subsets evaluated
  std::size_t evaluated = 0;   // unassigned points in those subsets
  std::size_t score = 0;       // compatible points among them
  double estimate(std::size_t remaining) const { return double(score) * double(remaining) / double(std::max<std::size_t>(evaluated, 1)); }
};

// Distance to the surface and |cos| of the angle between `n` and the surface normal there.
struct Residual {
  double distance;
  double cosine;
};

Residual residual(const Primitive& s, const Vector3d& p, const Vector3d& n) {
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
  }
  return {std::numeric_limits<double>::infinity(), 0.0};
}

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

// Candidates of each enabled type from a minimal set (3 points with normals); each checked on
// all three points.
void make_candidates(const Vector3d* p, const Vector3d* n, unsigned types, double eps, double cos_max, double scene,
                     std::vector<Primitive>& out) {
  out.clear();
  auto fits = [&](const Primitive& s) {
    for (int i = 0; i < 3; ++i) {
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
}

// Least-squares refit to the points `idx` of `pts`/`nrm`; nullopt when degenerate.
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
  }
  return std::nullopt;
}

// The largest connected component of `idx` on a grid of cells of `cell`: points in cells that
// touch (26-neighbourhood) are connected.
std::vector<std::uint32_t> largest_component(const std::vector<Vector3d>& pts, const std::vector<std::uint32_t>& idx, double cell) {
  if (idx.empty()) return {};
  auto key = [](std::int64_t x, std::int64_t y, std::int64_t z) {
    constexpr std::int64_t off = std::int64_t(1) << 20, mask = (std::int64_t(1) << 21) - 1;
    return std::uint64_t(((x + off) & mask) | (((y + off) & mask) << 21) | (((z + off) & mask) << 42));
  };
  std::unordered_map<std::uint64_t, std::uint32_t> cells;  // cell -> cell number
  std::vector<Eigen::Array3i> coords;
  std::vector<std::uint32_t> cell_of(idx.size());
  for (std::size_t j = 0; j < idx.size(); ++j) {
    const Eigen::Array3i c = (pts[idx[j]].array() / cell).floor().cast<int>();
    const auto [it, added] = cells.emplace(key(c.x(), c.y(), c.z()), std::uint32_t(coords.size()));
    if (added) coords.push_back(c);
    cell_of[j] = it->second;
  }
  std::vector<std::int32_t> comp(coords.size(), -1);
  std::vector<std::size_t> comp_points;
  std::vector<std::uint32_t> count(coords.size(), 0);
  for (std::uint32_t c : cell_of) ++count[c];
  std::vector<std::uint32_t> stack;
  for (std::uint32_t start = 0; start < coords.size(); ++start) {
    if (comp[start] >= 0) continue;
    const std::int32_t id = std::int32_t(comp_points.size());
    comp_points.push_back(0);
    comp[start] = id;
    stack.assign(1, start);
    while (!stack.empty()) {
      const std::uint32_t c = stack.back();
      stack.pop_back();
      comp_points[std::size_t(id)] += count[c];
      for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
          for (int dz = -1; dz <= 1; ++dz) {
            const auto it = cells.find(key(coords[c].x() + dx, coords[c].y() + dy, coords[c].z() + dz));
            if (it != cells.end() && comp[it->second] < 0) comp[it->second] = id, stack.push_back(it->second);
          }
    }
  }
  const std::int32_t best = std::int32_t(std::max_element(comp_points.begin(), comp_points.end()) - comp_points.begin());
  std::vector<std::uint32_t> out;
  for (std::size_t j = 0; j < idx.size(); ++j)
    if (comp[cell_of[j]] == best) out.push_back(idx[j]);
  return out;
}

}  // namespace

const char* primitive_type_name(PrimitiveType type) noexcept {
  switch (type) {
    case PrimitiveType::Plane: return "plane";
    case PrimitiveType::Sphere: return "sphere";
    case PrimitiveType::Cylinder: return "cylinder";
    case PrimitiveType::Cone: return "cone";
  }
  return "unknown";
}

double Primitive::distance(const Eigen::Vector3d& p) const { return residual(*this, p, Vector3d::Zero()).distance; }

void PrimitiveParams::validate() const {
  constexpr std::string_view fn = "detect_primitives";
  if ((types & kAllPrimitives) == 0 || (types & ~unsigned(kAllPrimitives)) != 0)
    throw UsageError(fmt::format("{}: types must name at least one of plane, sphere, cylinder, cone, got bits {}", fn, types));
  auto length = [&](const char* name, double value, double in_spacings, const char* in_name) {
    if (!std::isfinite(value) || value < 0.0) throw UsageError(fmt::format("{}: {} must be >= 0 (cloud units), got {}", fn, name, value));
    if (value == 0.0 && !(std::isfinite(in_spacings) && in_spacings > 0.0))
      throw UsageError(fmt::format("{}: {} must be > 0, got {}", fn, in_name, in_spacings));
  };
  length("epsilon", epsilon, epsilon_in_spacings, "epsilon_in_spacings");
  length("cluster_epsilon", cluster_epsilon, cluster_in_spacings, "cluster_in_spacings");
  if (!(max_normal_deg > 0.0 && max_normal_deg < 90.0))
    throw UsageError(fmt::format("{}: max_normal_deg must be in (0, 90) degrees, got {}", fn, max_normal_deg));
  if (!(probability > 0.0 && probability < 1.0)) throw UsageError(fmt::format("{}: probability must be in (0, 1), got {}", fn, probability));
}

PrimitiveResult detect_primitives(const PointCloud& cloud, const PrimitiveParams& params, const ProgressCallback& progress) {
  constexpr std::string_view fn = "detect_primitives";
  params.validate();
  const std::size_t n_all = cloud.size();
  PrimitiveResult result;
  result.labels.assign(n_all, -1);
  result.unassigned = n_all;
  if (n_all > 0 && !cloud.has_normals())
    throw UsageError(fmt::format("{}: the cloud has no normals (estimate them first: pointsurf normals)", fn));
  if (n_all < 3) return result;
  const double spacing = (params.epsilon > 0.0 && params.cluster_epsilon > 0.0) ? 0.0 : mean_spacing(cloud.positions);
  const double eps = params.epsilon > 0.0 ? params.epsilon : params.epsilon_in_spacings * spacing;
  const double cluster = params.cluster_epsilon > 0.0 ? params.cluster_epsilon : params.cluster_in_spacings * spacing;
  const std::size_t min_points = params.min_points > 0 ? params.min_points : std::max<std::size_t>(30, n_all / 200);
  result.epsilon_used = eps;
  result.cluster_epsilon_used = cluster;
  result.min_points_used = min_points;
  if (!(eps > 0.0) || !(cluster > 0.0)) return result;  // every point at one place: nothing to fit
  const double cos_max = std::cos(params.max_normal_deg * kDeg);

  // Points relative to the box centre, in Morton order (ties by coordinates), so that sampling
  // does not depend on the input order.
  const BoundingBox box = bounding_box(cloud.positions);
  const Vector3d centre = box.center();
  const double side = std::max(box.extent().maxCoeff(), 1e-300);
  const double scene = 10.0 * box.diagonal();
  std::vector<std::uint64_t> codes(n_all);
  for (std::size_t i = 0; i < n_all; ++i) {
    const Eigen::Array3d t = ((cloud.positions[i] - box.min).array() / side * double((1 << kMortonBits) - 1)).round();
    const auto q = t.cast<std::uint64_t>();
    codes[i] = detail::morton_code(q.x(), q.y(), q.z());
  }
  std::vector<std::uint32_t> order(n_all);
  std::iota(order.begin(), order.end(), 0u);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    if (codes[a] != codes[b]) return codes[a] < codes[b];
    const Vector3d &pa = cloud.positions[a], &pb = cloud.positions[b];
    return std::lexicographical_compare(pa.data(), pa.data() + 3, pb.data(), pb.data() + 3);
  });
  std::vector<Vector3d> pts(n_all), nrm(n_all);
  std::vector<std::uint64_t> sorted_codes(n_all);
  std::vector<std::uint8_t> usable(n_all);
  for (std::size_t r = 0; r < n_all; ++r) {
    pts[r] = cloud.positions[order[r]] - centre;
    const Vector3d& nn = cloud.normals[order[r]];
    const double l = nn.norm();
    usable[r] = std::isfinite(l) && l > 0.0;
    nrm[r] = usable[r] ? Vector3d(nn / l) : Vector3d::Zero();
    sorted_codes[r] = codes[order[r]];
  }

  // Scoring subsets: subset 0 about kSmallestSubset points, each next one about twice as large
  // (the last holds about half); a point's subset comes from the seed and its rank.
  int subset_count = 1;
  while (subset_count < 16 && (n_all >> subset_count) >= kSmallestSubset) ++subset_count;
  std::vector<std::vector<std::uint32_t>> subsets(static_cast<std::size_t>(subset_count));
  std::uint64_t state = detail::mix(params.seed);
  for (std::uint32_t r = 0; r < n_all; ++r) {
    if (!usable[r]) continue;
    const double u = detail::uniform01(state);
    int j = subset_count - 1;
    while (j > 0 && u < std::ldexp(1.0, -(subset_count - j))) --j;
    subsets[std::size_t(j)].push_back(r);
  }
  std::vector<std::uint8_t> assigned(n_all, 0);
  std::vector<std::uint32_t> remaining;
  for (std::uint32_t r = 0; r < n_all; ++r)
    if (usable[r]) remaining.push_back(r);

  // Octree levels: from the whole box down to cells of a few cluster cells.
  int levels = 1;
  while (levels < kMortonBits && side / std::ldexp(1.0, levels + 1) > 2.0 * cluster) ++levels;
  std::vector<double> level_weight(std::size_t(levels) + 1, 1.0);
  level_weight[0] = 0.0;

  auto compatible = [&](const Primitive& s, std::uint32_t r) {
    const Residual res = residual(s, pts[r], nrm[r]);
    return res.distance <= eps && res.cosine >= cos_max;
  };
  auto refine = [&](Candidate& c) {
    const std::vector<std::uint32_t>& subset = subsets[std::size_t(c.subsets++)];
    for (std::uint32_t r : subset) {
      if (assigned[r]) continue;
      ++c.evaluated;
      c.score += compatible(c.shape, r);
    }
  };
  auto collect = [&](const Primitive& s) {
    std::vector<std::uint32_t> idx;
    for (std::uint32_t r : remaining)
      if (compatible(s, r)) idx.push_back(r);
    return idx;
  };

  detail::ProgressReporter reporter(progress, 0.0, 1.0, n_all);
  std::vector<Candidate> candidates;
  std::vector<Primitive> made;
  std::size_t draws = 0;
  int failures = 0;
  while (remaining.size() >= min_points && failures < kMaxFailures) {
    if (reporter.cancelled()) break;
    // Draw a batch of minimal sets: the first point uniformly among the unassigned ones, the
    // other two from its octree cell at a level chosen by the levels' past success.
    for (std::size_t b = 0; b < kBatch; ++b) {
      ++draws;
      const std::uint32_t r0 = remaining[std::size_t(detail::uniform01(state) * double(remaining.size()))];
      const double total = std::accumulate(level_weight.begin(), level_weight.end(), 0.0);
      double pick = detail::uniform01(state) * total;
      int level = 1;
      while (level < levels && pick >= level_weight[std::size_t(level)]) pick -= level_weight[std::size_t(level++)];
      const int shift = 3 * (kMortonBits - level);
      const std::uint64_t lo_code = (sorted_codes[r0] >> shift) << shift;
      const std::uint64_t hi_code = lo_code | ((std::uint64_t(1) << shift) - 1);
      const std::size_t lo = std::size_t(std::lower_bound(sorted_codes.begin(), sorted_codes.end(), lo_code) - sorted_codes.begin());
      const std::size_t hi = std::size_t(std::upper_bound(sorted_codes.begin(), sorted_codes.end(), hi_code) - sorted_codes.begin());
      if (hi - lo < 3) continue;
      std::uint32_t rs[3] = {r0, r0, r0};
      bool ok = true;
      for (int k = 1; k < 3 && ok; ++k) {
        ok = false;
        for (int attempt = 0; attempt < 8 && !ok; ++attempt) {
          const std::uint32_t r = std::uint32_t(lo + std::size_t(detail::uniform01(state) * double(hi - lo)));
          ok = usable[r] && !assigned[r] && r != rs[0] && r != rs[1];
          if (ok) rs[k] = r;
        }
      }
      if (!ok) continue;
      const Vector3d p[3] = {pts[rs[0]], pts[rs[1]], pts[rs[2]]};
      const Vector3d nn[3] = {nrm[rs[0]], nrm[rs[1]], nrm[rs[2]]};
      make_candidates(p, nn, params.types, eps, cos_max, scene, made);
      for (const Primitive& s : made) {
        Candidate c;
        c.shape = s;
        c.level = level;
        refine(c);
        candidates.push_back(c);
      }
    }
    result.candidates = draws;
    if (candidates.empty()) {
      if (draws > kMaxDraws) break;
      continue;
    }
    // Lazy scoring: refine the candidate with the best estimate until it is the best exactly.
    std::size_t best = 0;
    for (;;) {
      best = 0;
      for (std::size_t i = 1; i < candidates.size(); ++i)
        if (candidates[i].estimate(remaining.size()) > candidates[best].estimate(remaining.size())) best = i;
      if (candidates[best].subsets == subset_count) break;
      refine(candidates[best]);
    }
    const double found = double(candidates[best].score);
    // Chance that one draw finds a given primitive of n points: its first point on it, and
    // (about) the right level with the other two on it as well; a conservative estimate.
    auto miss = [&](double n) {
      const double hit = n / (double(remaining.size()) * double(levels) * 4.0);
      return std::pow(1.0 - std::min(hit, 1.0), double(draws));
    };
    if (found < double(min_points)) {
      if (miss(double(min_points)) < params.probability || draws > kMaxDraws) break;
      continue;
    }
    if (miss(found) >= params.probability && draws <= kMaxDraws) continue;

    // Extract: compatible points, their largest connected component, a least-squares refit,
    // and again with the refitted primitive.
    Candidate chosen = candidates[best];
    Primitive shape = chosen.shape;
    std::vector<std::uint32_t> idx = largest_component(pts, collect(shape), cluster);
    for (int pass = 0; pass < 2 && idx.size() >= min_points; ++pass) {
      const std::optional<Primitive> fitted = refit(shape, pts, nrm, idx);
      if (!fitted) break;
      std::vector<std::uint32_t> again = largest_component(pts, collect(*fitted), cluster);
      if (again.size() < idx.size() * 9 / 10) break;  // the refit lost its points: keep the sample's fit
      shape = *fitted;
      idx = std::move(again);
    }
    if (idx.size() < min_points) {
      // Its points are scattered (Schnabel et al.: the score is the largest component): keep it
      // with that score, so that it ranks below the others and counts against min_points.
      Candidate& failed = candidates[best];
      failed.subsets = subset_count;
      failed.evaluated = remaining.size();
      failed.score = idx.size();
      ++failures;
      continue;
    }
    failures = 0;
    level_weight[std::size_t(chosen.level)] += 1.0;
    double squares = 0.0;
    for (std::uint32_t r : idx) {
      const double d = residual(shape, pts[r], nrm[r]).distance;
      squares += d * d;
      assigned[r] = 1;
      result.labels[order[r]] = std::int32_t(result.primitives.size());
    }
    shape.inliers = idx.size();
    shape.rms = std::sqrt(squares / double(idx.size()));
    shape.point += centre;
    result.primitives.push_back(shape);
    std::erase_if(remaining, [&](std::uint32_t r) { return assigned[r] != 0; });
    candidates.clear();
    draws = 0;
    reporter.report(1.0 - double(remaining.size()) / double(n_all));
  }
  reporter.throw_if_cancelled();
  result.unassigned = static_cast<std::size_t>(std::count(result.labels.begin(), result.labels.end(), -1));
  return result;
}

}  // namespace pointsurf
