// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/evaluate/triangle_bvh.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <numbers>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "core/detail/progress_reporter.h"
#include "pointsurf/core/error.h"

namespace pointsurf {
namespace {

constexpr int kLeafSize = 4;

// The split: the left part a multiple of 4, so every node but those of the last slots begins at
// a multiple of 4 and every leaf but the last holds 4 triangles, one block of float lanes.
int left_size(int n) { return (n / 2 + 3) / 4 * 4; }

// Nodes of the subtree over n triangles: the split fixes the shape, so every subtree's place in
// the node array is known before it is built and the halves build in parallel.
int subtree_nodes(int n) { return n <= kLeafSize ? 1 : n % 4 == 0 ? n / 2 - 1 : 1 + subtree_nodes(left_size(n)) + subtree_nodes(n - left_size(n)); }

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
  BoxLanes(const Vector3d& p, double corner_extent) {
    // How far rounding the query and the corners to float can move a distance (each coordinate
    // by half an ulp, 2^-24 relative, at most), doubled.
    shift_ = static_cast<float>(4.0 * 0x1p-24 * std::sqrt(3.0) * (p.cwiseAbs().maxCoeff() + corner_extent) * 1.001);
    for (int a = 0; a < 3; ++a) {
#if defined(__SSE2__)
      near_[a] = _mm_set1_ps(static_cast<float>(p[a]));
#endif
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

  // Lower bounds of the squared distances from the query to the 4 triangles of a leaf, none
  // above the exact distance to the double triangle. In float lanes: the distance to the plane
  // when the query's projection lies inside the float triangle or within the rounding of its
  // barycentric coordinates (the plane is never farther than the triangle), else the nearest of
  // the 3 edges (the exact distance when outside). Less an allowance of 2^-15 of the squared
  // lengths involved (float arithmetic errs by a few 2^-24 of them), the root less the shift
  // of rounding the query and the corners to float. Without SSE2: 0, the exact test decides.
  template <class Lanes>
  void triangle_bounds(const Lanes& l, float* lb2) const {
#if defined(__SSE2__)
    const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f);
    const __m128 tol = _mm_set1_ps(16.0f * 0x1p-24f), allowance = _mm_set1_ps(0x1p-15f);
    __m128 ap[3], bp[3], bc[3];
    for (int i = 0; i < 3; ++i) {
      ap[i] = _mm_sub_ps(near_[i], _mm_load_ps(l.a[i]));
      bp[i] = _mm_sub_ps(ap[i], _mm_load_ps(l.ab[i]));
      bc[i] = _mm_sub_ps(_mm_load_ps(l.ac[i]), _mm_load_ps(l.ab[i]));
    }
    auto dot = [](const __m128* x, const float (*y)[4]) {
      return _mm_add_ps(_mm_add_ps(_mm_mul_ps(x[0], _mm_load_ps(y[0])), _mm_mul_ps(x[1], _mm_load_ps(y[1]))), _mm_mul_ps(x[2], _mm_load_ps(y[2])));
    };
    auto dot3 = [](const __m128* x, const __m128* y) {
      return _mm_add_ps(_mm_add_ps(_mm_mul_ps(x[0], y[0]), _mm_mul_ps(x[1], y[1])), _mm_mul_ps(x[2], y[2]));
    };
    // Squared distance from point x (about the edge's start) to the edge e with 1/|e|^2.
    auto edge = [&](const __m128* x, const __m128* e, __m128 inv) {
      const __m128 t = _mm_min_ps(_mm_max_ps(_mm_mul_ps(dot3(x, e), inv), zero), one);
      __m128 v[3];
      for (int i = 0; i < 3; ++i) v[i] = _mm_sub_ps(x[i], _mm_mul_ps(t, e[i]));
      return dot3(v, v);
    };
    __m128 ab[3], ac[3];
    for (int i = 0; i < 3; ++i) {
      ab[i] = _mm_load_ps(l.ab[i]);
      ac[i] = _mm_load_ps(l.ac[i]);
    }
    const __m128 ap2 = dot3(ap, ap), ap_len = _mm_sqrt_ps(ap2);
    const __m128 plane = dot(ap, l.n), bary_b = dot(ap, l.gb), bary_c = dot(ap, l.gc);
    const __m128 tb = _mm_mul_ps(tol, _mm_mul_ps(_mm_load_ps(l.gb_norm), ap_len));
    const __m128 tc = _mm_mul_ps(tol, _mm_mul_ps(_mm_load_ps(l.gc_norm), ap_len));
    const __m128 inside = _mm_and_ps(_mm_and_ps(_mm_cmpge_ps(bary_b, _mm_sub_ps(zero, tb)), _mm_cmpge_ps(bary_c, _mm_sub_ps(zero, tc))),
                                     _mm_cmpge_ps(_mm_sub_ps(_mm_sub_ps(one, bary_b), bary_c), _mm_sub_ps(zero, _mm_add_ps(_mm_add_ps(tb, tc), tol))));
    const __m128 edges = _mm_min_ps(_mm_min_ps(edge(ap, ab, _mm_load_ps(l.inv_ab2)), edge(ap, ac, _mm_load_ps(l.inv_ac2))),
                                    edge(bp, bc, _mm_load_ps(l.inv_bc2)));
    const __m128 d2 = _mm_or_ps(_mm_and_ps(inside, _mm_mul_ps(plane, plane)), _mm_andnot_ps(inside, edges));
    const __m128 slack = _mm_mul_ps(allowance, _mm_add_ps(ap2, _mm_load_ps(l.edges2)));
    const __m128 root = _mm_sub_ps(_mm_sqrt_ps(_mm_max_ps(_mm_sub_ps(d2, slack), zero)), _mm_set1_ps(shift_));
    const __m128 lb = _mm_max_ps(root, zero);
    _mm_storeu_ps(lb2, _mm_mul_ps(_mm_mul_ps(lb, lb), _mm_set1_ps(1.0f - 1e-6f)));
#else
    (void)l;
    for (int k = 0; k < 4; ++k) lb2[k] = 0.0f;
#endif
  }

private:
#if defined(__SSE2__)
  __m128 down_[3], up_[3], near_[3];
#else
  float down_[3], up_[3];
#endif
  float shift_ = 0.0f;
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
  detail::ProgressReporter* reporter;  // advanced by the triangles of each finished subtree below kReportItems
};

namespace {
// Subtrees of at most this many triangles report when finished (a few hundred reports on 1M).
constexpr int kReportItems = 4096;
// Shares of the build's time (1.2M triangles): centroids, the recursive split, corners in
// leaf order, the wide nodes, the float lanes.
constexpr double kShareSplit = 0.6, kShareCorners = 0.75, kShareCollapse = 0.85;
}  // namespace

TriangleBvh::TriangleBvh(std::span<const Vector3d> vertices, std::span<const Triangle> triangles, const ProgressCallback& progress) {
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
  {
    detail::ProgressReporter reporter(progress, 0.05, kShareSplit, f);
    reporter.report(0.05);
    build(0, 0, static_cast<int>(f), items, BuildInput{vertices, triangles, &reporter}, 0);
    reporter.throw_if_cancelled();
  }
  if (progress && !progress(kShareSplit)) throw CancelledError();
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
  if (progress && !progress(kShareCorners)) throw CancelledError();
  wide_.reserve(nodes_.size() / 2 + 1);
  collapse(0);
  if (progress && !progress(kShareCollapse)) throw CancelledError();
  make_lanes();
  if (progress && !progress(1.0)) throw CancelledError();
}

void TriangleBvh::make_lanes() {
  const std::size_t f = corners_.size();
  lanes_.resize((f + 3) / 4);
  corner_extent_ = tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, lanes_.size()), 0.0,
      [&](const tbb::blocked_range<std::size_t>& range, double extent) {
        for (std::size_t b = range.begin(); b != range.end(); ++b) {
          LeafLanes& l = lanes_[b];
          std::memset(static_cast<void*>(&l), 0, sizeof(LeafLanes));
          for (std::size_t k = 0; k < 4 && 4 * b + k < f; ++k) {
            const Corners& t = corners_[4 * b + k];
            for (int c = 0; c < 3; ++c) extent = std::max(extent, t[static_cast<std::size_t>(c)].cwiseAbs().maxCoeff());
            // The float triangle: corners rounded to float; its edges from those.
            Eigen::Vector3f a = t[0].cast<float>(), b2 = t[1].cast<float>(), c2 = t[2].cast<float>();
            const Eigen::Vector3f ab = b2 - a, ac = c2 - a, bc = ac - ab;
            const Vector3d e1 = ab.cast<double>(), e2 = ac.cast<double>(), e3 = bc.cast<double>();
            for (int i = 0; i < 3; ++i) {
              l.a[i][k] = a[i];
              l.ab[i][k] = ab[i];
              l.ac[i][k] = ac[i];
            }
            const double l1 = e1.squaredNorm(), l2 = e2.squaredNorm(), l3 = e3.squaredNorm();
            l.inv_ab2[k] = l1 > 0.0 ? static_cast<float>(1.0 / l1) : 0.0f;
            l.inv_ac2[k] = l2 > 0.0 ? static_cast<float>(1.0 / l2) : 0.0f;
            l.inv_bc2[k] = l3 > 0.0 ? static_cast<float>(1.0 / l3) : 0.0f;
            l.edges2[k] = static_cast<float>(l1 + l2 + l3);
            const Vector3d cross = e1.cross(e2);
            const double det = cross.squaredNorm();
            if (!(det > 1e-12 * l1 * l2) || !std::isfinite(det)) continue;  // nearly degenerate: bound 0, the exact test decides
            const Vector3d n = cross / std::sqrt(det);
            const double d12 = e1.dot(e2);
            const Vector3d gb = (l2 * e1 - d12 * e2) / det, gc = (l1 * e2 - d12 * e1) / det;
            for (int i = 0; i < 3; ++i) {
              l.n[i][k] = static_cast<float>(n[i]);
              l.gb[i][k] = static_cast<float>(gb[i]);
              l.gc[i][k] = static_cast<float>(gc[i]);
            }
            l.gb_norm[k] = static_cast<float>(gb.norm());
            l.gc_norm[k] = static_cast<float>(gc.norm());
          }
        }
        return extent;
      },
      [](double x, double y) { return std::max(x, y); });
}

