// SPDX-License-Identifier: GPL-3.0-or-later
// Short handles (topological noise): found by growing geodesic balls and watching their front
// meet itself, removed by cutting along the loop and closing both sides (reconstruct/handles.h).
#include "pointsurf/reconstruct/handles.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <queue>
#include <span>
#include <utility>

#include <fmt/format.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "core/detail/progress_reporter.h"
#include "pointsurf/core/error.h"
#include "pointsurf/core/mesh_topology.h"

namespace pointsurf {
namespace {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
constexpr int kRounds = 8;
// A cap is the minimum-area triangulation of its loop, cubic in its corners.
constexpr std::size_t kMaxCapCorners = 256;
// Seeds cover the surface to a quarter of the limit; balls grow to 3/4 of it, so that a loop at
// most the limit long lies in the ball of a seed near it.
constexpr double kCoverShare = 0.25, kRadiusShare = 0.75;

// The mesh seen from its vertices: the triangles at each vertex and, for vertices with one
// consistently oriented fan, the ring of neighbours counter-clockwise with the triangle between
// each neighbour and the next. Each hole is closed by a virtual vertex (ids n and up, one per
// boundary loop) joined to the loop's vertices: a border vertex's ring ends with it, through
// two virtual triangles (kNone). The virtual vertices never join a ball, but the searches on
// either side of a loop pass through them, so that a surface with holes is seen as the closed
// surface of the same genus.
struct Fans {
  std::size_t n = 0;                     // real vertices
  std::vector<std::uint32_t> offset;     // n + 1: corners of each vertex (adjacent: 2 per corner)
  std::vector<std::uint32_t> adjacent;   // every real v: the other two corners of each triangle
                                         // (duplicates kept)
  std::vector<std::uint32_t> ring_offset;  // n + 1
  std::vector<std::uint32_t> ring;       // one-fan v: counter-clockwise, a virtual vertex last on a border
  std::vector<std::uint32_t> face;       // triangle (v, ring[j], ring[j + 1]); kNone where virtual
  std::vector<std::uint8_t> interior;    // real, one fan (closed, or open on a border): grown over
  std::vector<std::uint32_t> hole_offset, hole_members;  // virtual vertex n + h: its loop's vertices

