// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/reconstruct/triangulate.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <optional>
#include <queue>
#include <functional>
#include <limits>
#include <utility>
#include <vector>

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "core/detail/progress_reporter.h"
#include "reconstruct/detail/exact_copies.h"
#include "pointsurf/core/error.h"
#include "reconstruct/detail/hole_filling.h"
#include "reconstruct/detail/region_growing.h"
#include "reconstruct/detail/triangulate_half_edges.h"

namespace pointsurf {
namespace {

using Eigen::Vector2d;
using detail::HalfEdgeMap;

constexpr std::uint32_t kNone = HalfEdgeMap::kNone;
// Points closer than this fraction of the mean spacing are the same point.
constexpr double kDuplicateFraction = 1e-9;
// Neighbours searched for the local spacing (the 3 nearest distinct ones are averaged).
constexpr std::size_t kSpacingNeighbours = 8;
constexpr std::size_t kSpacingAveraged = 3;
// Longest fan walked around a vertex.
constexpr int kMaxFanWalk = 64;
// Unused points are inserted in this many rounds (one per triangle and round), each looking at
// the triangles of this many nearest points.
constexpr int kInsertRounds = 3;
constexpr std::size_t kInsertNeighbours = 8;
// Neighbours whose normal agrees with the centre's may lie this many local spacings off its
// tangent plane (plus what the turn of the normals explains).
constexpr double kFlatOffsetInSpacings = 0.5;
// A hole that holds a usable point no triangle uses is a gap of the reconstruction, not of the
// data (where the sampling density changes abruptly, as in CGAL's radar.xyz): it is closed up to
// this many times the perimeter limit, and the point is then inserted into the filling.
constexpr double kHoldingPointFactor = 15.0;
// A loop along which the local spacing changes abruptly (its largest is this many times its
// mean) has its limit set by the largest; random uniform samples stay well below.
constexpr double kAbruptDensityRatio = 3.0;
// A point whose nearest neighbours lie along a line through it (a scan line) sees no point of the
// next line among its k nearest or within a few of its spacings, and the growth never crosses
// the band between two lines (CGAL's radar.xyz). Along a line, in the point's tangent plane, the
// two largest angular gaps between its neighbours are both at least kLineGapDeg wide and their
// directions agree as axes (the mean of their doubled angles' unit vectors is at least
// kLineResultant long; 1 on a straight line). Random samples of a surface show such a
// neighbourhood now and then (3 % of points pass the gap test alone), a scan line a run of
// them: a point counts as on a line when one of its two nearest neighbours also passes. Its
// umbrella then reaches kLineReachFactor times farther and takes as many times more neighbours.
constexpr double kLineGapDeg = 120.0;
constexpr double kLineResultant = 0.6;
constexpr double kLineReachFactor = 4.0;

double radians(double degrees) { return degrees * std::numbers::pi / 180.0; }

using Candidate = detail::GrowthCandidate;  // reconstruct/detail/region_growing.h
using detail::CandidateEdge;

Candidate make_candidate(std::uint32_t a, std::uint32_t b, std::uint32_t c, double min_angle_deg) {
  Candidate cand{};
  if (a < b && a < c) cand.v = {a, b, c};
  else if (b < a && b < c) cand.v = {b, c, a};
  else cand.v = {c, a, b};
  cand.min_angle_deg = static_cast<float>(min_angle_deg);
  cand.votes = 1;
  return cand;
}

// Inner angles of triangle abc, degrees; false if it is degenerate.
bool inner_angles(const Vector3d& a, const Vector3d& b, const Vector3d& c, double& smallest, double& largest) {
  const std::array<Vector3d, 3> p{a, b, c};
  smallest = 180.0;
  largest = 0.0;
  for (int i = 0; i < 3; ++i) {
    const Vector3d u = p[(i + 1) % 3] - p[i], v = p[(i + 2) % 3] - p[i];
    const double nu = u.norm(), nv = v.norm();
    if (!(nu > 0.0) || !(nv > 0.0)) return false;
    const double angle = std::acos(std::clamp(u.dot(v) / (nu * nv), -1.0, 1.0)) * 180.0 / std::numbers::pi;
    smallest = std::min(smallest, angle);
    largest = std::max(largest, angle);
  }
  return true;
}

// One neighbour in the tangent plane of the umbrella's centre.
struct Planar {
  Vector2d u;
  std::uint32_t index;
};

// Per-thread buffers of the umbrella pass: no allocation per point once warmed up.
struct UmbrellaBuffers {
  std::vector<Neighbor> neighbors;
  std::vector<Planar> planar;
  std::vector<Vector2d> cell, next_cell;
  std::vector<int> labels, next_labels;
  std::vector<Candidate> candidates;
};

// Clips the convex polygon (cell, labels) by the half-plane x.u <= |u|^2 / 2 (the side of the
// origin of the bisector between the origin and u). labels[i] names the edge cell[i] -> cell[i+1]:
// -1 for the initial square, otherwise the neighbour whose bisector it lies on.
void clip_cell(UmbrellaBuffers& b, const Vector2d& u, int label) {
  const double offset = 0.5 * u.squaredNorm();
  const std::size_t m = b.cell.size();
  b.next_cell.clear();
  b.next_labels.clear();
  for (std::size_t i = 0; i < m; ++i) {
    const Vector2d& p = b.cell[i];
    const Vector2d& q = b.cell[(i + 1) % m];
    const double fp = p.dot(u) - offset, fq = q.dot(u) - offset;
    const bool p_in = fp <= 0.0, q_in = fq <= 0.0;
    if (p_in) {
      b.next_cell.push_back(p);
      b.next_labels.push_back(b.labels[i]);
    }
    if (p_in != q_in) {
      const Vector2d crossing = p + (q - p) * (fp / (fp - fq));
      b.next_cell.push_back(crossing);
      // Leaving the half-plane: the edge from here on runs along the bisector. Entering it:
      // the rest of the old edge keeps its label.
      b.next_labels.push_back(p_in ? label : b.labels[i]);
    }
  }
  b.cell.swap(b.next_cell);
  b.labels.swap(b.next_labels);
}

struct Setup {
  const PointCloud& cloud;
  const TriangulateParams& params;
  const KdTree& tree;
  const std::vector<Vector3d>& normals;   // unit, or zero where unusable
  const std::vector<double>& local_spacing;
  const std::vector<std::uint8_t>& usable;
  const std::vector<double>& radius_of;  // search radius and longest edge per point
  const std::vector<std::uint8_t>& on_line;  // scan-line points: k times kLineReachFactor
};

// The Delaunay umbrella of point i in its tangent plane; appends accepted candidates.
void umbrella(const Setup& s, std::uint32_t i, UmbrellaBuffers& b) {
  if (!s.usable[i]) return;
  const Vector3d& p = s.cloud.positions[i];
  const Vector3d& n = s.normals[i];
  const double radius = s.radius_of[i];
  const double max_offset = s.params.max_offset_in_spacings * s.local_spacing[i];
  const double min_normal_dot = std::cos(radians(s.params.max_normal_angle_deg));
  const double k = s.on_line[i] ? kLineReachFactor * double(s.params.k) : double(s.params.k);
  s.tree.hybrid(p, static_cast<std::size_t>(k) + 1, radius, b.neighbors);

  const Vector3d e1 = n.unitOrthogonal(), e2 = n.cross(e1);
  b.planar.clear();
  for (const Neighbor& nb : b.neighbors) {
    const std::uint32_t j = nb.index;
    if (j == i || !s.usable[j]) continue;
    const Vector3d d = s.cloud.positions[j] - p;
    const double height = d.dot(n);
    if (std::abs(height) > max_offset) continue;
    const double normal_dot = s.normals[j].dot(n);
    if (normal_dot < min_normal_dot) continue;
    // A neighbour whose normal agrees with p's lies on the same smooth sheet only if it is near
    // p's tangent plane: on a curve of radius R a neighbour at distance d sits d^2 / 2R off the
    // plane while its normal turns by d / R, so the offset allowed grows with the sine of the
    // normals' angle (a sharp edge allows the whole max_offset). This keeps a parallel sheet a
    // few spacings away (a floor under a table) out of the umbrella.
    const double sine = s.normals[j].cross(n).norm();
    if (std::abs(height) > std::max(kFlatOffsetInSpacings * s.local_spacing[i], std::sqrt(nb.squared_distance) * sine)) continue;
    const Vector3d tangent = d - height * n;
    const double tangent_length = tangent.norm(), distance = std::sqrt(nb.squared_distance);
    if (!(tangent_length > 1e-9 * distance) || !(distance > 0.0)) continue;
    // Unfold: keep the 3D distance in the direction of the projection, so that the points of
    // a face meeting this one at a sharp edge do not all land on the edge line.
    const double scale = distance / tangent_length;
    b.planar.push_back({Vector2d(tangent.dot(e1) * scale, tangent.dot(e2) * scale), j});
  }
  if (b.planar.size() < 2) return;

  b.cell.assign({Vector2d(-radius, -radius), Vector2d(radius, -radius), Vector2d(radius, radius), Vector2d(-radius, radius)});
  b.labels.assign({-1, -1, -1, -1});
  double cell_reach2 = 2.0 * radius * radius;  // largest squared distance of a cell corner
  for (std::size_t q = 0; q < b.planar.size(); ++q) {
    const Vector2d& u = b.planar[q].u;
    // Neighbours come nearest first and keep their distance: once a bisector lies beyond the
    // cell's farthest corner, no later one can cut it.
    if (0.25 * u.squaredNorm() > cell_reach2) break;
    bool cuts = false;
    const double offset = 0.5 * u.squaredNorm();
    for (const Vector2d& corner : b.cell) cuts = cuts || corner.dot(u) > offset;
    if (!cuts) continue;
    clip_cell(b, u, static_cast<int>(q));
    cell_reach2 = 0.0;
    for (const Vector2d& corner : b.cell) cell_reach2 = std::max(cell_reach2, corner.squaredNorm());
  }

  const std::size_t m = b.labels.size();
  const double radius2 = radius * radius;
  for (std::size_t e = 0; e < m; ++e) {
    const int l1 = b.labels[e], l2 = b.labels[(e + 1) % m];
    if (l1 < 0 || l2 < 0 || l1 == l2) continue;
    const std::uint32_t j1 = b.planar[static_cast<std::size_t>(l1)].index, j2 = b.planar[static_cast<std::size_t>(l2)].index;
    const Vector3d& q1 = s.cloud.positions[j1];
    const Vector3d& q2 = s.cloud.positions[j2];
    if ((q2 - q1).squaredNorm() > radius2) continue;
    double smallest = 0.0, largest = 0.0;
    if (!inner_angles(p, q1, q2, smallest, largest)) continue;
    if (smallest < s.params.min_angle_deg || largest > s.params.max_angle_deg) continue;
    const Vector3d face = (q1 - p).cross(q2 - p);
    if (!(face.dot(n) > 0.0) || !(face.dot(s.normals[j1]) > 0.0) || !(face.dot(s.normals[j2]) > 0.0)) continue;
    b.candidates.push_back(make_candidate(i, j1, j2, smallest));
  }
}

// Whether the neighbours `nb` of point i (normal n) lie along a line through it: their doubled
// angles around n agree (kLineResultant) and the two largest angular gaps between them are both
// at least kLineGapDeg.
bool lies_on_line(const std::vector<Vector3d>& positions, std::uint32_t i, const Vector3d& n, const std::vector<Neighbor>& nb,
                  std::vector<double>& angles) {
  const Vector3d e1 = n.unitOrthogonal(), e2 = n.cross(e1);
  // The doubled angle's unit vector of (x, y) is (x^2 - y^2, 2 x y) / (x^2 + y^2): no
  // trigonometry for the test most points fail.
  Vector2d sum = Vector2d::Zero();
  int count = 0;
  for (const Neighbor& x : nb) {
    if (x.index == i || !(x.squared_distance > 0.0)) continue;
    const Vector3d d = positions[x.index] - positions[i];
    const double u = d.dot(e1), v = d.dot(e2), r2 = u * u + v * v;
    if (!(r2 > 0.0)) continue;
    sum += Vector2d(u * u - v * v, 2.0 * u * v) / r2;
    ++count;
  }
  if (count < 2 || sum.norm() < kLineResultant * double(count)) return false;
  angles.clear();
  for (const Neighbor& x : nb) {
    if (x.index == i || !(x.squared_distance > 0.0)) continue;
    const Vector3d d = positions[x.index] - positions[i];
    const double u = d.dot(e1), v = d.dot(e2);
    if (u * u + v * v > 0.0) angles.push_back(std::atan2(v, u));
  }
  std::sort(angles.begin(), angles.end());
  double first = 0.0, second = 0.0;
  for (std::size_t a = 0; a < angles.size(); ++a) {
    const double gap = a + 1 < angles.size() ? angles[a + 1] - angles[a] : angles[0] + 2.0 * std::numbers::pi - angles[a];
    if (gap > first) { second = first; first = gap; }
    else if (gap > second) second = gap;
  }
  return second >= radians(kLineGapDeg);
}

void check_params(const PointCloud& cloud, const TriangulateParams& p, const KdTree* tree) {
  p.validate();
  const std::size_t n = cloud.size();
  if (n < 3) throw UsageError(fmt::format("reconstruct_region_growing: needs at least 3 points, got {}", n));
  // Triangles hold int vertex indices, and candidate ids must stay below kNone.
  constexpr std::size_t kMaxPoints = std::size_t(std::numeric_limits<int>::max() / 4);
  if (n > kMaxPoints) throw UsageError(fmt::format("reconstruct_region_growing: at most {} points, got {}", kMaxPoints, n));
  if (!cloud.has_normals())
    throw UsageError("reconstruct_region_growing: the cloud has no normals; estimate and orient them first "
                     "(estimate_normals, orient_normals)");
  if (cloud.normals.size() != n)
    throw UsageError(fmt::format("reconstruct_region_growing: the cloud has {} normals for {} points", cloud.normals.size(), n));
  if (tree != nullptr && tree->size() != n)
    throw UsageError(fmt::format("reconstruct_region_growing: the kd-tree holds {} points but the cloud has {}", tree->size(), n));
  for (std::size_t i = 0; i < n; ++i)
    if (!cloud.positions[i].allFinite())
      throw InputError(fmt::format("reconstruct_region_growing: point {} has a non-finite coordinate", i));
}

using detail::Selection;  // reconstruct/detail/hole_filling.h

// Counter-clockwise angle from direction a to direction b around the unit normal n, in [0, 2 pi).
double ccw_angle(const Vector3d& a, const Vector3d& b, const Vector3d& n) {
  double angle = std::atan2(n.dot(a.cross(b)), a.dot(b) - a.dot(n) * b.dot(n));
  if (angle < 0.0) angle += 2.0 * std::numbers::pi;
  return angle;
}

// Whether a new triangle with corner v (next x, previous y, counter-clockwise) fits into the
// gap of v's fan instead of overlapping it: walking the fan from the shared edge v-x (or v-y)
// to its other end z, y (or x) must come before z, seen around v's normal. A corner with no
// shared edge, or whose fan the triangle closes, fits.
bool fits_gap(const std::vector<Vector3d>& positions, const std::vector<Vector3d>& normals, const Selection& sel, std::uint32_t v,
              std::uint32_t x, std::uint32_t y) {
  const Vector3d& n = normals[v];
  const auto dir = [&](std::uint32_t w) { return Vector3d(positions[w] - positions[v]); };
  const auto corner_next = [&](std::uint32_t t) {
    const Triangle& tri = sel.triangles[t];
    const int c = std::uint32_t(tri[0]) == v ? 0 : std::uint32_t(tri[1]) == v ? 1 : 2;
    return std::array<std::uint32_t, 2>{std::uint32_t(tri[(c + 1) % 3]), std::uint32_t(tri[(c + 2) % 3])};
  };
  if (sel.edges.contains(x, v)) {
    // The fan runs clockwise from x: triangles (z, v, w) with w clockwise of z.
    std::uint32_t z = x;
    for (int step = 0; step < kMaxFanWalk; ++step) {
      const std::uint32_t t = sel.edges.find(z, v);
      if (t == kNone) break;
      z = corner_next(t)[0];
      if (z == y) return true;
    }
    return ccw_angle(dir(x), dir(y), n) < ccw_angle(dir(x), dir(z), n);
  }
  if (sel.edges.contains(v, y)) {
    // The fan runs counter-clockwise from y.
    std::uint32_t z = y;
    for (int step = 0; step < kMaxFanWalk; ++step) {
      const std::uint32_t t = sel.edges.find(v, z);
      if (t == kNone) break;
      z = corner_next(t)[1];
      if (z == x) return true;
    }
    return ccw_angle(dir(x), dir(y), n) < ccw_angle(dir(z), dir(y), n);
  }
  return true;
}

// Closes the front where it turns sharply: at a boundary vertex v between boundary edges
// u -> v -> w whose opening angle on the hole side (in v's tangent plane) is below
// `max_angle_deg`, adds the triangle (v, u, w), smallest angle first, while the new edge u-w is
// at most the local search radius. This zips up the narrow gaps and small holes left where
// growing fronts met with umbrellas that disagree, without crossing a straight rim of an open
// surface. Returns the triangles added.
std::size_t close_front(const PointCloud& cloud, const std::vector<Vector3d>& normals, const std::vector<double>& radius_of,
                        double max_angle_deg, double min_dihedral_cos, Selection& sel) {
  const std::size_t n = cloud.size();
  std::vector<std::uint32_t> next(n, kNone), prev(n, kNone);
  std::vector<std::uint8_t> out_degree(n, 0), in_degree(n, 0);
  // Boundary edges x -> y. Where several leave or reach a vertex, which one next / prev keep
  // does not matter: such a vertex is never an ear tip.
  for (const detail::HoleEdge& e : detail::all_hole_edges(sel)) {
    const std::uint32_t x = e.x, y = e.y;
    next[x] = y;
    prev[y] = x;
    out_degree[x] = std::uint8_t(std::min(out_degree[x] + 1, 2));
    in_degree[y] = std::uint8_t(std::min(in_degree[y] + 1, 2));
  }
  const double max_angle = radians(max_angle_deg);
  // Hole-side angle at v, or infinity when v cannot be an ear tip.
  const auto hole_angle = [&](std::uint32_t v) {
    if (out_degree[v] != 1 || in_degree[v] != 1) return double(INFINITY);
    const std::uint32_t u = prev[v], w = next[v];
    if (u == kNone || w == kNone || u == w) return double(INFINITY);
    const Vector3d& nv = normals[v];
    const Vector3d e1 = nv.unitOrthogonal(), e2 = nv.cross(e1);
    const Vector3d a3 = cloud.positions[u] - cloud.positions[v], b3 = cloud.positions[w] - cloud.positions[v];
    const Vector2d a(a3.dot(e1), a3.dot(e2)), b(b3.dot(e1), b3.dot(e2));
    double angle = std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b));
    if (angle < 0.0) angle += 2.0 * std::numbers::pi;
    return angle;
  };
  using Entry = std::pair<double, std::uint32_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> queue;
  for (std::uint32_t v = 0; v < n; ++v) {
    const double angle = hole_angle(v);
    if (angle < max_angle) queue.emplace(angle, v);
  }
  std::size_t added = 0;
  while (!queue.empty()) {
    const auto [angle, v] = queue.top();
    queue.pop();
    if (hole_angle(v) != angle) continue;  // stale entry
    const std::uint32_t u = prev[v], w = next[v];
    if (sel.edges.contains(u, w)) continue;
    const Vector3d &pv = cloud.positions[v], &pu = cloud.positions[u], &pw = cloud.positions[w];
    if ((pw - pu).norm() > 2.0 * std::max(radius_of[u], radius_of[w])) continue;
    const Vector3d face = (pu - pv).cross(pw - pv);
    if (!(face.norm() > 0.0)) continue;
    const Vector3d unit = face.normalized();
    if (!(unit.dot(normals[v]) > 0.0) || !(unit.dot(normals[u]) > 0.0) || !(unit.dot(normals[w]) > 0.0)) continue;
    const std::uint32_t t1 = sel.edges.find(u, v), t2 = sel.edges.find(v, w);
    if ((t1 != kNone && unit.dot(sel.normals[t1]) < min_dihedral_cos) || (t2 != kNone && unit.dot(sel.normals[t2]) < min_dihedral_cos))
      continue;
    const std::uint32_t closing = sel.edges.find(w, u);  // the hole was the triangle u v w
    sel.add(v, u, w, unit);
    ++added;
    out_degree[v] = in_degree[v] = 0;
    next[v] = prev[v] = kNone;
    if (closing != kNone) {
      // The hole was the triangle u v w and is gone: u lost u -> v and w -> u, w lost v -> w
      // and w -> u. A vertex with boundary edges left was pinched; its other neighbours are
      // not tracked, so it stays barred as an ear tip.
      for (std::uint32_t x : {u, w}) {
        out_degree[x] = std::uint8_t(out_degree[x] - 1);
        in_degree[x] = std::uint8_t(in_degree[x] - 1);
        if (out_degree[x] != 0 || in_degree[x] != 0) out_degree[x] = in_degree[x] = 2;
        next[x] = prev[x] = kNone;
      }
    } else {
      next[u] = w;
      prev[w] = u;
    }
    for (std::uint32_t x : {u, w}) {
      const double a = hole_angle(x);
      if (a < max_angle) queue.emplace(a, x);
    }
  }
  return added;
}

