// SPDX-License-Identifier: GPL-3.0-or-later
// CGAL's 2D alpha shape stays inside this file.
#include "pointsurf/segment/outlines.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <unordered_map>

#include <CGAL/Alpha_shape_2.h>
#include <CGAL/Alpha_shape_face_base_2.h>
#include <CGAL/Alpha_shape_vertex_base_2.h>
#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>
#include <Eigen/Eigenvalues>
#include <fmt/format.h>

#include "pointsurf/core/error.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf {
namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Alpha_shape_vertex_base_2<K, CGAL::Triangulation_vertex_base_with_info_2<std::uint32_t, K>>;
using Fb = CGAL::Alpha_shape_face_base_2<K>;
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
using Delaunay = CGAL::Delaunay_triangulation_2<K, Tds>;
using AlphaShape = CGAL::Alpha_shape_2<Delaunay>;

double signed_area(const std::vector<Eigen::Vector2d>& loop) {
  double a = 0.0;
  for (std::size_t i = 0; i < loop.size(); ++i) {
    const Eigen::Vector2d& p = loop[i];
    const Eigen::Vector2d& q = loop[(i + 1) % loop.size()];
    a += p.x() * q.y() - q.x() * p.y();
  }
  return 0.5 * a;
}

bool inside(const Eigen::Vector2d& p, const std::vector<Eigen::Vector2d>& loop) {
  bool in = false;
  for (std::size_t i = 0, j = loop.size() - 1; i < loop.size(); j = i++) {
    const Eigen::Vector2d &a = loop[i], &b = loop[j];
    if ((a.y() > p.y()) != (b.y() > p.y()) && p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x()) in = !in;
  }
  return in;
}

// Chains undirected boundary edges into closed loops (at a pinch vertex of degree 4 the walk
// takes the first unused edge).
std::vector<std::vector<std::uint32_t>> chain_loops(const std::vector<std::pair<std::uint32_t, std::uint32_t>>& edges) {
  std::map<std::uint32_t, std::vector<std::size_t>> at;
  for (std::size_t e = 0; e < edges.size(); ++e) at[edges[e].first].push_back(e), at[edges[e].second].push_back(e);
  std::vector<std::uint8_t> used(edges.size(), 0);
  std::vector<std::vector<std::uint32_t>> loops;
  for (std::size_t start = 0; start < edges.size(); ++start) {
    if (used[start]) continue;
    used[start] = 1;
    std::vector<std::uint32_t> loop = {edges[start].first};
    std::uint32_t current = edges[start].second;
    while (current != loop.front()) {
      loop.push_back(current);
      std::size_t next = edges.size();
      for (std::size_t e : at[current])
        if (!used[e]) {
          next = e;
          break;
        }
      if (next == edges.size()) break;  // open chain: not a loop
      used[next] = 1;
      current = edges[next].first == current ? edges[next].second : edges[next].first;
    }
    if (current == loop.front() && loop.size() >= 3) loops.push_back(std::move(loop));
  }
  return loops;
}

// Douglas-Peucker on the open chain loop[first..last] (indices mod size): marks kept vertices.
void douglas_peucker(const std::vector<Eigen::Vector2d>& loop, std::size_t first, std::size_t last, double tolerance,
                     std::vector<std::uint8_t>& keep) {
  const std::size_t n = loop.size();
  const Eigen::Vector2d a = loop[first % n], b = loop[last % n];
  const Eigen::Vector2d d = b - a;
  const double l = d.norm();
  double worst = -1.0;
  std::size_t at = first;
  for (std::size_t i = first + 1; i < last; ++i) {
    const Eigen::Vector2d q = loop[i % n] - a;
    const double dist = l > 0.0 ? std::abs(d.x() * q.y() - d.y() * q.x()) / l : q.norm();
    if (dist > worst) worst = dist, at = i;
  }
  if (worst <= tolerance) return;
  keep[at % n] = 1;
  douglas_peucker(loop, first, at, tolerance, keep);
  douglas_peucker(loop, at, last, tolerance, keep);
}