  std::size_t total() const { return n + hole_offset.size() - 1; }
  std::uint32_t degree(std::uint32_t v) const { return ring_offset[v + 1] - ring_offset[v]; }
  // Position of w in v's ring, or kNone.
  std::uint32_t find(std::uint32_t v, std::uint32_t w) const {
    for (std::uint32_t j = ring_offset[v]; j < ring_offset[v + 1]; ++j)
      if (ring[j] == w) return j - ring_offset[v];
    return kNone;
  }
  bool adjacent_to(std::uint32_t v, std::uint32_t w) const {
    for (std::uint32_t j = 2 * offset[v]; j < 2 * offset[v + 1]; ++j)
      if (adjacent[j] == w) return true;
    return false;
  }
  // Calls f(w) for each neighbour of v (real or virtual).
  template <class F>
  void for_each_neighbour(std::uint32_t v, F&& f) const {
    if (v >= n) {
      const std::size_t h = v - n;
      for (std::uint32_t j = hole_offset[h]; j < hole_offset[h + 1]; ++j) f(hole_members[j]);
    } else if (interior[v]) {
      for (std::uint32_t j = ring_offset[v]; j < ring_offset[v + 1]; ++j) f(ring[j]);
    } else {
      for (std::uint32_t j = 2 * offset[v]; j < 2 * offset[v + 1]; ++j) f(adjacent[j]);
    }
  }
};

Fans build_fans(const std::vector<Triangle>& triangles, std::size_t n) {
  Fans fans;
  fans.n = n;
  fans.offset.assign(n + 1, 0);
  for (const Triangle& t : triangles)
    for (int c = 0; c < 3; ++c) ++fans.offset[std::size_t(t[c]) + 1];
  for (std::size_t v = 0; v < n; ++v) fans.offset[v + 1] += fans.offset[v];
  const std::size_t corners = fans.offset[n];
  std::vector<std::uint32_t> around(corners);
  {
    std::vector<std::uint32_t> cursor(fans.offset.begin(), fans.offset.end() - 1);
    for (std::size_t t = 0; t < triangles.size(); ++t)
      for (int c = 0; c < 3; ++c) around[cursor[std::size_t(triangles[t][c])]++] = static_cast<std::uint32_t>(t);
  }
  fans.adjacent.assign(2 * corners, kNone);
  // Per vertex: 0 no usable fan, 1 closed, 2 open (a border); the fan's triangles in order in
  // `ordered` (same slots as `around`) with the neighbour each starts with in `first`.
  std::vector<std::uint8_t> kind(n, 0);
  std::vector<std::uint32_t> ordered(corners, kNone), first(corners, kNone), last_of(n, kNone);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<std::uint32_t> next, prev;
    for (std::size_t v = r.begin(); v != r.end(); ++v) {
      const std::uint32_t begin = fans.offset[v], end = fans.offset[v + 1], d = end - begin;
      if (d == 0) continue;
      next.clear();
      prev.clear();
      for (std::uint32_t i = begin; i < end; ++i) {
        const Triangle& t = triangles[around[i]];
        const int c = std::size_t(t[0]) == v ? 0 : std::size_t(t[1]) == v ? 1 : 2;
        next.push_back(std::uint32_t(t[(c + 1) % 3]));
        prev.push_back(std::uint32_t(t[(c + 2) % 3]));
        fans.adjacent[2 * i] = next.back();
        fans.adjacent[2 * i + 1] = prev.back();
      }
      // One fan: each neighbour starts at most one triangle (v, a, b) and ends at most one; the
      // fan is closed when every neighbour does both, open when exactly one only starts.
      bool ok = true;
      std::uint32_t start = kNone, opens = 0, closes = 0;
      for (std::uint32_t i = 0; i < d && ok; ++i) {
        if (next[i] == v || prev[i] == v || next[i] == prev[i]) ok = false;
        int starts = 0, ends = 0, p_starts = 0;
        for (std::uint32_t k = 0; k < d; ++k) {
          starts += next[k] == next[i];
          ends += prev[k] == next[i];
          p_starts += next[k] == prev[i];
        }
        ok = ok && starts == 1 && ends <= 1;
        if (ends == 0) {
          ++opens;
          start = i;
        }
        if (p_starts == 0) ++closes;
      }
      if (!ok || opens > 1 || opens != closes || (opens == 0 && d < 3)) continue;
      std::uint32_t k = opens == 1 ? start : 0;
      std::uint32_t visited = 0;
      for (; visited < d && k != kNone; ++visited) {
        ordered[begin + visited] = around[begin + k];
        first[begin + visited] = next[k];
        const std::uint32_t b = prev[k];
        k = kNone;
        for (std::uint32_t i = 0; i < d; ++i)
          if (next[i] == b) k = i;
        if (opens == 0 && k == (opens == 1 ? start : 0)) {
          ++visited;
          break;
        }
      }
      if (visited != d) continue;
      if (opens == 1) {
        const Triangle& t = triangles[ordered[end - 1]];
        const int c = std::size_t(t[0]) == v ? 0 : std::size_t(t[1]) == v ? 1 : 2;
        last_of[v] = std::uint32_t(t[(c + 2) % 3]);
      } else if (k != 0) {
        continue;
      }
      kind[v] = static_cast<std::uint8_t>(opens == 1 ? 2 : 1);
    }
  });
  // Holes: border vertices joined along their boundary edges.
  std::vector<std::uint32_t> parent(n);
  for (std::size_t v = 0; v < n; ++v) parent[v] = static_cast<std::uint32_t>(v);
  const auto root = [&](std::uint32_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (std::size_t v = 0; v < n; ++v)
    if (kind[v] == 2)
      for (const std::uint32_t w : {first[fans.offset[v]], last_of[v]})
        if (kind[w] == 2) parent[root(std::uint32_t(v))] = root(w);  // not through a pinched vertex: two holes
                                                                       // under one cap would make a handle
  // A hole whose rim passes a pinched or non-manifold vertex is not capped (its rim is not one
  // loop of border vertices): its vertices are not grown over, as without caps.
  std::vector<std::uint8_t> broken(n, 0);
  for (std::size_t v = 0; v < n; ++v)
    if (kind[v] == 2 && (kind[first[fans.offset[v]]] != 2 || kind[last_of[v]] != 2)) broken[root(std::uint32_t(v))] = 1;
  for (std::size_t v = 0; v < n; ++v)
    if (kind[v] == 2 && broken[root(std::uint32_t(v))]) kind[v] = 3;  // a border vertex left out
  for (std::size_t v = 0; v < n; ++v)
    if (kind[v] == 3) kind[v] = 0;
  std::vector<std::uint32_t> hole_of(n, kNone);
  std::uint32_t holes = 0;
  std::vector<std::uint32_t> id_of_root(n, kNone);
  for (std::size_t v = 0; v < n; ++v)
    if (kind[v] == 2) {
      const std::uint32_t r0 = root(std::uint32_t(v));
      if (id_of_root[r0] == kNone) id_of_root[r0] = holes++;
      hole_of[v] = id_of_root[r0];
    }
  fans.hole_offset.assign(holes + 1, 0);
  for (std::size_t v = 0; v < n; ++v)
    if (hole_of[v] != kNone) ++fans.hole_offset[hole_of[v] + 1];
  for (std::uint32_t h = 0; h < holes; ++h) fans.hole_offset[h + 1] += fans.hole_offset[h];
  fans.hole_members.assign(fans.hole_offset[holes], kNone);
  {
    std::vector<std::uint32_t> cursor(fans.hole_offset.begin(), fans.hole_offset.end() - 1);
    for (std::size_t v = 0; v < n; ++v)
      if (hole_of[v] != kNone) fans.hole_members[cursor[hole_of[v]]++] = std::uint32_t(v);
  }
  // Rings: d neighbours of a closed fan; d + 1 and the hole's virtual vertex of an open one.
  fans.ring_offset.assign(n + 1, 0);
  for (std::size_t v = 0; v < n; ++v) {
    const std::uint32_t d = fans.offset[v + 1] - fans.offset[v];
    fans.ring_offset[v + 1] = fans.ring_offset[v] + (kind[v] == 1 ? d : kind[v] == 2 ? d + 2 : 0);
  }
  fans.ring.assign(fans.ring_offset[n], kNone);
  fans.face.assign(fans.ring_offset[n], kNone);
  fans.interior.assign(n + holes, 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t v = r.begin(); v != r.end(); ++v) {
      if (kind[v] == 0) continue;
      const std::uint32_t begin = fans.offset[v], d = fans.offset[v + 1] - begin, out = fans.ring_offset[v];
      for (std::uint32_t j = 0; j < d; ++j) {
        fans.ring[out + j] = first[begin + j];
        fans.face[out + j] = ordered[begin + j];
      }
      if (kind[v] == 2) {
        fans.ring[out + d] = last_of[v];  // face (v, last, hole): virtual
        fans.ring[out + d + 1] = static_cast<std::uint32_t>(n + hole_of[v]);  // face (v, hole, first): virtual
      }
      fans.interior[v] = 1;
    }
  });
  return fans;
}