// Whether the hole loop (hole on the left of loop[i] -> loop[i+1], seen from the normals' side)
// holds a usable point that no triangle uses: projected on the plane of the corners' mean
// normal, the loop must run counter-clockwise (a hole, not the outer border of an open
// surface, around which it runs the other way) and hold the point.
bool hole_holds_unused_point(const std::vector<std::uint32_t>& loop, const std::vector<Vector3d>& positions,
                             const std::vector<Vector3d>& normals, const std::vector<std::uint8_t>& unused, const KdTree& tree,
                             std::vector<Vector2d>& polygon, std::vector<Neighbor>& neighbors) {
  const std::size_t m = loop.size();
  Vector3d normal = Vector3d::Zero(), centre = Vector3d::Zero();
  for (std::uint32_t v : loop) {
    normal += normals[v];
    centre += positions[v];
  }
  centre /= double(m);
  if (!(normal.norm() > 0.0)) return false;
  normal.normalize();
  const Vector3d e1 = normal.unitOrthogonal(), e2 = normal.cross(e1);
  polygon.clear();
  double reach2 = 0.0, twice_area = 0.0;
  for (std::uint32_t v : loop) {
    const Vector3d d = positions[v] - centre;
    polygon.emplace_back(d.dot(e1), d.dot(e2));
    reach2 = std::max(reach2, d.squaredNorm());
  }
  for (std::size_t i = 0; i < m; ++i) {
    const Vector2d &a = polygon[i], &b = polygon[(i + 1) % m];
    twice_area += a.x() * b.y() - a.y() * b.x();
  }
  if (!(twice_area > 0.0)) return false;
  tree.radius(centre, std::sqrt(reach2), neighbors);
  for (const Neighbor& nb : neighbors) {
    if (!unused[nb.index]) continue;
    const Vector3d d = positions[nb.index] - centre;
    const double x = d.dot(e1), y = d.dot(e2);
    bool inside = false;
    for (std::size_t i = 0, j = m - 1; i < m; j = i++) {
      const Vector2d &a = polygon[i], &b = polygon[j];
      if ((a.y() > y) != (b.y() > y) && x < (b.x() - a.x()) * (y - a.y()) / (b.y() - a.y()) + a.x()) inside = !inside;
    }
    if (inside) return true;
  }
  return false;
}

