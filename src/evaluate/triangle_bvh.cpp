// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/evaluate/triangle_bvh.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <numbers>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include "pointsurf/core/error.h"

namespace pointsurf {
namespace {

constexpr int kLeafSize = 4;

// Nodes of the subtree over n triangles: the median split fixes the shape, so every subtree's
// place in the node array is known before it is built and the halves build in parallel.
int subtree_nodes(int n) { return n <= kLeafSize ? 1 : 1 + subtree_nodes(n / 2) + subtree_nodes(n - n / 2); }

double box_squared_distance(const Vector3d& p, const Vector3d& lo, const Vector3d& hi) {
  const Vector3d d = (lo - p).cwiseMax(p - hi).cwiseMax(0.0);
  return d.squaredNorm();
}

ClosestPoint on_segment(const Vector3d& p, const Vector3d& a, const Vector3d& b, int edge) {
  const Vector3d ab = b - a;
  const double len2 = ab.squaredNorm();
  double t = len2 > 0.0 ? (p - a).dot(ab) / len2 : 0.0;
  ClosestPoint r;
  r.feature = TriangleFeature::Edge;
  r.local_index = edge;
  if (t <= 0.0) {
    t = 0.0;
    r.feature = TriangleFeature::Vertex;
    r.local_index = edge;
  } else if (t >= 1.0) {
    t = 1.0;
    r.feature = TriangleFeature::Vertex;
    r.local_index = (edge + 1) % 3;
  }
  r.point = a + t * ab;
  r.squared_distance = (p - r.point).squaredNorm();
  r.triangle = 0;
  return r;
}

}  // namespace

ClosestPoint closest_point_on_triangle(const Vector3d& p, const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  const Vector3d ab = b - a, ac = c - a;
  ClosestPoint r;
  r.triangle = 0;
  const double cross2 = ab.cross(ac).squaredNorm();
  if (!(cross2 > 1e-30 * ab.squaredNorm() * ac.squaredNorm()) || cross2 == 0.0) {
    ClosestPoint best = on_segment(p, a, b, 0);
    for (const ClosestPoint& s : {on_segment(p, b, c, 1), on_segment(p, c, a, 2)})
      if (s.squared_distance < best.squared_distance) best = s;
    return best;
  }
  auto finish = [&](const Vector3d& q, TriangleFeature f, int i) {
    r.point = q;
    r.feature = f;
    r.local_index = i;
    r.squared_distance = (p - q).squaredNorm();
    return r;
  };
  const Vector3d ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return finish(a, TriangleFeature::Vertex, 0);
  const Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return finish(b, TriangleFeature::Vertex, 1);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return finish(a + (d1 / (d1 - d3)) * ab, TriangleFeature::Edge, 0);
  const Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return finish(c, TriangleFeature::Vertex, 2);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return finish(a + (d2 / (d2 - d6)) * ac, TriangleFeature::Edge, 2);
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0)
    return finish(b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b), TriangleFeature::Edge, 1);
  const double denom = 1.0 / (va + vb + vc);
  return finish(a + ab * (vb * denom) + ac * (vc * denom), TriangleFeature::Face, 0);
}

TriangleBvh::TriangleBvh(std::span<const Vector3d> vertices, std::span<const Triangle> triangles) {
  BoundingBox box;
  for (const Triangle& t : triangles)
    for (int c = 0; c < 3; ++c) {
      if (t[c] < 0 || static_cast<std::size_t>(t[c]) >= vertices.size())
        throw InputError(fmt::format("triangle {}: vertex index {} out of range (the mesh has {} vertices)",
                                     &t - triangles.data(), t[c], vertices.size()));
      box.extend(vertices[static_cast<std::size_t>(t[c])]);
    }
  origin_ = box.center();
  const std::size_t f = triangles.size();
  if (f > static_cast<std::size_t>(std::numeric_limits<int>::max() / 3))
    throw InputError(fmt::format("{} triangles: more than a hierarchy can index", f));
  vertices_.resize(vertices.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, vertices.size()), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t v = range.begin(); v != range.end(); ++v) vertices_[v] = vertices[v] - origin_;
  });
  faces_.assign(triangles.begin(), triangles.end());  // by the mesh's index while building
  order_.resize(f);
  slot_.resize(f);
  std::vector<Vector3d> centroids(f);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, f), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t t = range.begin(); t != range.end(); ++t) {
      centroids[t] = (slot_corner(t, 0) + slot_corner(t, 1) + slot_corner(t, 2)) / 3.0;
      order_[t] = static_cast<int>(t);
    }
  });
  if (f == 0) {
    vertices_.clear();
    return;
  }
  nodes_.resize(static_cast<std::size_t>(subtree_nodes(static_cast<int>(f))));
  build(0, 0, static_cast<int>(f), centroids, 0);
  centroids = {};
  // Faces in leaf order and vertices renumbered by first use: a leaf's triangles and their
  // corners lie side by side in memory. Unused vertices are dropped.
  std::vector<int> renumber(vertices_.size(), -1);
  std::vector<Vector3d> used;
  used.reserve(vertices_.size());
  std::vector<Triangle> ordered(f);
  for (std::size_t i = 0; i < f; ++i) {
    const std::size_t t = static_cast<std::size_t>(order_[i]);
    slot_[t] = static_cast<int>(i);
    for (int c = 0; c < 3; ++c) {
      int& id = renumber[static_cast<std::size_t>(faces_[t][c])];
      if (id < 0) {
        id = static_cast<int>(used.size());
        used.push_back(vertices_[static_cast<std::size_t>(faces_[t][c])]);
      }
      ordered[i][c] = id;
    }
  }
  faces_ = std::move(ordered);
  vertices_ = std::move(used);
}