struct Round {
  std::size_t applied = 0;
  std::vector<HandleLoop> loops;
};

struct Candidate {
  std::vector<std::uint32_t> loop;  // closed, first not repeated
  double length = 0.0;
};

// Where a loop lies: the centroid of its vertices and the largest distance from it. Loops
// closer than `gap` (spheres' distance) are taken for the same handle.
struct LoopSphere {
  Vector3d centre = Vector3d::Zero();
  double radius = 0.0;
  LoopSphere() = default;
  LoopSphere(const std::vector<std::uint32_t>& loop, const std::vector<Vector3d>& p) {
    for (const std::uint32_t v : loop) centre += p[v];
    centre /= double(loop.size());
    for (const std::uint32_t v : loop) radius = std::max(radius, (p[v] - centre).norm());
  }
  bool near(const LoopSphere& o, double gap) const { return (o.centre - centre).norm() < o.radius + radius + gap; }
};

// One geodesic ball at a time (per thread): distances, tree and marks, reset by stamp.
class BallSearch {
public:
  struct Run {
    bool ball;
    std::uint32_t start, count;
  };
  BallSearch(const Fans& fans, const std::vector<Vector3d>& p) : fans_(fans), p_(p), n_(fans.total()) {
    stamp_.assign(n_, 0);
    settled_.assign(n_, 0);
    dist_.assign(n_, 0.0);
    parent_.assign(n_, kNone);
    hops_.assign(n_, 0);
    bfs_stamp_.assign(n_, 0);
    side_.assign(n_, 0);
  }

  // Grows the ball of `seed` up to `radius`; returns the first non-separating loop at most
  // `max_length` long that closes, if any.
  bool grow(std::uint32_t seed, double radius, double max_length, Candidate& found) {
    ++ball_;
    using Item = std::pair<double, std::uint32_t>;
    std::priority_queue<Item, std::vector<Item>, std::greater<>> heap;
    touch(seed);
    dist_[seed] = 0.0;
    parent_[seed] = kNone;
    hops_[seed] = 0;
    heap.emplace(0.0, seed);
    while (!heap.empty()) {
      const auto [d, v] = heap.top();
      heap.pop();
      if (settled_[v] || d > dist_[v]) continue;
      if (d > radius) break;
      settled_[v] = 1;
      if (v != seed && closes_loop(v, max_length, found)) return true;
      for (std::uint32_t j = fans_.ring_offset[v]; j < fans_.ring_offset[v + 1]; ++j) {
        const std::uint32_t w = fans_.ring[j];
        if (w >= fans_.n || !fans_.interior[w]) continue;
        touch(w);
        if (settled_[w]) continue;
        const double nd = d + (p_[w] - p_[v]).norm();
        if (nd < dist_[w]) {
          dist_[w] = nd;
          parent_[w] = v;
          hops_[w] = hops_[v] + 1;
          heap.emplace(nd, w);
        }
      }
    }
    return false;
  }

private:
  void touch(std::uint32_t v) {
    if (stamp_[v] == ball_) return;
    stamp_[v] = ball_;
    settled_[v] = 0;
    dist_[v] = std::numeric_limits<double>::infinity();
  }
  bool in_ball(std::uint32_t v) const { return stamp_[v] == ball_ && settled_[v]; }