// The perimeter limit factor of a hole loop: where the density changes abruptly along it, the
// limit follows the sparsest corner's spacing, not the mean; a hole that holds an unused point
// (see hole_holds_unused_point) gets kHoldingPointFactor.
detail::LoopLimit loop_limit(const std::vector<std::uint32_t>& loop, const std::vector<Vector3d>& positions,
                             const std::vector<Vector3d>& normals, const std::vector<double>& local_spacing,
                             const std::vector<std::uint8_t>& unused, const KdTree& tree, std::vector<Vector2d>& polygon,
                             std::vector<Neighbor>& neighbors) {
  double sum = 0.0, largest = 0.0;
  for (std::uint32_t v : loop) {
    sum += local_spacing[v];
    largest = std::max(largest, local_spacing[v]);
  }
  double sparsest = largest * double(loop.size()) / sum;
  if (sparsest < kAbruptDensityRatio) sparsest = 1.0;
  if (hole_holds_unused_point(loop, positions, normals, unused, tree, polygon, neighbors))
    return detail::LoopLimit{std::max(sparsest, kHoldingPointFactor), true};
  return detail::LoopLimit{sparsest, false};
}

// Inserts the usable points that no triangle uses (their umbrella triangles lost to
// neighbouring ones, or they sat in a hole that was filled without them) into the mesh: into
// the triangle whose plane they project into (along its normal), split in three, or else onto
// the interior edge they project onto, whose two triangles are split in two each. The point
// must lie within its search radius of the plane and face the way the new triangles do. Both
// moves keep the mesh edge-manifold and oriented. Returns the number of points inserted.
std::size_t insert_unused_points(const std::vector<Vector3d>& positions, const std::vector<Vector3d>& normals,
                                 const std::vector<std::uint8_t>& usable, const std::vector<double>& radius_of, const KdTree& tree,
                                 Selection& sel) {
  const std::size_t n = positions.size();
  std::size_t inserted = 0;
  std::vector<std::uint8_t> used(n), taken;
  std::vector<std::uint32_t> unused, offset(n + 1), around, new_id;
  std::vector<Neighbor> neighbors;
  std::vector<Triangle> next_triangles;
  for (int round = 0; round < kInsertRounds; ++round) {
    std::fill(used.begin(), used.end(), std::uint8_t{0});
    for (const Triangle& t : sel.triangles)
      for (int c = 0; c < 3; ++c) used[std::size_t(t[c])] = 1;
    unused.clear();
    for (std::uint32_t i = 0; i < n; ++i)
      if (usable[i] && !used[i]) unused.push_back(i);
    if (unused.empty() || sel.triangles.empty()) break;
    const std::size_t f = sel.triangles.size();
    std::fill(offset.begin(), offset.end(), 0u);
    for (const Triangle& t : sel.triangles)
      for (int c = 0; c < 3; ++c) ++offset[std::size_t(t[c]) + 1];
    for (std::size_t v = 0; v < n; ++v) offset[v + 1] += offset[v];
    around.resize(3 * f);
    {
      std::vector<std::uint32_t> cursor(offset.begin(), offset.end() - 1);
      for (std::size_t t = 0; t < f; ++t)
        for (int c = 0; c < 3; ++c) around[cursor[std::size_t(sel.triangles[t][c])]++] = static_cast<std::uint32_t>(t);
    }
    taken.assign(f, 0);
    next_triangles.clear();
    const auto corner = [&](std::uint32_t t, int c) { return std::uint32_t(sel.triangles[t][c]); };
    const auto faces = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c, const Vector3d& n_p) {
      const Vector3d face = (positions[b] - positions[a]).cross(positions[c] - positions[a]);
      return face.dot(n_p) > 0.0 && face.dot(normals[a] + normals[b] + normals[c]) > 0.0;
    };
    std::size_t placed = 0;
    for (const std::uint32_t p : unused) {
      const Vector3d& x = positions[p];
      const Vector3d& n_p = normals[p];
      tree.knn(x, kInsertNeighbours, neighbors);
      // Best triangle: smallest distance to its plane among those the point projects into.
      std::uint32_t best = kNone;
      double best_height = radius_of[p];
      for (const Neighbor& nb : neighbors)
        for (std::uint32_t i = offset[nb.index]; i < offset[nb.index + 1]; ++i) {
          const std::uint32_t t = around[i];
          if (taken[t]) continue;
          const Vector3d &a = positions[corner(t, 0)], &b = positions[corner(t, 1)], &c = positions[corner(t, 2)];
          const Vector3d face = (b - a).cross(c - a);
          const double twice_area = face.norm();
          if (!(twice_area > 0.0)) continue;
          const Vector3d unit = face / twice_area;
          if (!(unit.dot(n_p) > 0.0)) continue;
          const double height = std::abs((x - a).dot(unit));
          if (!(height < best_height)) continue;
          const bool inside = (b - a).cross(x - a).dot(unit) >= 0.0 && (c - b).cross(x - b).dot(unit) >= 0.0 &&
                              (a - c).cross(x - c).dot(unit) >= 0.0;
          if (!inside) continue;
          best = t;
          best_height = height;
        }
      if (best != kNone) {
        const std::uint32_t a = corner(best, 0), b = corner(best, 1), c = corner(best, 2);
        if (faces(a, b, p, n_p) && faces(b, c, p, n_p) && faces(c, a, p, n_p)) {
          taken[best] = 1;
          next_triangles.insert(next_triangles.end(), {Triangle(int(a), int(b), int(p)), Triangle(int(b), int(c), int(p)),
                                                       Triangle(int(c), int(a), int(p))});
          ++placed;
          continue;
        }
      }
      // Otherwise the nearest interior edge a -> b whose span the point projects into.
      std::uint32_t t1 = kNone, t2 = kNone, ea = kNone, eb = kNone;
      double best_distance = radius_of[p];
      for (const Neighbor& nb : neighbors)
        for (std::uint32_t i = offset[nb.index]; i < offset[nb.index + 1]; ++i) {
          const std::uint32_t t = around[i];
          if (taken[t]) continue;
          for (int e = 0; e < 3; ++e) {
            const std::uint32_t a = corner(t, e), b = corner(t, (e + 1) % 3);
            const std::uint32_t twin = sel.edges.find(b, a);
            if (twin == kNone || taken[twin]) continue;
            const Vector3d ab = positions[b] - positions[a];
            const double along = (x - positions[a]).dot(ab) / ab.squaredNorm();
            if (!(along > 0.0 && along < 1.0)) continue;
            const double distance = (x - positions[a] - along * ab).norm();
            if (!(distance < best_distance)) continue;
            best_distance = distance;
            t1 = t;
            t2 = twin;
            ea = a;
            eb = b;
          }
        }
      if (t1 == kNone) continue;
      const std::uint32_t c = corner(t1, 0) != ea && corner(t1, 0) != eb ? corner(t1, 0)
                              : corner(t1, 1) != ea && corner(t1, 1) != eb ? corner(t1, 1) : corner(t1, 2);
      const std::uint32_t d = corner(t2, 0) != ea && corner(t2, 0) != eb ? corner(t2, 0)
                              : corner(t2, 1) != ea && corner(t2, 1) != eb ? corner(t2, 1) : corner(t2, 2);
      if (!(faces(ea, p, c, n_p) && faces(p, eb, c, n_p) && faces(eb, p, d, n_p) && faces(p, ea, d, n_p))) continue;
      taken[t1] = taken[t2] = 1;
      next_triangles.insert(next_triangles.end(), {Triangle(int(ea), int(p), int(c)), Triangle(int(p), int(eb), int(c)),
                                                   Triangle(int(eb), int(p), int(d)), Triangle(int(p), int(ea), int(d))});
      ++placed;
    }
    if (placed == 0) break;
    inserted += placed;
    // The split triangles leave in place (the others keep their order and edges), their parts
    // come last.
    sel.remove(taken, new_id);
    for (const Triangle& t : next_triangles) {
      const auto a = std::uint32_t(t[0]), b = std::uint32_t(t[1]), c = std::uint32_t(t[2]);
      sel.add(a, b, c, (positions[b] - positions[a]).cross(positions[c] - positions[a]).normalized());
    }
  }
  return inserted;
}

}  // namespace