// A closed loop simplified: split at its first vertex and the vertex farthest from it.
std::vector<Eigen::Vector2d> simplify_loop(const std::vector<Eigen::Vector2d>& loop, double tolerance) {
  const std::size_t n = loop.size();
  if (!(tolerance > 0.0) || n < 4) return loop;
  std::size_t far = 0;
  for (std::size_t i = 1; i < n; ++i)
    if ((loop[i] - loop[0]).squaredNorm() > (loop[far] - loop[0]).squaredNorm()) far = i;
  std::vector<std::uint8_t> keep(n, 0);
  keep[0] = keep[far] = 1;
  douglas_peucker(loop, 0, far, tolerance, keep);
  douglas_peucker(loop, far, n, tolerance, keep);
  std::vector<Eigen::Vector2d> out;
  for (std::size_t i = 0; i < n; ++i)
    if (keep[i]) out.push_back(loop[i]);
  return out.size() >= 3 ? out : loop;
}

// The loop moved by `distance` along its vertices' mitred normals: outwards (away from the
// enclosed area) for `grow`, inwards otherwise.
std::vector<Eigen::Vector2d> offset_loop(const std::vector<Eigen::Vector2d>& loop, double distance, bool grow) {
  if (!(distance > 0.0)) return loop;
  const std::size_t n = loop.size();
  // Counter-clockwise loops have the outside on the right of each edge.
  const double side = (signed_area(loop) > 0.0 ? 1.0 : -1.0) * (grow ? 1.0 : -1.0);
  std::vector<Eigen::Vector2d> out(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d a = (loop[i] - loop[(i + n - 1) % n]).normalized(), b = (loop[(i + 1) % n] - loop[i]).normalized();
    const Eigen::Vector2d na(a.y(), -a.x()), nb(b.y(), -b.x());
    Eigen::Vector2d m = na + nb;
    const double c = m.norm();
    // A mitre longer than 2 distances (a turn sharper than 120 degrees) is cut to that length.
    m = c > 1e-9 ? Eigen::Vector2d(m / c) : nb;
    const double scale = std::min(1.0 / std::max(m.dot(nb), 1e-9), 2.0);
    out[i] = loop[i] + side * distance * scale * m;
  }
  return out;
}

}  // namespace

const FieldTable<OutlineParams>& OutlineParams::fields() {
  static const FieldTable<OutlineParams> table = [] {
    using P = OutlineParams;
    FieldTable<P> t;
    t.length("alpha", &P::alpha, "Alpha radius of the outlines").positive().was("alpha_in_spacings");
    t.number("simplify_in_spacings", &P::simplify_in_spacings, "Douglas-Peucker tolerance of the loops (0: none)").unit("mean spacings").non_negative();
    t.number("offset_in_spacings", &P::offset_in_spacings, "Loops are moved this far away from the points (outer out, holes in)")
        .unit("mean spacings")
        .non_negative();
    t.number("max_rms_in_spacings", &P::max_rms_in_spacings, "A segment is planar when its RMS distance to its plane is at most this")
        .unit("mean spacings")
        .non_negative();
    t.integer("min_points", &P::min_points, "Fewest points of an outlined segment").at_least(3).unit("points");
    return t;
  }();
  return table;
}

void OutlineParams::validate() const {
  constexpr std::string_view fn = "outline_planar_segments";
  if (!(std::isfinite(max_rms_in_spacings) && max_rms_in_spacings >= 0.0))
    throw UsageError(fmt::format("{}: max_rms_in_spacings must be >= 0, got {}", fn, max_rms_in_spacings));
  if (!(std::isfinite(offset_in_spacings) && offset_in_spacings >= 0.0))
    throw UsageError(fmt::format("{}: offset_in_spacings must be >= 0, got {}", fn, offset_in_spacings));
  if (!(std::isfinite(simplify_in_spacings) && simplify_in_spacings >= 0.0))
    throw UsageError(fmt::format("{}: simplify_in_spacings must be >= 0, got {}", fn, simplify_in_spacings));
  if (min_points < 3) throw UsageError(fmt::format("{}: min_points must be >= 3, got {}", fn, min_points));
  fields().validate(*this, fn);
}