  // v has just joined the ball. Its ring splits into arcs of ball vertices and gaps of others;
  // with two arcs or more a loop closes through v. For each gap, the loop through the arcs on
  // either side of it is non-separating when the gap's vertices reach those of the other gaps
  // outside the ball.
  bool closes_loop(std::uint32_t v, double max_length, Candidate& found) {
    const std::uint32_t begin = fans_.ring_offset[v], d = fans_.degree(v);
    std::uint32_t first_gap_start = kNone;
    for (std::uint32_t j = 0; j < d; ++j)
      if (in_ball(fans_.ring[begin + j]) && !in_ball(fans_.ring[begin + (j + 1) % d])) {
        first_gap_start = (j + 1) % d;
        break;
      }
    if (first_gap_start == kNone) return false;  // the ring is all in the ball, or none of it
    // Runs from first_gap_start: gap, arc, gap, arc, ...
    runs_.clear();
    for (std::uint32_t k = 0; k < d; ++k) {
      const std::uint32_t j = (first_gap_start + k) % d;
      const bool ball = in_ball(fans_.ring[begin + j]);
      if (runs_.empty() || runs_.back().ball != ball) runs_.push_back(Run{ball, j, 0});
      ++runs_.back().count;
    }
    if (runs_.size() < 4) return false;  // one gap, one arc: the ball stays a disc
    const std::size_t r = runs_.size();
    for (std::size_t g = 0; g < r; g += 2) {
      if (!gap_reaches_others(v, g)) continue;
      const Run& before = runs_[(g + r - 1) % r];
      const Run& after = runs_[(g + 1) % r];
      const std::uint32_t a = nearest(v, before), b = nearest(v, after);
      if (make_loop(v, a, b, found) && found.length <= max_length) return true;
    }
    return false;
  }

  std::uint32_t nearest(std::uint32_t v, const Run& run) const {
    const std::uint32_t begin = fans_.ring_offset[v], d = fans_.degree(v);
    std::uint32_t best = kNone;
    for (std::uint32_t k = 0; k < run.count; ++k) {
      const std::uint32_t w = fans_.ring[begin + (run.start + k) % d];
      if (best == kNone || dist_[w] + (p_[w] - p_[v]).norm() < dist_[best] + (p_[best] - p_[v]).norm()) best = w;
    }
    return best;
  }

  // The loop v -> a -> ... -> common ancestor -> ... -> b -> v along the shortest-path tree.
  bool make_loop(std::uint32_t v, std::uint32_t a, std::uint32_t b, Candidate& c) {
    path_a_.assign(1, a);
    path_b_.assign(1, b);
    std::uint32_t x = a, y = b;
    while (x != y) {
      if (hops_[x] >= hops_[y]) {
        x = parent_[x];
        if (x == kNone) return false;
        path_a_.push_back(x);
      } else {
        y = parent_[y];
        if (y == kNone) return false;
        path_b_.push_back(y);
      }
    }
    c.loop.assign(1, v);
    c.loop.insert(c.loop.end(), path_a_.begin(), path_a_.end());
    for (std::size_t i = path_b_.size() - 1; i-- > 0;) c.loop.push_back(path_b_[i]);
    c.length = 0.0;
    for (std::size_t i = 0; i < c.loop.size(); ++i) c.length += (p_[c.loop[(i + 1) % c.loop.size()]] - p_[c.loop[i]]).norm();
    return c.loop.size() >= 3;
  }

  // Breadth-first from the gap runs_[g] (side 0) and from the other gaps (side 1), in turn, over
  // vertices outside the ball: true when the two meet, false when either runs out.
  bool gap_reaches_others(std::uint32_t v, std::size_t g) {
    ++bfs_;
    queue_[0].clear();
    queue_[1].clear();
    const std::uint32_t begin = fans_.ring_offset[v], d = fans_.degree(v);
    for (std::size_t k = 0; k < runs_.size(); k += 2) {
      const int side = k == g ? 0 : 1;
      for (std::uint32_t i = 0; i < runs_[k].count; ++i) {
        const std::uint32_t w = fans_.ring[begin + (runs_[k].start + i) % d];
        bfs_stamp_[w] = bfs_;
        side_[w] = static_cast<std::uint8_t>(side);
        queue_[side].push_back(w);
      }
    }
    std::size_t head[2] = {0, 0};
    while (head[0] < queue_[0].size() && head[1] < queue_[1].size()) {
      for (int side = 0; side < 2; ++side) {
        if (head[side] >= queue_[side].size()) return false;
        const std::uint32_t x = queue_[side][head[side]++];
        bool met = false;
        fans_.for_each_neighbour(x, [&](std::uint32_t w) {
          if (met || w == v || in_ball(w)) return;
          if (bfs_stamp_[w] == bfs_) {
            met = side_[w] != side;
            return;
          }
          bfs_stamp_[w] = bfs_;
          side_[w] = static_cast<std::uint8_t>(side);
          queue_[side].push_back(w);
        });
        if (met) return true;
      }
    }
    return false;
  }

  const Fans& fans_;
  const std::vector<Vector3d>& p_;
  std::size_t n_;
  std::uint32_t ball_ = 0, bfs_ = 0;
  std::vector<std::uint32_t> stamp_, parent_, hops_, bfs_stamp_;
  std::vector<std::uint8_t> settled_, side_;
  std::vector<double> dist_;
  std::vector<Run> runs_;
  std::vector<std::uint32_t> path_a_, path_b_, queue_[2];
};

