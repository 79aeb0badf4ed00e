// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/evaluate/triangle_bvh.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <numbers>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "pointsurf/core/error.h"

namespace pointsurf {
namespace {

constexpr int kLeafSize = 4;

// Nodes of the subtree over n triangles: the median split fixes the shape, so every subtree's
// place in the node array is known before it is built and the halves build in parallel.
int subtree_nodes(int n) { return n <= kLeafSize ? 1 : 1 + subtree_nodes(n / 2) + subtree_nodes(n - n / 2); }

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

// Squared distances from a query to the 4 float boxes of a wide node, computed in float lanes
// and never above the exact ones: the query is rounded down and up to float, each gap taken
// against the side that shrinks it, and the sum scaled by 1 - 1e-6, more than the float
// rounding of the subtractions, squares and sums can add (relative 2^-24 each). Coordinates
// below 1e15 keep the squares finite.
class BoxLanes {
public:
  explicit BoxLanes(const Vector3d& p) {
    for (int a = 0; a < 3; ++a) {
      float down = static_cast<float>(p[a]), up = down;
      if (static_cast<double>(down) > p[a]) down = std::nextafter(down, -std::numeric_limits<float>::infinity());
      if (static_cast<double>(up) < p[a]) up = std::nextafter(up, std::numeric_limits<float>::infinity());
#if defined(__SSE2__)
      down_[a] = _mm_set1_ps(down);
      up_[a] = _mm_set1_ps(up);
#else
      down_[a] = down;
      up_[a] = up;
#endif
    }
  }
  template <class Node>
  void distances(const Node& w, double* d2) const {
#if defined(__SSE2__)
    const __m128 zero = _mm_setzero_ps();
    __m128 sum = zero;
    for (int a = 0; a < 3; ++a) {
      const __m128 below = _mm_sub_ps(_mm_load_ps(w.lo[a]), up_[a]), above = _mm_sub_ps(down_[a], _mm_load_ps(w.hi[a]));
      const __m128 g = _mm_max_ps(_mm_max_ps(below, above), zero);
      sum = _mm_add_ps(sum, _mm_mul_ps(g, g));
    }
    alignas(16) float s[4];
    _mm_store_ps(s, sum);
#else
    float s[4];
    for (int k = 0; k < 4; ++k) {
      s[k] = 0.0f;
      for (int a = 0; a < 3; ++a) {
        const float g = std::max({w.lo[a][k] - up_[a], down_[a] - w.hi[a][k], 0.0f});
        s[k] += g * g;
      }
    }
#endif
    for (int k = 0; k < 4; ++k) d2[k] = static_cast<double>(s[k]) * (1.0 - 1e-6);
  }

private:
#if defined(__SSE2__)
  __m128 down_[3], up_[3];
#else
  float down_[3], up_[3];
#endif
};

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

// What the median-split build moves: a triangle's centroid with its index, so the loops over a
// node's triangles run through memory in order.
struct TriangleBvh::BuildItem {
  Vector3d centroid;
  int triangle;
  BuildItem() {}  // NOLINT(modernize-use-equals-default): a vector of them is filled at once
  BuildItem(const Vector3d& c, int t) : centroid(c), triangle(t) {}
};

struct TriangleBvh::BuildInput {
  std::span<const Vector3d> vertices;
  std::span<const Triangle> triangles;
};

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
  if (f == 0) return;
  std::vector<BuildItem> items(f);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, f), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t t = range.begin(); t != range.end(); ++t) {
      const Triangle& tri = triangles[t];
      const Vector3d sum = (vertices[static_cast<std::size_t>(tri[0])] - origin_) + (vertices[static_cast<std::size_t>(tri[1])] - origin_) +
                           (vertices[static_cast<std::size_t>(tri[2])] - origin_);
      items[t] = BuildItem(sum / 3.0, static_cast<int>(t));
    }
  });
  nodes_.resize(static_cast<std::size_t>(subtree_nodes(static_cast<int>(f))));
  build(0, 0, static_cast<int>(f), items, BuildInput{vertices, triangles}, 0);
  // Corners in leaf order: a leaf's triangles lie side by side in memory.
  order_.resize(f);
  slot_.resize(f);
  corners_.resize(f);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, f), [&](const tbb::blocked_range<std::size_t>& range) {
    for (std::size_t i = range.begin(); i != range.end(); ++i) {
      const std::size_t t = static_cast<std::size_t>(items[i].triangle);
      order_[i] = static_cast<int>(t);
      slot_[t] = static_cast<int>(i);
      for (int c = 0; c < 3; ++c) corners_[i].c[c] = vertices[static_cast<std::size_t>(triangles[t][c])] - origin_;
    }
  });
  wide_.reserve(nodes_.size() / 2 + 1);
  collapse(0);
}