std::string describe_skipped(const OutlineResult& r, std::size_t segments, const OutlineParams& params) {
  if (r.skipped.empty()) return {};
  std::vector<std::string> parts;
  if (r.nonplanar > 0) {
    double lo = std::numeric_limits<double>::infinity(), hi = 0.0;
    bool own = false;
    for (const SkippedSegment& s : r.skipped)
      if (s.reason == SkipReason::NotPlanar) {
        lo = std::min(lo, s.rms), hi = std::max(hi, s.rms);
        own = own || s.threshold != params.max_rms_in_spacings * r.spacing;
      }
    const double sp = r.spacing > 0.0 ? r.spacing : 1.0;
    parts.push_back(fmt::format("{} not planar (RMS to their plane {:.3g}{} mean spacings, above {}{})", r.nonplanar, lo / sp,
                                hi > lo ? fmt::format("-{:.3g}", hi / sp) : std::string(), own ? "their band or " : "",
                                fmt::format("max_rms_in_spacings {:g}", params.max_rms_in_spacings)));
  }
  if (r.too_small > 0) parts.push_back(fmt::format("{} with fewer than min_points {} points", r.too_small, params.min_points));
  std::string joined;
  for (std::size_t i = 0; i < parts.size(); ++i) joined += (i ? ", " : "") + parts[i];
  return fmt::format("{} of {} segments have no outline: {}", r.skipped.size(), segments, joined);
}