void TriangleBvh::build(int index, int begin, int end, std::vector<Vector3d>& centroids, int depth) {
  Node& node = nodes_[static_cast<std::size_t>(index)];
  node.lo = Vector3d::Constant(std::numeric_limits<double>::infinity());
  node.hi = -node.lo;
  Vector3d clo = node.lo, chi = node.hi;
  for (int i = begin; i < end; ++i) {
    const std::size_t t = static_cast<std::size_t>(order_[static_cast<std::size_t>(i)]);
    const Vector3d &a = slot_corner(t, 0), &b = slot_corner(t, 1), &c = slot_corner(t, 2);
    node.lo = node.lo.cwiseMin(a).cwiseMin(b).cwiseMin(c);
    node.hi = node.hi.cwiseMax(a).cwiseMax(b).cwiseMax(c);
    clo = clo.cwiseMin(centroids[t]);
    chi = chi.cwiseMax(centroids[t]);
  }
  const int n = end - begin;
  if (n <= kLeafSize) {
    node.first = begin;
    node.count = n;
    return;
  }
  int axis = 0;
  (chi - clo).maxCoeff(&axis);
  const int mid = begin + n / 2;
  std::nth_element(order_.begin() + begin, order_.begin() + mid, order_.begin() + end,
                   [&](int x, int y) { return centroids[static_cast<std::size_t>(x)][axis] < centroids[static_cast<std::size_t>(y)][axis]; });
  const int left = index + 1, right = index + 1 + subtree_nodes(mid - begin);
  node.count = 0;
  node.right = right;
  if (n > 4096 && depth < 16)
    tbb::parallel_invoke([&] { build(left, begin, mid, centroids, depth + 1); }, [&] { build(right, mid, end, centroids, depth + 1); });
  else {
    build(left, begin, mid, centroids, depth + 1);
    build(right, mid, end, centroids, depth + 1);
  }
}

void TriangleBvh::make_dipoles(int index, int depth) const {
  const Node& node = nodes_[static_cast<std::size_t>(index)];
  Dipole& d = dipoles_[static_cast<std::size_t>(index)];
  Vector3d weighted = Vector3d::Zero();
  if (node.count > 0) {
    for (int i = node.first; i < node.first + node.count; ++i) {
      const std::size_t slot = static_cast<std::size_t>(i);
      const Vector3d &a = slot_corner(slot, 0), &b = slot_corner(slot, 1), &c = slot_corner(slot, 2);
      const Vector3d n = 0.5 * (b - a).cross(c - a);
      const double area = n.norm();
      d.area_normal += n;
      d.area += area;
      weighted += area * (a + b + c) / 3.0;
    }
  } else {
    const int left = index + 1, right = node.right;
    if (depth < 12)
      tbb::parallel_invoke([&] { make_dipoles(left, depth + 1); }, [&] { make_dipoles(right, depth + 1); });
    else {
      make_dipoles(left, depth + 1);
      make_dipoles(right, depth + 1);
    }
    for (const int child : {left, right}) {
      const Dipole& c = dipoles_[static_cast<std::size_t>(child)];
      d.area_normal += c.area_normal;
      d.area += c.area;
      weighted += c.area * c.area_centroid;
    }
  }
  d.area_centroid = d.area > 0.0 ? Vector3d(weighted / d.area) : Vector3d(0.5 * (node.lo + node.hi));
  for (int k = 0; k < 8; ++k) {
    const Vector3d corner((k & 1) ? node.hi.x() : node.lo.x(), (k & 2) ? node.hi.y() : node.lo.y(), (k & 4) ? node.hi.z() : node.lo.z());
    d.radius = std::max(d.radius, (corner - d.area_centroid).norm());
  }
}