// Dijkstra along the edges from `sources` up to `reach`: visit(v) once for each vertex reached,
// over the rings of interior vertices when `interior_only`, else over every edge. `dist` (size
// n, all infinite) is left as it was found; `reached` is a buffer.
template <class Visit>
void grow_within(const Fans& fans, const std::vector<Vector3d>& p, std::span<const std::uint32_t> sources, double reach, bool interior_only,
                 std::vector<double>& dist, std::vector<std::uint32_t>& reached, Visit&& visit) {
  using Item = std::pair<double, std::uint32_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> heap;
  reached.clear();
  for (const std::uint32_t s : sources) {
    if (std::isfinite(dist[s])) continue;
    dist[s] = 0.0;
    reached.push_back(s);
    heap.emplace(0.0, s);
  }
  const auto relax = [&](std::uint32_t v, double d, std::uint32_t w) {
    const double nd = d + (p[w] - p[v]).norm();
    if (nd <= reach && nd < dist[w]) {
      if (!std::isfinite(dist[w])) reached.push_back(w);
      dist[w] = nd;
      heap.emplace(nd, w);
    }
  };
  while (!heap.empty()) {
    const auto [d, v] = heap.top();
    heap.pop();
    if (d > dist[v]) continue;
    visit(v);
    if (interior_only) {
      for (std::uint32_t j = fans.ring_offset[v]; j < fans.ring_offset[v + 1]; ++j)
        if (const std::uint32_t w = fans.ring[j]; w < fans.n && fans.interior[w]) relax(v, d, w);
    } else {
      for (std::uint32_t j = 2 * fans.offset[v]; j < 2 * fans.offset[v + 1]; ++j) relax(v, d, fans.adjacent[j]);
    }
  }
  for (const std::uint32_t v : reached) dist[v] = std::numeric_limits<double>::infinity();
}

// Seeds: every interior vertex within kCoverShare x limit (along edges) of one.
std::vector<std::uint32_t> cover_seeds(const Fans& fans, const std::vector<Vector3d>& p, double cover, const std::vector<std::uint8_t>& region,
                                       detail::ProgressReporter& reporter) {
  const std::size_t n = p.size();
  std::vector<std::uint8_t> covered(n, 0);
  std::vector<double> dist(n, std::numeric_limits<double>::infinity());
  std::vector<std::uint32_t> seeds, reached;
  for (std::uint32_t s = 0; s < n; ++s) {
    if ((s & 0xffffu) == 0xffffu) {
      reporter.advance(0x10000);
      reporter.throw_if_cancelled();
    }
    if (!fans.interior[s] || covered[s] || (!region.empty() && !region[s])) continue;
    seeds.push_back(s);
    grow_within(fans, p, std::span<const std::uint32_t>(&s, 1), cover, true, dist, reached, [&](std::uint32_t v) { covered[v] = 1; });
  }
  return seeds;
}

// The vertices within `reach` (along edges) of `sources`.
std::vector<std::uint8_t> near(const Fans& fans, const std::vector<Vector3d>& p, const std::vector<std::uint32_t>& sources, double reach) {
  std::vector<std::uint8_t> in(p.size(), 0);
  std::vector<double> dist(p.size(), std::numeric_limits<double>::infinity());
  std::vector<std::uint32_t> reached;
  grow_within(fans, p, sources, reach, false, dist, reached, [&](std::uint32_t v) { in[v] = 1; });
  return in;
}

// Candidates from seeds covering the surface, or only `region` where it is not empty.
// Progress: the seed cover (serial) about a tenth of the time, the ball searches the rest.
std::vector<Candidate> search(const Fans& fans, const std::vector<Vector3d>& p, double limit, const std::vector<std::uint8_t>& region,
                              const ProgressCallback& progress) {
  std::vector<std::uint32_t> seeds;
  {
    detail::ProgressReporter cover(progress, 0.0, 0.1, p.size());
    seeds = cover_seeds(fans, p, kCoverShare * limit, region, cover);
  }
  std::vector<Candidate> found(seeds.size());
  tbb::enumerable_thread_specific<BallSearch> searches([&] { return BallSearch(fans, p); });
  detail::ProgressReporter reporter(progress, 0.1, 1.0, seeds.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, seeds.size(), 64), [&](const tbb::blocked_range<std::size_t>& r) {
    if (reporter.cancelled()) return;
    BallSearch& s = searches.local();
    for (std::size_t i = r.begin(); i != r.end(); ++i)
      if (!s.grow(seeds[i], kRadiusShare * limit, limit, found[i])) found[i].loop.clear();
    reporter.advance(r.size());
  });
  reporter.throw_if_cancelled();
  std::erase_if(found, [](const Candidate& c) { return c.loop.empty(); });
  std::sort(found.begin(), found.end(), [](const Candidate& a, const Candidate& b) {
    return a.length != b.length ? a.length < b.length : a.loop < b.loop;
  });
  return found;
}