const FieldTable<TriangulateParams>& TriangulateParams::fields() {
  static const FieldTable<TriangulateParams> table = [] {
    using P = TriangulateParams;
    FieldTable<P> t;
    t.integer("k", &P::k, "At most k neighbours per point (4k within 4x the radius for points on a scan line)").at_least(3).unit("points");
    t.length("radius", &P::radius, "Search radius and longest edge (in spacings: each point's local spacing)")
        .positive()
        .unit("cloud units or local spacings")
        .was("radius_in_spacings");
    t.number("max_offset_in_spacings", &P::max_offset_in_spacings, "Ignore neighbours farther from the tangent plane").unit("local spacings").positive();
    t.number("max_normal_angle_deg", &P::max_normal_angle_deg, "Ignore neighbours whose normal deviates more").unit("degrees").range(0, 180, true, false);
    t.number("min_angle_deg", &P::min_angle_deg, "Smallest inner angle of a triangle").unit("degrees").range(0, 60, false, true);
    t.number("max_angle_deg", &P::max_angle_deg, "Largest inner angle of a triangle").unit("degrees").range(60, 180, true, false);
    t.number("max_dihedral_deg", &P::max_dihedral_deg, "Largest angle between neighbouring triangle normals").unit("degrees").range(0, 180, true, false);
    t.number("max_front_angle_deg", &P::max_front_angle_deg, "Close boundary corners opening less than this after growing; 0: off")
        .unit("degrees")
        .range(0, 180, false, true);
    t.number("max_hole_perimeter_in_spacings", &P::max_hole_perimeter_in_spacings, "Close holes up to this perimeter (fill_holes, every interpolating method); 0: none")
        .unit("local spacings")
        .non_negative();
    return t;
  }();
  return table;
}