void TriangleBvh::build(int index, int begin, int end, std::vector<BuildItem>& items, const BuildInput& in, int depth) {
  Node& node = nodes_[static_cast<std::size_t>(index)];
  const int n = end - begin;
  if (n <= kLeafSize) {
    node.lo = Vector3d::Constant(std::numeric_limits<double>::infinity());
    node.hi = -node.lo;
    for (int i = begin; i < end; ++i)
      for (int c = 0; c < 3; ++c) {
        // The same rounding as the corners stored after the build.
        const Triangle& t = in.triangles[static_cast<std::size_t>(items[static_cast<std::size_t>(i)].triangle)];
        const Vector3d v = in.vertices[static_cast<std::size_t>(t[c])] - origin_;
        node.lo = node.lo.cwiseMin(v);
        node.hi = node.hi.cwiseMax(v);
      }
    node.first = begin;
    node.count = n;
    return;
  }
  Vector3d clo = Vector3d::Constant(std::numeric_limits<double>::infinity()), chi = -clo;
  for (int i = begin; i < end; ++i) {
    const Vector3d& c = items[static_cast<std::size_t>(i)].centroid;
    clo = clo.cwiseMin(c);
    chi = chi.cwiseMax(c);
  }
  int axis = 0;
  (chi - clo).maxCoeff(&axis);
  const int mid = begin + n / 2;
  std::nth_element(items.begin() + begin, items.begin() + mid, items.begin() + end,
                   [axis](const BuildItem& x, const BuildItem& y) { return x.centroid[axis] < y.centroid[axis]; });
  const int left = index + 1, right = index + 1 + subtree_nodes(mid - begin);
  node.count = 0;
  node.right = right;
  if (n > 4096 && depth < 16)
    tbb::parallel_invoke([&] { build(left, begin, mid, items, in, depth + 1); }, [&] { build(right, mid, end, items, in, depth + 1); });
  else {
    build(left, begin, mid, items, in, depth + 1);
    build(right, mid, end, items, in, depth + 1);
  }
  // Boxes bottom-up: the union of the children's.
  const Node &l = nodes_[static_cast<std::size_t>(left)], &r = nodes_[static_cast<std::size_t>(right)];
  node.lo = l.lo.cwiseMin(r.lo);
  node.hi = l.hi.cwiseMax(r.hi);
}