// Minimum-area triangulation of a loop (hole half-edges loop[i] -> loop[i + 1]), its triangles
// (loop[i], loop[k], loop[j]) oriented as the faces they replace; no diagonal may be an edge
// already. Returns false when there is none.
bool cap_loop(const std::vector<std::uint32_t>& loop, const std::vector<Vector3d>& p, const Fans& fans, std::vector<Triangle>& out) {
  const std::size_t m = loop.size();
  if (m < 3 || m > kMaxCapCorners) return false;
  const auto at = [m](std::size_t i, std::size_t j) { return i * m + j; };
  std::vector<double> cost(m * m, std::numeric_limits<double>::infinity());
  std::vector<std::uint32_t> split(m * m, 0);
  for (std::size_t i = 0; i + 1 < m; ++i) cost[at(i, i + 1)] = 0.0;
  for (std::size_t length = 2; length < m; ++length)
    for (std::size_t i = 0; i + length < m; ++i) {
      const std::size_t j = i + length;
      const bool side = i == 0 && j == m - 1;
      if (!side && fans.adjacent_to(loop[i], loop[j])) continue;
      for (std::size_t k = i + 1; k < j; ++k) {
        const double sub = cost[at(i, k)] + cost[at(k, j)];
        if (!std::isfinite(sub)) continue;
        const Vector3d& a = p[loop[i]];
        const double area = 0.5 * (p[loop[k]] - a).cross(p[loop[j]] - a).norm();
        if (!(area > 0.0)) continue;
        if (sub + area < cost[at(i, j)]) {
          cost[at(i, j)] = sub + area;
          split[at(i, j)] = static_cast<std::uint32_t>(k);
        }
      }
    }
  if (!std::isfinite(cost[at(0, m - 1)])) return false;
  std::vector<std::pair<std::size_t, std::size_t>> stack{{0, m - 1}};
  while (!stack.empty()) {
    const auto [i, j] = stack.back();
    stack.pop_back();
    if (j - i < 2) continue;
    const std::size_t k = split[at(i, j)];
    out.emplace_back(int(loop[i]), int(loop[k]), int(loop[j]));
    stack.emplace_back(i, k);
    stack.emplace_back(k, j);
  }
  return true;
}

// The cut of one candidate: the triangles on the right of its loop removed, the two loops this
// leaves closed. False (nothing changed) where the neighbourhood is not simple enough or touches
// vertices another cut changed this round (`dirty`).
bool plan_cut(const Candidate& c, const std::vector<Triangle>& triangles, const std::vector<Vector3d>& p, const Fans& fans,
              const std::vector<std::uint8_t>& dirty, std::vector<std::uint32_t>& removed, std::vector<Triangle>& caps) {
  removed.clear();
  caps.clear();
  const std::size_t m = c.loop.size();
  for (std::size_t i = 0; i < m; ++i) {
    const std::uint32_t v = c.loop[i], prev = c.loop[(i + m - 1) % m], next = c.loop[(i + 1) % m];
    if (!fans.interior[v] || dirty[v]) return false;
    const std::uint32_t jp = fans.find(v, prev), jq = fans.find(v, next), d = fans.degree(v);
    if (jp == kNone || jq == kNone) return false;
    for (std::uint32_t j = jp; j != jq; j = (j + 1) % d) {
      const std::uint32_t t = fans.face[fans.ring_offset[v] + j];
      if (t == kNone) return false;  // the loop runs along a hole: its side there is the hole
      removed.push_back(t);
    }
  }
  std::sort(removed.begin(), removed.end());
  removed.erase(std::unique(removed.begin(), removed.end()), removed.end());
  // Hole half-edges: the removed triangles' edges x -> y whose twin stays.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> hole;
  for (const std::uint32_t t : removed)
    for (int k = 0; k < 3; ++k) {
      const auto x = std::uint32_t(triangles[t][k]), y = std::uint32_t(triangles[t][(k + 1) % 3]);
      if (dirty[x] || dirty[y] || !fans.interior[y]) return false;
      const std::uint32_t j = fans.find(y, x);
      if (j == kNone) return false;
      const std::uint32_t twin = fans.face[fans.ring_offset[y] + j];
      if (twin == kNone) return false;
      if (!std::binary_search(removed.begin(), removed.end(), twin)) hole.emplace_back(x, y);
    }
  std::sort(hole.begin(), hole.end());
  for (std::size_t i = 1; i < hole.size(); ++i)
    if (hole[i].first == hole[i - 1].first) return false;  // a vertex where two loops touch
  std::vector<std::uint8_t> used(hole.size(), 0);
  std::size_t loops = 0;
  std::vector<std::uint32_t> loop;
  for (std::size_t s = 0; s < hole.size(); ++s) {
    if (used[s]) continue;
    loop.clear();
    std::size_t e = s;
    while (!used[e]) {
      used[e] = 1;
      loop.push_back(hole[e].first);
      const auto it = std::lower_bound(hole.begin(), hole.end(), std::make_pair(hole[e].second, std::uint32_t{0}));
      if (it == hole.end() || it->first != hole[e].second) return false;
      e = std::size_t(it - hole.begin());
    }
    if (e != s) return false;
    ++loops;
    if (!cap_loop(loop, p, fans, caps)) return false;
  }
  return loops == 2;
}

// One planned cut: the triangles it removes (indices into the triangles it was planned on) and
// the caps it adds.
struct Edit {
  std::vector<std::uint32_t> removed;
  std::vector<Triangle> caps;
  HandleLoop loop;
  LoopSphere where;
};