void TriangulateParams::validate() const {
  const TriangulateParams& p = *this;
  const auto bad = [](const char* name, double value, const char* expected) {
    return UsageError(fmt::format("reconstruct_region_growing: {} must be {}, got {}", name, expected, value));
  };
  if (p.k < 3) throw bad("k", p.k, ">= 3");
  if (!(p.max_offset_in_spacings > 0.0) || !std::isfinite(p.max_offset_in_spacings))
    throw bad("max_offset_in_spacings", p.max_offset_in_spacings, "> 0");
  if (!(p.max_normal_angle_deg > 0.0 && p.max_normal_angle_deg <= 180.0))
    throw bad("max_normal_angle_deg", p.max_normal_angle_deg, "in (0, 180]");
  if (!(p.min_angle_deg >= 0.0 && p.min_angle_deg < 60.0)) throw bad("min_angle_deg", p.min_angle_deg, "in [0, 60)");
  if (!(p.max_angle_deg > 60.0 && p.max_angle_deg <= 180.0)) throw bad("max_angle_deg", p.max_angle_deg, "in (60, 180]");
  if (!(p.max_dihedral_deg > 0.0 && p.max_dihedral_deg <= 180.0))
    throw bad("max_dihedral_deg", p.max_dihedral_deg, "in (0, 180]");
  if (!(p.max_front_angle_deg >= 0.0 && p.max_front_angle_deg < 180.0))
    throw bad("max_front_angle_deg", p.max_front_angle_deg, "in [0, 180)");
  if (!(p.max_hole_perimeter_in_spacings >= 0.0) || !std::isfinite(p.max_hole_perimeter_in_spacings))
    throw bad("max_hole_perimeter_in_spacings", p.max_hole_perimeter_in_spacings, ">= 0");
  fields().validate(*this, "reconstruct_region_growing");
}