int TriangleBvh::collapse(int index) {
  // The children of a wide node: the binary node's two, the one of largest box split into its
  // own two while fewer than 4 and one is not a leaf.
  int kids[4];
  int n = 0;
  const Node& top = nodes_[static_cast<std::size_t>(index)];
  if (top.count > 0) kids[n++] = index;  // a root that is a leaf
  else {
    kids[n++] = index + 1;
    kids[n++] = top.right;
  }
  while (n < 4) {
    int pick = -1;
    double largest = -1.0;
    for (int k = 0; k < n; ++k) {
      const Node& c = nodes_[static_cast<std::size_t>(kids[k])];
      if (c.count > 0) continue;
      const Vector3d e = c.hi - c.lo;
      const double area = e.x() * e.y() + e.y() * e.z() + e.z() * e.x();
      if (area > largest) {
        largest = area;
        pick = k;
      }
    }
    if (pick < 0) break;
    const int split = kids[pick];
    for (int k = pick; k + 1 < n; ++k) kids[k] = kids[k + 1];  // keeps the children in walk order
    kids[n - 1] = split + 1;
    kids[n++] = nodes_[static_cast<std::size_t>(split)].right;
  }
  const int self = static_cast<int>(wide_.size());
  wide_.emplace_back();
  for (int k = 0; k < 4; ++k) {
    WideNode& w = wide_[static_cast<std::size_t>(self)];
    if (k >= n) {
      for (int a = 0; a < 3; ++a) {
        w.lo[a][k] = std::numeric_limits<float>::infinity();
        w.hi[a][k] = -std::numeric_limits<float>::infinity();
      }
      w.child[k] = 0;
      w.count[k] = -1;
      continue;
    }
    const Node& c = nodes_[static_cast<std::size_t>(kids[k])];
    for (int a = 0; a < 3; ++a) {
      float lo = static_cast<float>(c.lo[a]), hi = static_cast<float>(c.hi[a]);
      if (static_cast<double>(lo) > c.lo[a]) lo = std::nextafter(lo, -std::numeric_limits<float>::infinity());
      if (static_cast<double>(hi) < c.hi[a]) hi = std::nextafter(hi, std::numeric_limits<float>::infinity());
      w.lo[a][k] = lo;
      w.hi[a][k] = hi;
    }
    w.count[k] = c.count;
    w.child[k] = c.count > 0 ? c.first : 0;
  }
  for (int k = 0; k < n; ++k) {
    const Node& c = nodes_[static_cast<std::size_t>(kids[k])];
    if (c.count == 0) {
      const int child = collapse(kids[k]);  // may move wide_
      wide_[static_cast<std::size_t>(self)].child[k] = child;
    }
  }
  return self;
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

ClosestPoint TriangleBvh::closest(const Vector3d& query, double max_distance) const { return closest_near(query, -1, max_distance); }

ClosestPoint TriangleBvh::closest_near(const Vector3d& query, int hint, double max_distance) const {
  ClosestPoint best;
  if (wide_.empty()) return best;
  const Vector3d p = query - origin_;
  double best2 = max_distance * max_distance;
  // The hinted triangle's distance bounds the walk from the start; it answers unless a nearer
  // triangle, or one as near of smaller index, is found.
  if (hint >= 0 && static_cast<std::size_t>(hint) < slot_.size()) {
    const Corners& t = corners_[static_cast<std::size_t>(slot_[static_cast<std::size_t>(hint)])];
    ClosestPoint c = closest_point_on_triangle(p, t[0], t[1], t[2]);
    if (c.squared_distance <= best2) {
      best2 = c.squared_distance;
      c.triangle = hint;
      best = c;
    }
  }
  // A box is skipped when farther than the best so far widened by kPruneSlack, so rounding in
  // the box distance never skips a triangle tied with the best (the smaller index wins).
  constexpr double kPruneSlack = 1.0 + 1e-12;
  struct Entry {
    int ref, count;  // count > 0: leaf slots [ref, ref + count); 0: wide node ref
    double d2;
  };
  // The 4 box distances in float lanes where the query is within float range of the origin.
  std::optional<BoxLanes> lanes;
  if (p.cwiseAbs().maxCoeff() < 1e15) lanes.emplace(p);
  Entry stack[256];
  int top = 0;
  stack[top++] = {0, 0, 0.0};
  while (top > 0) {
    const Entry e = stack[--top];
    if (e.d2 > best2 * kPruneSlack) continue;
    if (e.count > 0) {
      for (int i = e.ref; i < e.ref + e.count; ++i) {
        const std::size_t slot = static_cast<std::size_t>(i);
        const Corners& t = corners_[slot];
        ClosestPoint c = closest_point_on_triangle(p, t[0], t[1], t[2]);
        const int triangle = order_[slot];
        if (best.found() ? c.squared_distance < best2 || (c.squared_distance == best2 && triangle < best.triangle) : c.squared_distance <= best2) {
          best2 = c.squared_distance;
          c.triangle = triangle;
          best = c;
        }
      }
      continue;
    }
    const WideNode& w = wide_[static_cast<std::size_t>(e.ref)];
    double d2[4];
    if (lanes) lanes->distances(w, d2);
    else
      for (int k = 0; k < 4; ++k) {
        double s = 0.0;
        for (int a = 0; a < 3; ++a) {
          const double g = std::max({static_cast<double>(w.lo[a][k]) - p[a], p[a] - static_cast<double>(w.hi[a][k]), 0.0});
          s += g * g;
        }
        d2[k] = s;
      }
    // The children within reach, pushed farthest first so the nearest is walked first.
    Entry near[4];
    int m = 0;
    const double reach = best2 * kPruneSlack;
    for (int k = 0; k < 4; ++k) {
      if (w.count[k] < 0 || d2[k] > reach) continue;
      Entry x{w.child[k], w.count[k], d2[k]};
      int j = m++;
      while (j > 0 && near[j - 1].d2 < x.d2) {
        near[j] = near[j - 1];
        --j;
      }
      near[j] = x;
    }
    for (int j = 0; j < m; ++j) stack[top++] = near[j];
  }
  if (best.found()) best.point += origin_;
  return best;
}

ClosestPoint TriangleBvh::closest_near(const Vector3d& query, const std::optional<Vector3d>& on_mesh, double max_distance) const {
  // A point of the mesh at distance b from the query bounds the answer by b, so boxes farther
  // than b are skipped from the start. They hold no closest triangle, and ties go to the
  // smallest index whatever the walk, so the answer is the same. The bound is widened by 1e-9
  // against rounding; should nothing lie within it, the plain walk answers.
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
  if (wide_.empty()) return;
  const Vector3d lo = lo_abs - origin_, hi = hi_abs - origin_;
  struct Entry {
    int ref, count;
  };
  Entry stack[256];
  int top = 0;
  stack[top++] = {0, 0};
  while (top > 0) {
    const Entry e = stack[--top];
    if (e.count > 0) {
      for (int i = e.ref; i < e.ref + e.count; ++i) {
        const std::size_t slot = static_cast<std::size_t>(i);
        const Vector3d &a = slot_corner(slot, 0), &b = slot_corner(slot, 1), &c = slot_corner(slot, 2);
        const Vector3d tlo = a.cwiseMin(b).cwiseMin(c), thi = a.cwiseMax(b).cwiseMax(c);
        if ((tlo.array() <= hi.array()).all() && (thi.array() >= lo.array()).all()) visit(order_[slot]);
      }
      continue;
    }
    // Float boxes rounded outward: a box that misses [lo, hi] misses it in double too.
    const WideNode& w = wide_[static_cast<std::size_t>(e.ref)];
    for (int k = 3; k >= 0; --k) {
      if (w.count[k] < 0) continue;
      bool apart = false;
      for (int a = 0; a < 3; ++a) apart |= static_cast<double>(w.lo[a][k]) > hi[a] || static_cast<double>(w.hi[a][k]) < lo[a];
      if (!apart) stack[top++] = {w.child[k], w.count[k]};
    }
  }
}

}  // namespace pointsurf