ClosestPoint TriangleBvh::closest(const Vector3d& query, double max_distance) const {
  ClosestPoint best;
  if (nodes_.empty()) return best;
  const Vector3d p = query - origin_;
  double best2 = max_distance * max_distance;
  struct Entry {
    int node;
    double d2;
  };
  Entry stack[128];
  int top = 0;
  stack[top++] = {0, box_squared_distance(p, nodes_[0].lo, nodes_[0].hi)};
  while (top > 0) {
    const Entry e = stack[--top];
    if (e.d2 > best2 || (best.found() && e.d2 >= best2)) continue;
    const Node& node = nodes_[static_cast<std::size_t>(e.node)];
    if (node.count > 0) {
      for (int i = node.first; i < node.first + node.count; ++i) {
        const std::size_t slot = static_cast<std::size_t>(i);
        ClosestPoint c = closest_point_on_triangle(p, slot_corner(slot, 0), slot_corner(slot, 1), slot_corner(slot, 2));
        if (c.squared_distance < best2 || (!best.found() && c.squared_distance <= best2)) {
          best2 = c.squared_distance;
          c.triangle = order_[slot];
          best = c;
        }
      }
      continue;
    }
    const int l = e.node + 1, r = node.right;
    const double dl = box_squared_distance(p, nodes_[static_cast<std::size_t>(l)].lo, nodes_[static_cast<std::size_t>(l)].hi);
    const double dr = box_squared_distance(p, nodes_[static_cast<std::size_t>(r)].lo, nodes_[static_cast<std::size_t>(r)].hi);
    if (dl <= dr) {
      stack[top++] = {r, dr};
      stack[top++] = {l, dl};
    } else {
      stack[top++] = {l, dl};
      stack[top++] = {r, dr};
    }
  }
  if (best.found()) best.point += origin_;
  return best;
}

ClosestPoint TriangleBvh::closest_near(const Vector3d& query, const std::optional<Vector3d>& on_mesh, double max_distance) const {
  // A point of the mesh at distance b from the query bounds the answer by b, so boxes farther
  // than b are skipped from the start. They hold no closest triangle, and the walk visits the
  // rest in the same order, so the first closest triangle found is the same. The bound is
  // widened by 1e-9 against rounding; should nothing lie within it, the plain walk answers.
  if (on_mesh) {
    const double bound = (query - *on_mesh).norm() * (1.0 + 1e-9) + 1e-300;
    if (bound < max_distance) {
      const ClosestPoint c = closest(query, bound);
      if (c.found()) return c;
    }
  }
  return closest(query, max_distance);
}

double TriangleBvh::winding_number(const Vector3d& query, double accuracy) const {
  if (nodes_.empty()) return 0.0;
  std::call_once(dipoles_once_, [this] {
    dipoles_.resize(nodes_.size());
    make_dipoles(0, 0);
  });
  const Vector3d p = query - origin_;
  double solid_angle = 0.0;
  int stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const std::size_t index = static_cast<std::size_t>(stack[--top]);
    const Node& node = nodes_[index];
    const Dipole& dipole = dipoles_[index];
    const Vector3d d = dipole.area_centroid - p;
    const double dist = d.norm();
    if (dist > accuracy * dipole.radius && dist > 0.0) {
      solid_angle += d.dot(dipole.area_normal) / (dist * dist * dist);
      continue;
    }
    if (node.count > 0) {
      for (int i = node.first; i < node.first + node.count; ++i) {
        const std::size_t t = static_cast<std::size_t>(i);
        // Van Oosterom and Strackee's formula for the signed solid angle of one triangle.
        const Vector3d a = slot_corner(t, 0) - p, b = slot_corner(t, 1) - p, c = slot_corner(t, 2) - p;
        const double la = a.norm(), lb = b.norm(), lc = c.norm();
        const double numerator = a.dot(b.cross(c));
        const double denominator = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
        solid_angle += 2.0 * std::atan2(numerator, denominator);
      }
      continue;
    }
    stack[top++] = node.right;
    stack[top++] = static_cast<int>(index) + 1;
  }
  return solid_angle / (4.0 * std::numbers::pi);
}

void TriangleBvh::overlapping(const Vector3d& lo_abs, const Vector3d& hi_abs, const std::function<void(int)>& visit) const {
  if (nodes_.empty()) return;
  const Vector3d lo = lo_abs - origin_, hi = hi_abs - origin_;
  int stack[128];
  int top = 0;
  stack[top++] = 0;
  while (top > 0) {
    const Node& node = nodes_[static_cast<std::size_t>(stack[--top])];
    if ((node.lo.array() > hi.array()).any() || (node.hi.array() < lo.array()).any()) continue;
    if (node.count > 0) {
      for (int i = node.first; i < node.first + node.count; ++i) {
        const std::size_t slot = static_cast<std::size_t>(i);
        const Vector3d &a = slot_corner(slot, 0), &b = slot_corner(slot, 1), &c = slot_corner(slot, 2);
        const Vector3d tlo = a.cwiseMin(b).cwiseMin(c), thi = a.cwiseMax(b).cwiseMax(c);
        if ((tlo.array() <= hi.array()).all() && (thi.array() >= lo.array()).all()) visit(order_[slot]);
      }
      continue;
    }
    const int self = static_cast<int>(&node - nodes_.data());
    stack[top++] = node.right;
    stack[top++] = self + 1;
  }
}

}  // namespace pointsurf