// Plans the cuts of `candidates` (shortest first) that touch no vertex another changes and lie
// farther than `apart` from the loops already taken: two loops around one short tube would cut
// it twice, and the second cut would split the mesh.
std::vector<Edit> plan_cuts(const std::vector<Triangle>& triangles, const std::vector<Vector3d>& p, const Fans& fans,
                            const std::vector<Candidate>& candidates, double apart) {
  std::vector<Edit> edits;
  std::vector<std::uint8_t> dirty(p.size(), 0);
  Edit e;
  Candidate reversed;
  for (const Candidate& c : candidates) {
    e.where = LoopSphere(c.loop, p);
    if (std::any_of(edits.begin(), edits.end(), [&](const Edit& o) { return o.where.near(e.where, apart); })) continue;
    // The faces on the right of the loop go; where that side is a hole (a loop along a border),
    // those on the left.
    if (!plan_cut(c, triangles, p, fans, dirty, e.removed, e.caps)) {
      reversed.loop.assign(c.loop.rbegin(), c.loop.rend());
      if (!plan_cut(reversed, triangles, p, fans, dirty, e.removed, e.caps)) continue;
    }
    for (const std::uint32_t t : e.removed)
      for (int k = 0; k < 3; ++k) dirty[std::size_t(triangles[t][k])] = 1;
    e.loop = HandleLoop{std::vector<int>(c.loop.begin(), c.loop.end()), c.length};
    edits.push_back(e);
  }
  return edits;
}

// `triangles` with the edits `take` applied.
std::vector<Triangle> apply(const std::vector<Triangle>& triangles, const std::vector<Edit>& edits, const std::vector<std::size_t>& take) {
  std::vector<std::uint8_t> gone(triangles.size(), 0);
  std::size_t caps = 0;
  for (const std::size_t i : take) {
    for (const std::uint32_t t : edits[i].removed) gone[t] = 1;
    caps += edits[i].caps.size();
  }
  std::vector<Triangle> out;
  out.reserve(triangles.size() + caps);
  for (std::size_t t = 0; t < triangles.size(); ++t)
    if (!gone[t]) out.push_back(triangles[t]);
  for (const std::size_t i : take) out.insert(out.end(), edits[i].caps.begin(), edits[i].caps.end());
  return out;
}

// Each cut of a handle raises V - E + F by 2 and keeps the components and the boundary; nothing
// may become less manifold.
bool as_expected(const MeshTopology& after, const MeshTopology& before, std::size_t cuts) {
  return after.euler_characteristic == before.euler_characteristic + 2 * long(cuts) && after.non_manifold_edges <= before.non_manifold_edges && after.non_manifold_vertices <= before.non_manifold_vertices &&
         after.inconsistent_edges <= before.inconsistent_edges && after.boundary_edges <= before.boundary_edges &&
         after.components == before.components;
}

double mean_edge_length(const TriangleMesh& mesh) {
  double sum = 0.0;
  std::size_t count = 0;
  const auto& p = mesh.vertices.positions;
  for (const Triangle& t : mesh.triangles)
    for (int c = 0; c < 3; ++c) {
      sum += (p[std::size_t(t[(c + 1) % 3])] - p[std::size_t(t[c])]).norm();
      ++count;
    }
  return count > 0 ? sum / double(count) : 0.0;
}

}  // namespace

const FieldTable<HandleParams>& HandleParams::fields() {
  static const FieldTable<HandleParams> table = [] {
    FieldTable<HandleParams> t;
    t.number("max_handle_loop", &HandleParams::max_loop_in_spacings,
             "Handles with a non-separating loop at most this long are topological noise; 0: none looked for")
        .unit("spacings")
        .non_negative();
    t.boolean("remove_handles", &HandleParams::remove, "Cut the short handles along their loop and close both sides; else only count them");
    return t;
  }();
  return table;
}

void HandleParams::validate() const {
  if (!(max_loop_in_spacings >= 0.0) || !std::isfinite(max_loop_in_spacings))
    throw UsageError(fmt::format("remove_short_handles: max_loop_in_spacings must be a number >= 0, got {}", max_loop_in_spacings));
  if (!(spacing >= 0.0) || !std::isfinite(spacing))
    throw UsageError(fmt::format("remove_short_handles: spacing must be a number >= 0, got {}", spacing));
  fields().validate(*this, "remove_short_handles");
}