namespace detail {

RegionGrowing::RegionGrowing(const PointCloud& cloud, const TriangulateParams& params, const KdTree& tree,
                             const ProgressCallback& progress)
    : cloud(cloud), params(params), tree(tree), reporter(progress, 0.0, 1.0, 0), n(cloud.size()),
      order(tree.spatial_order()), min_dihedral_cos(std::cos(radians(params.max_dihedral_deg))), progress_(progress) {
  out.mean_spacing = mean_spacing(tree);
}

void RegionGrowing::measure_points() {
  const double duplicate2 = std::pow(kDuplicateFraction * out.mean_spacing, 2);
  normals.assign(n, Vector3d::Zero());
  local_spacing.assign(n, out.mean_spacing);
  usable.assign(n, 0);
  line_like.assign(n, 0);
  nearest.assign(n, {kNone, kNone});
  {
    // Exact copies by sorting: a stack of more copies than the kNN below sees stays one point.
    const std::vector<std::uint8_t> copies = detail::later_exact_copies(cloud.positions);
    detail::ProgressReporter pass(progress_, 0.0, 0.1, n);
    tbb::enumerable_thread_specific<std::vector<Neighbor>> buffers;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 512), [&](const tbb::blocked_range<std::size_t>& r) {
      if (pass.cancelled()) return;
      std::vector<Neighbor>& nb = buffers.local();
      std::vector<double> angles;
      for (std::size_t pos = r.begin(); pos != r.end(); ++pos) {
        const std::uint32_t i = order[pos];
        tree.knn(cloud.positions[i], kSpacingNeighbours, nb);
        bool duplicate = copies[i] != 0;
        double sum = 0.0;
        std::size_t count = 0;
        for (const Neighbor& x : nb) {
          if (x.index == i) continue;
          if (x.squared_distance <= duplicate2) {
            duplicate = duplicate || x.index < i;
            continue;
          }
          if (count < 2) nearest[i][count] = x.index;
          if (count < kSpacingAveraged) { sum += std::sqrt(x.squared_distance); ++count; }
        }
        if (count > 0) local_spacing[i] = sum / double(count);
        const double length = cloud.normals[i].norm();
        const bool has_normal = length > 0.0 && std::isfinite(length);
        normals[i] = has_normal ? Vector3d(cloud.normals[i] / length) : Vector3d::Zero();
        usable[i] = static_cast<std::uint8_t>(has_normal && !duplicate && out.mean_spacing > 0.0);
        line_like[i] = static_cast<std::uint8_t>(usable[i] && lies_on_line(cloud.positions, i, normals[i], nb, angles));
      }
      pass.advance(r.size());
    });
    pass.throw_if_cancelled();
  }
  double spacing_sum = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    spacing_sum += local_spacing[i];
    // Duplicates are counted by their later copies: the first of a group stays usable.
    if (!usable[i] && normals[i] != Vector3d::Zero()) ++out.duplicate_points;
  }
  out.local_spacing_mean = spacing_sum / double(n);
}