OutlineResult outline_planar_segments(const PointCloud& cloud, std::span<const std::int32_t> labels, const OutlineParams& params,
                                      std::span<const SegmentPlane> planes) {
  constexpr std::string_view fn = "outline_planar_segments";
  params.validate();
  if (labels.size() != cloud.size())
    throw UsageError(fmt::format("{}: {} labels for {} points", fn, labels.size(), cloud.size()));
  OutlineResult result;
  if (cloud.size() < 2) return result;
  const double spacing = mean_spacing(cloud.positions);
  const double alpha = params.alpha.resolve(spacing);
  result.alpha_used = alpha;
  result.spacing = spacing;
  std::map<std::int32_t, const SegmentPlane*> own_plane;
  for (const SegmentPlane& p : planes) {
    if (!(p.point.allFinite() && p.normal.allFinite() && p.normal.norm() > 0.0 && std::isfinite(p.band) && p.band >= 0.0))
      throw UsageError(fmt::format("{}: the plane of segment {} is not a plane (a finite point, a non-zero normal, a band >= 0)", fn, p.segment));
    own_plane[p.segment] = &p;
  }
  if (!(alpha > 0.0)) return result;
  std::map<std::int32_t, std::vector<std::uint32_t>> members;
  for (std::uint32_t i = 0; i < labels.size(); ++i)
    if (labels[i] >= 0) members[labels[i]].push_back(i);
  for (const auto& [label, idx] : members) {
    if (idx.size() < params.min_points) {
      ++result.too_small;
      result.skipped.push_back({label, idx.size(), SkipReason::TooSmall, 0.0, 0.0});
      continue;
    }
    // The least-squares plane, relative to the first point (georeferenced clouds).
    const Eigen::Vector3d origin = cloud.positions[idx.front()];
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (std::uint32_t i : idx) mean += cloud.positions[i] - origin;
    mean /= double(idx.size());
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (std::uint32_t i : idx) {
      const Eigen::Vector3d d = cloud.positions[i] - origin - mean;
      cov.noalias() += d * d.transpose();
    }
    cov /= double(idx.size());
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(cov);
    // The segment's own plane (RANSAC's, with its band) when given, else the least-squares one.
    Eigen::Vector3d normal = eigen.eigenvectors().col(0).normalized();
    double rms = std::sqrt(std::max(eigen.eigenvalues()[0], 0.0));
    double threshold = params.max_rms_in_spacings * spacing;
    if (const auto it = own_plane.find(label); it != own_plane.end()) {
      normal = it->second->normal.normalized();
      const Eigen::Vector3d on = it->second->point - origin;
      double sum = 0.0;
      for (std::uint32_t i : idx) {
        const double d = normal.dot(cloud.positions[i] - origin - on);
        sum += d * d;
      }
      rms = std::sqrt(sum / double(idx.size()));
      // RANSAC's inliers lie within the band of the candidate plane; the least-squares plane
      // it reports after refitting can leave their RMS a little above it (b9: 0.663 against
      // 0.660), hence the margin.
      threshold = std::max(threshold, 1.5 * it->second->band);
      mean -= normal.dot(mean - on) * normal;  // the centroid, on the plane
    }
    if (!(rms <= threshold) || !(eigen.eigenvalues()[1] > 0.0)) {
      ++result.nonplanar;
      result.skipped.push_back({label, idx.size(), SkipReason::NotPlanar, rms, threshold});
      continue;
    }
    // In-plane axes: the direction of largest spread, made perpendicular to the normal.
    Eigen::Vector3d u = eigen.eigenvectors().col(2) - normal.dot(eigen.eigenvectors().col(2)) * normal;
    if (!(u.norm() > 1e-9)) u = normal.unitOrthogonal();
    u.normalize();
    const Eigen::Vector3d v = normal.cross(u);
    std::vector<std::pair<K::Point_2, std::uint32_t>> flat;
    std::vector<Eigen::Vector2d> uv(idx.size());
    for (std::uint32_t j = 0; j < idx.size(); ++j) {
      const Eigen::Vector3d d = cloud.positions[idx[j]] - origin - mean;
      uv[j] = Eigen::Vector2d(u.dot(d), v.dot(d));
      flat.emplace_back(K::Point_2(uv[j].x(), uv[j].y()), j);
    }
    AlphaShape shape(flat.begin(), flat.end(), alpha * alpha, AlphaShape::REGULARIZED);
    std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;
    for (auto it = shape.alpha_shape_edges_begin(); it != shape.alpha_shape_edges_end(); ++it) {
      if (shape.classify(*it) != AlphaShape::REGULAR) continue;
      const auto f = it->first;
      const int i = it->second;
      edges.emplace_back(f->vertex(Delaunay::cw(i))->info(), f->vertex(Delaunay::ccw(i))->info());
    }
    std::sort(edges.begin(), edges.end());
    const std::vector<std::vector<std::uint32_t>> chains = chain_loops(edges);
    std::vector<std::vector<Eigen::Vector2d>> loops2;
    for (std::vector<std::uint32_t> c : chains) {
      // Douglas-Peucker depends on where the loop starts: start at its lexicographically
      // smallest point, so that the outline does not depend on the order of the points.
      const auto lowest = std::min_element(c.begin(), c.end(), [&](std::uint32_t a, std::uint32_t b) {
        const Eigen::Vector3d &pa = cloud.positions[idx[a]], &pb = cloud.positions[idx[b]];
        return std::lexicographical_compare(pa.data(), pa.data() + 3, pb.data(), pb.data() + 3);
      });
      std::rotate(c.begin(), lowest, c.end());
      std::vector<Eigen::Vector2d> l;
      for (std::uint32_t j : c) l.push_back(uv[j]);
      loops2.push_back(simplify_loop(l, params.simplify_in_spacings * spacing));
    }
    std::vector<std::size_t> order(chains.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return std::abs(signed_area(loops2[a])) > std::abs(signed_area(loops2[b])); });
    SegmentOutline out;
    out.segment = label;
    out.centroid = origin + mean;
    out.normal = normal;
    for (std::size_t k = 0; k < order.size(); ++k) {
      const std::vector<Eigen::Vector2d>& l = loops2[order[k]];
      std::int32_t around = -1;
      for (std::size_t m = 0; m < k && around < 0; ++m)
        if (!out.hole[m] && inside(l.front(), loops2[order[m]])) around = static_cast<std::int32_t>(m);
      const bool is_hole = around >= 0;
      const std::vector<Eigen::Vector2d> moved = offset_loop(l, params.offset_in_spacings * spacing, !is_hole);
      Polyline line;
      line.closed = true;
      for (const Eigen::Vector2d& p : moved) line.points.push_back(out.centroid + p.x() * u + p.y() * v);
      const double area = std::abs(signed_area(moved));
      out.area += is_hole ? -area : area;
      out.perimeter += line.length();
      out.loops.push_back(std::move(line));
      out.hole.push_back(is_hole);
      out.outer.push_back(around);
    }
    if (!out.loops.empty()) result.outlines.push_back(std::move(out));
  }
  return result;
}

}  // namespace pointsurf