void TriangleBvh::build(int index, int begin, int end, std::vector<BuildItem>& items, const BuildInput& in, int depth) {
  const int n = end - begin;
  if (n <= kReportItems && in.reporter != nullptr) {
    // A subtree small enough to report when finished; below it, no reporting.
    if (in.reporter->cancelled()) return;
    build(index, begin, end, items, BuildInput{in.vertices, in.triangles, nullptr}, depth);
    in.reporter->advance(static_cast<std::size_t>(n));
    return;
  }
  Node& node = nodes_[static_cast<std::size_t>(index)];
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
  const int mid = begin + left_size(n);
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
  if (p.cwiseAbs().maxCoeff() < 1e15 && corner_extent_ < 1e15) lanes.emplace(p, corner_extent_);
  Entry stack[256];
  int top = 0;
  stack[top++] = {0, 0, 0.0};
  while (top > 0) {
    const Entry e = stack[--top];
    if (e.d2 > best2 * kPruneSlack) continue;
    if (e.count > 0) {
      float lb2[4] = {0.0f, 0.0f, 0.0f, 0.0f};
      if (lanes) lanes->triangle_bounds(lanes_[static_cast<std::size_t>(e.ref / 4)], lb2);
      for (int i = e.ref; i < e.ref + e.count; ++i) {
        if (static_cast<double>(lb2[i - e.ref]) > best2 * kPruneSlack) continue;
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
#if defined(__SSE2__)
  __m128 qlo[3], qhi[3];
  for (int a = 0; a < 3; ++a) {
    float down = static_cast<float>(lo[a]), up = static_cast<float>(hi[a]);
    if (static_cast<double>(down) > lo[a]) down = std::nextafter(down, -std::numeric_limits<float>::infinity());
    if (static_cast<double>(up) < hi[a]) up = std::nextafter(up, std::numeric_limits<float>::infinity());
    qlo[a] = _mm_set1_ps(down);
    qhi[a] = _mm_set1_ps(up);
  }
#endif
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
    // Float boxes rounded outward against [lo, hi] rounded outward: a box apart from it in
    // float is apart in double too.
    const WideNode& w = wide_[static_cast<std::size_t>(e.ref)];
#if defined(__SSE2__)
    __m128 apart = _mm_setzero_ps();
    for (int a = 0; a < 3; ++a)
      apart = _mm_or_ps(apart, _mm_or_ps(_mm_cmpgt_ps(_mm_load_ps(w.lo[a]), qhi[a]), _mm_cmplt_ps(_mm_load_ps(w.hi[a]), qlo[a])));
    const int apart_mask = _mm_movemask_ps(apart);
#endif
    for (int k = 3; k >= 0; --k) {
      if (w.count[k] < 0) continue;
#if defined(__SSE2__)
      if (!(apart_mask & (1 << k))) stack[top++] = {w.child[k], w.count[k]};
#else
      bool apart = false;
      for (int a = 0; a < 3; ++a) apart |= static_cast<double>(w.lo[a][k]) > hi[a] || static_cast<double>(w.hi[a][k]) < lo[a];
      if (!apart) stack[top++] = {w.child[k], w.count[k]};
#endif
    }
  }
}

}  // namespace pointsurf