// A point is on a scan line when it and one of its two nearest neighbours look so (see
// kLineGapDeg). An explicit radius is the user's reach: nothing is widened then.
void RegionGrowing::widen_scan_lines() {
  on_line.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i)
    on_line[i] = static_cast<std::uint8_t>(params.radius.in_spacings() && line_like[i] && ((nearest[i][0] != kNone && line_like[nearest[i][0]]) ||
                                                                                    (nearest[i][1] != kNone && line_like[nearest[i][1]])));
  radius_of.assign(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    radius_of[i] = params.radius.resolve(local_spacing[i]);
    if (on_line[i]) radius_of[i] *= kLineReachFactor;
  }
}

// Umbrellas in parallel; candidates gathered per thread.
void RegionGrowing::propose_umbrellas() {
  const Setup setup{cloud, params, tree, normals, local_spacing, usable, radius_of, on_line};
  tbb::enumerable_thread_specific<UmbrellaBuffers> umbrella_buffers;
  {
    detail::ProgressReporter pass(progress_, 0.1, 0.7, n);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256), [&](const tbb::blocked_range<std::size_t>& r) {
      if (pass.cancelled()) return;
      UmbrellaBuffers& b = umbrella_buffers.local();
      for (std::size_t pos = r.begin(); pos != r.end(); ++pos) umbrella(setup, order[pos], b);
      pass.advance(r.size());
    });
    pass.throw_if_cancelled();
  }
  candidates.clear();
  std::size_t total = 0;
  for (const UmbrellaBuffers& b : umbrella_buffers) total += b.candidates.size();
  candidates.reserve(total);
  for (UmbrellaBuffers& b : umbrella_buffers) {
    candidates.insert(candidates.end(), b.candidates.begin(), b.candidates.end());
    std::vector<Candidate>().swap(b.candidates);
  }
}

// Merges the proposals of the three umbrellas of each triangle: votes = how many proposed it.
void RegionGrowing::merge_candidates() {
  tbb::parallel_sort(candidates.begin(), candidates.end(), [](const Candidate& x, const Candidate& y) { return x.v < y.v; });
  std::size_t unique = 0;
  for (std::size_t i = 0; i < candidates.size();) {
    std::size_t j = i + 1;
    while (j < candidates.size() && candidates[j].v == candidates[i].v) ++j;
    Candidate merged = candidates[i];
    merged.votes = static_cast<std::uint8_t>(std::min<std::size_t>(j - i, 255));
    candidates[unique++] = merged;
    i = j;
  }
  candidates.resize(unique);
  out.candidate_triangles = unique;
  tbb::parallel_sort(candidates.begin(), candidates.end(), [](const Candidate& x, const Candidate& y) {
    if (x.votes != y.votes) return x.votes > y.votes;
    if (x.min_angle_deg != y.min_angle_deg) return x.min_angle_deg > y.min_angle_deg;
    return x.v < y.v;
  });
}

// Each directed edge of each candidate, with its other vertex, filed by the kd-tree leaf rank
// of its first vertex: the growing front is compact in space, so its look-ups here and in the
// half-edge map (laid out the same way, see HalfEdgeMap) stay within a few cache lines instead
// of one miss each.
void RegionGrowing::index_candidate_edges() {
  const std::size_t unique = candidates.size();
  rank.assign(n, 0);
  for (std::size_t pos = 0; pos < n; ++pos) rank[order[pos]] = static_cast<std::uint32_t>(pos);
  by_edge.assign(3 * unique, {});
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, unique, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t c = r.begin(); c != r.end(); ++c)
      for (int e = 0; e < 3; ++e) {
        const std::array<std::uint32_t, 3>& v = candidates[c].v;
        by_edge[3 * c + std::size_t(e)] = {(std::uint64_t{rank[v[e]]} << 32) | v[(e + 1) % 3], std::uint32_t(c), v[(e + 2) % 3]};
      }
  });
  tbb::parallel_sort(by_edge.begin(), by_edge.end(), [](const CandidateEdge& x, const CandidateEdge& y) {
    return x.key != y.key ? x.key < y.key : x.id < y.id;
  });
  edges_from.assign(n + 1, 0);
  for (const CandidateEdge& entry : by_edge) ++edges_from[std::size_t(entry.key >> 32) + 1];
  for (std::size_t r = 0; r < n; ++r) edges_from[r + 1] += edges_from[r];
  sel = Selection(std::min<std::size_t>(unique, 2 * n + 16), &rank);
  in_mesh.assign(n, 0);
  accepted.assign(unique, 0);
}

// Seeds are taken best first among candidates whose vertices are all new; from each accepted
// triangle the front grows, best candidate first, across its edges (see try_accept).
void RegionGrowing::grow_regions() {
  const auto unique = static_cast<std::uint32_t>(candidates.size());
  for (std::uint32_t seed = 0; seed < unique; ++seed) {
    if (accepted[seed] || !try_accept(seed, candidates[seed].v, 0)) continue;
    push_neighbours(candidates[seed].v);
    report_growth();
    while (!front_.empty()) {
      const FrontEntry top = front_.top();
      front_.pop();
      if (accepted[top.id] || !try_accept(top.id, top.v, 1)) continue;
      push_neighbours(top.v);
      report_growth();
    }
  }
}

// Fronts that met out of step leave channels whose two sides only touch at vertices: bridge
// them with the remaining candidates that share an edge with the mesh.
void RegionGrowing::bridge_channels() {
  const auto unique = static_cast<std::uint32_t>(candidates.size());
  for (std::uint32_t id = 0; id < unique; ++id)
    if (!accepted[id]) try_accept(id, candidates[id].v, 2);
  std::vector<Candidate>().swap(candidates);
  out.selected_triangles = sel.triangles.size();
}