HandleResult remove_short_handles(TriangleMesh& mesh, const HandleParams& params, const ProgressCallback& progress) {
  params.validate();
  mesh.validate();
  HandleResult result;
  MeshTopology topo = analyze_topology(mesh);
  result.handles_before = result.handles_after = topo.handles();
  const double spacing = params.spacing > 0.0 ? params.spacing : mean_edge_length(mesh);
  result.max_loop_length = params.max_loop_in_spacings * spacing;
  if (!(result.max_loop_length > 0.0) || mesh.triangles.empty() || result.handles_before == 0) return result;
  if (!params.remove) return find_short_handles(mesh, params, progress);
  // Local origin: georeferenced coordinates keep their precision in the differences.
  const std::size_t n = mesh.vertices.positions.size();
  const Vector3d origin = mesh.vertices.positions[std::size_t(mesh.triangles.front()[0])];
  std::vector<Vector3d> p(n);
  for (std::size_t v = 0; v < n; ++v) p[v] = mesh.vertices.positions[v] - origin;
  std::vector<Triangle>& triangles = mesh.triangles;
  std::size_t left = 0;
  std::vector<std::uint32_t> unresolved;  // vertices of the loops found in the last round
  for (int r = 0; r < kRounds; ++r) {
    const Fans fans = build_fans(triangles, n);
    // After the first round, only where a loop was found but not cut: the cuts elsewhere leave
    // the rest of the surface as it was.
    const std::vector<std::uint8_t> region = r == 0 ? std::vector<std::uint8_t>{} : near(fans, p, unresolved, 2.0 * result.max_loop_length);
    // Progress: the first round searches the whole surface (90 %), later ones only near the
    // loops left, each half the share of the one before.
    const double begin = r == 0 ? 0.0 : 1.0 - 0.1 * std::pow(0.5, r - 1), end = 1.0 - 0.1 * std::pow(0.5, r);
    const std::vector<Candidate> candidates = search(fans, p, result.max_loop_length, region, sub_progress(progress, begin, end));
    if (candidates.empty()) {
      left = 0;
      break;
    }
    const std::vector<Edit> edits = plan_cuts(triangles, p, fans, candidates, result.max_loop_length);
    // All edits at once; where the check fails, the two halves in turn, down to single edits.
    const std::vector<Triangle> original = triangles;
    std::vector<std::size_t> accepted;
    MeshTopology after = topo;
    std::vector<std::vector<std::size_t>> pending(1);
    for (std::size_t i = 0; i < edits.size(); ++i) pending.front().push_back(i);
    while (!pending.empty()) {
      std::vector<std::size_t> trial = std::move(pending.back());
      pending.pop_back();
      if (trial.empty()) continue;
      std::vector<std::size_t> take = accepted;
      take.insert(take.end(), trial.begin(), trial.end());
      mesh.triangles = apply(original, edits, take);
      MeshTopology t = analyze_topology(mesh);
      if (as_expected(t, topo, take.size())) {
        accepted = std::move(take);
        after = std::move(t);
      } else if (trial.size() > 1) {
        const auto half = trial.begin() + std::ptrdiff_t(trial.size() / 2);
        pending.emplace_back(half, trial.end());
        pending.emplace_back(trial.begin(), half);
      }
    }
    mesh.triangles = apply(original, edits, accepted);
    Round round;
    round.applied = accepted.size();
    for (const std::size_t i : accepted) round.loops.push_back(edits[i].loop);
    unresolved.clear();
    for (const Candidate& c : candidates) unresolved.insert(unresolved.end(), c.loop.begin(), c.loop.end());
    if (round.applied == 0) {
      // Found but none could be cut: loops farther apart than the limit count as one handle
      // each (several seeds find each handle).
      std::vector<LoopSphere> taken;
      for (const Candidate& c : candidates) {
        const LoopSphere where(c.loop, p);
        if (std::any_of(taken.begin(), taken.end(), [&](const LoopSphere& o) { return o.near(where, result.max_loop_length); })) continue;
        taken.push_back(where);
        if (result.shortest_loop == 0.0 || c.length < result.shortest_loop) result.shortest_loop = c.length;
        result.loops.push_back(HandleLoop{std::vector<int>(c.loop.begin(), c.loop.end()), c.length});
      }
      left = taken.size();
      break;
    }
    for (HandleLoop& loop : round.loops) {
      if (result.shortest_loop == 0.0 || loop.length < result.shortest_loop) result.shortest_loop = loop.length;
      result.loops.push_back(std::move(loop));
    }
    result.handles_removed += round.applied;
    result.handles_after = after.handles();
    topo = std::move(after);
    if (result.handles_after == 0) break;
  }
  result.short_handles = result.handles_removed + left;
  if (result.handles_removed > 0 && !mesh.face_fields.empty()) mesh.face_fields = FieldSet{};  // a new triangle has no value
  return result;
}

HandleResult find_short_handles(const TriangleMesh& mesh, HandleParams params, const ProgressCallback& progress) {
  TriangleMesh copy;
  copy.vertices.positions = mesh.vertices.positions;
  copy.triangles = mesh.triangles;
  params.remove = true;
  HandleResult result = remove_short_handles(copy, params, progress);
  result.handles_after = result.handles_before;
  result.handles_removed = 0;
  return result;
}

const ResultTable<HandleResult>& HandleResult::results() {
  static const ResultTable<HandleResult> table = [] {
    using R = HandleResult;
    ResultTable<R> t;
    t.computed("handles_before", ResultType::Integer,
               [](const R& r) { return r.handles_before >= 0 ? ResultValue(std::int64_t{r.handles_before}) : ResultValue(std::numeric_limits<double>::quiet_NaN()); },
               "Genus summed over the components before the cut (null where undefined)");
    t.count("short_handles", &R::short_handles, "Handles with a loop at most max_handle_loop spacings long (topological noise)")
        .lower_is_better()
        .as_count();
    t.count("handles_removed", &R::handles_removed, "Of them cut and closed (remove_handles)").as_count();
    t.number("shortest_handle_loop", &R::shortest_loop, "Length of the shortest such loop; 0 when none").with_unit("cloud units");
    t.number("max_handle_loop_length", &R::max_loop_length, "The limit used, max_handle_loop x the mean spacing").with_unit("cloud units");
    return t;
  }();
  return table;
}

}  // namespace pointsurf