// A triangle is accepted when none of its directed edges is used yet (every edge then has at
// most two triangles, traversed in opposite directions: edge-manifold and consistently oriented
// by construction), when at every vertex already in the mesh it continues that vertex's fan
// across an edge (no pinched vertex, no tunnel), and when its normal is within max_dihedral_deg
// of each neighbour across a shared edge. mode 0: seed (all vertices new); 1: growth (fans
// continue at every old vertex); 2: closing (attached by at least one edge; closes fronts that
// met out of step).
bool RegionGrowing::try_accept(std::uint32_t id, const std::array<std::uint32_t, 3>& v, int mode) {
  const bool seed = mode == 0;
  if (!sel.free_edges(v[0], v[1], v[2])) return false;
  std::array<std::uint32_t, 3> twin{};
  for (int e = 0; e < 3; ++e) twin[std::size_t(e)] = sel.edges.find(v[(e + 1) % 3], v[e]);
  for (int c = 0; c < 3; ++c) {
    if (!in_mesh[v[c]]) continue;
    if (seed) return false;
    // Corner c lies on edges c-1 -> c and c -> c+1.
    if (mode == 1 && twin[std::size_t((c + 2) % 3)] == kNone && twin[std::size_t(c)] == kNone) return false;
  }
  if (mode == 2 && twin[0] == kNone && twin[1] == kNone && twin[2] == kNone) return false;
  for (int c = 0; c < 3; ++c)
    if (in_mesh[v[c]] && !fits_gap(cloud.positions, normals, sel, v[c], v[(c + 1) % 3], v[(c + 2) % 3])) return false;
  const Vector3d face =
      (cloud.positions[v[1]] - cloud.positions[v[0]]).cross(cloud.positions[v[2]] - cloud.positions[v[0]]).normalized();
  for (std::uint32_t t : twin)
    if (t != kNone && face.dot(sel.normals[t]) < min_dihedral_cos) return false;
  sel.add(v[0], v[1], v[2], face);
  for (std::uint32_t w : v) in_mesh[w] = 1;
  accepted[id] = 1;
  return true;
}

// Pushes the candidates across each edge of triangle v onto the front.
void RegionGrowing::push_neighbours(const std::array<std::uint32_t, 3>& v) {
  for (int e = 0; e < 3; ++e) {
    const std::uint32_t from = v[(e + 1) % 3], to = v[e], r = rank[from];
    const std::uint64_t key = (std::uint64_t{r} << 32) | to;
    for (std::uint32_t i = edges_from[r]; i < edges_from[r + 1]; ++i) {
      const CandidateEdge& entry = by_edge[i];
      if (entry.key == key && !accepted[entry.id]) front_.push({entry.id, make_candidate(from, to, entry.third, 0.0).v});
    }
  }
}

// Progress of the serial growth: accepted triangles against the about 2 N a closed surface
// has, reported every few thousand so that the bar moves through this pass.
void RegionGrowing::report_growth() {
  if ((++grown_ & 4095u) == 0) reporter.report(0.8 + 0.1 * std::min(1.0, double(grown_) / double(2 * std::max<std::size_t>(n, 1))));
}

void RegionGrowing::close_front_corners() {
  out.front_triangles = close_front(cloud, normals, radius_of, params.max_front_angle_deg, min_dihedral_cos, sel);
}

// Fill, then open the pinches that remain (vertices where fans touch) and fill again.
void RegionGrowing::close_small_holes() {
  // Points left out of the mesh so far: a hole holding one gets a larger perimeter limit.
  std::vector<std::uint8_t> unused(usable);
  for (const Triangle& t : sel.triangles)
    for (int c = 0; c < 3; ++c) unused[std::size_t(t[c])] = 0;
  std::vector<Vector2d> polygon;
  std::vector<Neighbor> neighbors;
  const detail::LoopLimitFactor holding_factor = [&](const std::vector<std::uint32_t>& loop) {
    return loop_limit(loop, cloud.positions, normals, local_spacing, unused, tree, polygon, neighbors);
  };
  detail::HoleClosing closing;
  detail::close_holes(cloud.positions, normals, local_spacing, params.max_hole_perimeter_in_spacings, sel, {}, closing,
                      [&](int round) { reporter.report(0.9 + 0.05 * double(round + 1) / 4.0); }, holding_factor);
  out.holes_filled = closing.holes_filled;
  out.fill_triangles = closing.fill_triangles;
  out.pinch_triangles_removed = closing.pinch_triangles_removed;
}

void RegionGrowing::insert_points() {
  out.inserted_points = insert_unused_points(cloud.positions, normals, usable, radius_of, tree, sel);
}

TriangulateResult RegionGrowing::result() && {
  TriangulateResult result = std::move(out);
  result.mesh = TriangleMesh{cloud, std::move(sel.triangles), {}};
  result.topology = analyze_topology(result.mesh);
  std::vector<std::uint8_t> used(n, 0);
  for (const Triangle& t : result.mesh.triangles)
    for (int c = 0; c < 3; ++c) used[static_cast<std::size_t>(t[c])] = 1;
  result.unused_points = n - static_cast<std::size_t>(std::count(used.begin(), used.end(), std::uint8_t{1}));
  ReconstructionStats& stats = result.stats;
  stats.input_points = n;
  stats.duplicate_points = result.duplicate_points;
  stats.candidate_triangles = result.candidate_triangles;
  stats.holes_filled = result.holes_filled;
  stats.fill_triangles = result.fill_triangles;
  stats.counts = {{"selected_triangles", result.selected_triangles},
                  {"front_triangles", result.front_triangles},
                  {"pinch_triangles_removed", result.pinch_triangles_removed},
                  {"inserted_points", result.inserted_points}};
  stats.figures = {{"local_spacing_mean", result.local_spacing_mean}};
  return result;
}

}  // namespace detail

TriangulateResult reconstruct_region_growing(const PointCloud& cloud, const TriangulateParams& params, const KdTree* tree,
                                             const ProgressCallback& progress) {
  const auto t_start = std::chrono::steady_clock::now();
  check_params(cloud, params, tree);
  std::optional<KdTree> own_tree;
  if (tree == nullptr) tree = &own_tree.emplace(cloud.positions);
  detail::RegionGrowing g(cloud, params, *tree, progress);
  detail::ProgressReporter& reporter = g.reporter;
  g.measure_points();
  g.widen_scan_lines();
  g.propose_umbrellas();
  reporter.report(0.72);
  reporter.throw_if_cancelled();
  g.merge_candidates();
  reporter.report(0.8);
  reporter.throw_if_cancelled();
  g.index_candidate_edges();
  g.grow_regions();
  g.bridge_channels();
  reporter.report(0.9);
  reporter.throw_if_cancelled();
  g.close_front_corners();
  g.close_small_holes();
  reporter.report(0.95);
  g.insert_points();
  reporter.report(0.98);
  TriangulateResult result = std::move(g).result();
  result.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  reporter.report(1.0);
  reporter.throw_if_cancelled();
  return result;
}

}  // namespace pointsurf
