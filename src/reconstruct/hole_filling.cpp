// SPDX-License-Identifier: GPL-3.0-or-later
// The hole filler (reconstruct/detail/hole_filling.h) and its public form fill_holes()
// (reconstruct/fill_holes.h).
#include "reconstruct/detail/hole_filling.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <utility>

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "pointsurf/core/error.h"
#include "pointsurf/core/mesh_topology.h"
#include "pointsurf/reconstruct/fill_holes.h"

namespace pointsurf {
namespace detail {
namespace {

using Eigen::Vector2d;

constexpr std::uint32_t kNone = HalfEdgeMap::kNone;
// Holes with more corners than this are left open (the dynamic programme is cubic in the corner count).
constexpr std::size_t kMaxHoleCorners = 64;
// Rounds of opening pinched vertices and filling the holes again.
constexpr int kRepairRounds = 3;
// Holes that the repair opened around a small unfillable one are closed up to this many times
// the perimeter limit.
constexpr double kRepairedPerimeterFactor = 3.0;
// A triangle closing a hole may deviate at most this far from each corner's normal.
constexpr double kFillMaxDeviationDeg = 120.0;
const double kFillMinCos = std::cos(kFillMaxDeviationDeg * std::numbers::pi / 180.0);

// Fills one simple hole loop (hole half-edges loop[i] -> loop[i+1], the hole on their left
// seen from the normals' side) by dynamic programming over its sub-chains (Barequet and Sharir
// 1995; Liepa 2003): among the triangulations whose new edges are in the mesh in neither
// direction and whose triangles face the way their corners' normals do, the one with
// the smallest worst normal deviation, then the smallest area. O(m^3) for m corners; the
// buffers are reused from loop to loop.
class LoopFiller {
public:
  bool fill(const std::vector<std::uint32_t>& loop, const std::vector<Vector3d>& positions, const std::vector<Vector3d>& normals,
            Selection& sel) {
    const std::size_t m = loop.size();
    if (m < 3) return false;
    const auto at = [m](std::size_t i, std::size_t j) { return i * m + j; };
    diagonal_ok_.assign(m * m, 0);
    for (std::size_t i = 0; i < m; ++i)
      for (std::size_t j = i + 1; j < m; ++j) {
        const bool side = j == i + 1 || (i == 0 && j == m - 1);
        diagonal_ok_[at(i, j)] =
            static_cast<std::uint8_t>(side || (!sel.edges.contains(loop[i], loop[j]) && !sel.edges.contains(loop[j], loop[i])));
      }
    cost_.assign(m * m, Cost{INFINITY, INFINITY});
    split_.assign(m * m, 0);
    for (std::size_t i = 0; i + 1 < m; ++i) cost_[at(i, i + 1)] = Cost{0.0, 0.0};
    for (std::size_t length = 2; length < m; ++length)
      for (std::size_t i = 0; i + length < m; ++i) {
        const std::size_t j = i + length;
        if (!diagonal_ok_[at(i, j)]) continue;
        Cost best{INFINITY, INFINITY};
        for (std::size_t k = i + 1; k < j; ++k) {
          const Cost &left = cost_[at(i, k)], &right = cost_[at(k, j)];
          if (!std::isfinite(left.worst) || !std::isfinite(right.worst)) continue;
          const Cost tri = triangle_cost(positions, normals, loop[i], loop[k], loop[j]);
          if (!std::isfinite(tri.worst)) continue;
          const Cost total{std::max({left.worst, right.worst, tri.worst}), left.area + right.area + tri.area};
          if (better(total, best)) {
            best = total;
            split_[at(i, j)] = static_cast<std::uint32_t>(k);
          }
        }
        cost_[at(i, j)] = best;
      }
    if (!std::isfinite(cost_[at(0, m - 1)].worst)) return false;
    stack_.assign(1, {0, static_cast<std::uint32_t>(m - 1)});
    while (!stack_.empty()) {
      const auto [i, j] = stack_.back();
      stack_.pop_back();
      if (j - i < 2) continue;
      const std::uint32_t k = split_[at(i, j)];
      const std::uint32_t a = loop[i], b = loop[k], c = loop[j];
      sel.add(a, b, c, (positions[b] - positions[a]).cross(positions[c] - positions[a]).normalized());
      stack_.push_back({i, k});
      stack_.push_back({k, j});
    }
    return true;
  }

private:
  struct Cost {
    double worst;  // largest 1 - cos(angle) between a triangle's normal and a corner's normal
    double area;
  };
  static bool better(const Cost& x, const Cost& y) {
    // Deviations within 1e-3 (about 2.5 degrees near 0) count as equal: then the area decides.
    if (std::abs(x.worst - y.worst) > 1e-3) return x.worst < y.worst;
    return x.area < y.area;
  }
  static Cost triangle_cost(const std::vector<Vector3d>& positions, const std::vector<Vector3d>& normals, std::uint32_t a,
                            std::uint32_t b, std::uint32_t c) {
    const Vector3d face = (positions[b] - positions[a]).cross(positions[c] - positions[a]);
    const double twice_area = face.norm();
    const double scale = (positions[b] - positions[a]).squaredNorm() + (positions[c] - positions[a]).squaredNorm();
    if (!(twice_area > 1e-12 * scale)) return Cost{INFINITY, INFINITY};
    const Vector3d unit = face / twice_area;
    // Across a sharp edge a corner's normal may stand at up to 90 degrees from the triangle
    // (more where the normals were estimated): the corners only have to agree with it on
    // average, each within kFillMaxDeviationDeg.
    double worst = 0.0;
    if (!(unit.dot(normals[a] + normals[b] + normals[c]) > 0.0)) return Cost{INFINITY, INFINITY};
    for (std::uint32_t v : {a, b, c}) {
      const double cosine = unit.dot(normals[v]);
      if (!(cosine > kFillMinCos)) return Cost{INFINITY, INFINITY};
      worst = std::max(worst, 1.0 - cosine);
    }
    return Cost{worst, 0.5 * twice_area};
  }

  std::vector<Cost> cost_;
  std::vector<std::uint32_t> split_;
  std::vector<std::uint8_t> diagonal_ok_;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> stack_;
};

}  // namespace

std::vector<HoleEdge> all_hole_edges(const Selection& sel) {
  tbb::enumerable_thread_specific<std::vector<HoleEdge>> found;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, sel.triangles.size(), 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<HoleEdge>& out = found.local();
    for (std::size_t t = r.begin(); t != r.end(); ++t)
      for (int c = 0; c < 3; ++c) {
        const auto x = static_cast<std::uint32_t>(sel.triangles[t][c]), y = static_cast<std::uint32_t>(sel.triangles[t][(c + 1) % 3]);
        if (!sel.edges.contains(y, x)) out.push_back({y, static_cast<std::uint32_t>(t), x});
      }
  });
  std::vector<HoleEdge> edges;
  for (const std::vector<HoleEdge>& part : found) edges.insert(edges.end(), part.begin(), part.end());
  std::sort(edges.begin(), edges.end(), [](const HoleEdge& a, const HoleEdge& b) {
    return a.y != b.y ? a.y < b.y : a.triangle < b.triangle;
  });
  return edges;
}

namespace {

// Whether the edge-connected piece of triangle `t` among the triangles below `triangle_total`
// has at most `limit` triangles: a breadth-first walk that stops after limit + 1.
bool piece_at_most(const Selection& sel, std::uint32_t t, std::size_t triangle_total, std::size_t limit,
                   std::vector<std::uint32_t>& seen) {
  seen.assign(1, t);
  for (std::size_t head = 0; head < seen.size(); ++head) {
    const Triangle& tri = sel.triangles[seen[head]];
    for (int c = 0; c < 3; ++c) {
      const std::uint32_t twin = sel.edges.find(std::uint32_t(tri[(c + 1) % 3]), std::uint32_t(tri[c]));
      if (twin == kNone || twin >= triangle_total || std::find(seen.begin(), seen.end(), twin) != seen.end()) continue;
      seen.push_back(twin);
      if (seen.size() > limit) return false;
    }
  }
  return true;
}

// Closes the holes with at most kMaxHoleCorners corners whose perimeter is at most
// `max_perimeter_in_spacings` local spacings (LoopFiller), walking the hole half-edges `hole`
// (all of them, in the order of all_hole_edges). Returns the number of holes closed and adds the
// triangles it made to `added`; flags the corners of the small holes it could not close in
// `reopen`.
std::size_t fill_small_holes(const std::vector<Vector3d>& positions, const std::vector<Vector3d>& normals,
                             const std::vector<double>& local_spacing, double max_perimeter_in_spacings, Selection& sel,
                             LoopFiller& filler, const std::vector<HoleEdge>& hole, const std::vector<std::uint8_t>& repaired,
                             const std::vector<std::uint8_t>& blocked, std::vector<std::uint8_t>& reopen, std::size_t& added,
                             const LoopLimitFactor& limit_factor) {
  const std::size_t n = positions.size();
  // The rim of a tiny isolated piece is not a hole: its size is counted among the triangles
  // there were before this pass.
  const std::size_t triangle_total = sel.triangles.size();
  // Hole half-edges run opposite to the boundary edges of the mesh: y -> x for an edge x -> y
  // without twin. The filling triangles use them in that direction. Up to three hole edges
  // leave a vertex (more than one at a pinch, where fans touch); more are left alone.
  constexpr std::size_t kSlots = 3;
  std::vector<std::array<std::uint32_t, kSlots>> hole_out(n, {kNone, kNone, kNone});
  std::vector<std::uint32_t> starts;
  for (const HoleEdge& e : hole) {
    if (starts.empty() || starts.back() != e.y) starts.push_back(e.y);
    for (std::uint32_t& slot : hole_out[e.y])
      if (slot == kNone) {
        slot = e.x;
        break;
      }
  }
  // Interior angle of the hole at v between the edges p -> v and v -> w, in v's tangent plane:
  // at a pinch the walk takes the tightest turn, which pairs each incoming hole edge with the
  // outgoing one across the same gap between fans.
  const auto turn = [&](std::uint32_t p, std::uint32_t v, std::uint32_t w) {
    const Vector3d& nv = normals[v];
    const Vector3d e1 = nv.unitOrthogonal(), e2 = nv.cross(e1);
    const Vector3d a3 = positions[w] - positions[v], b3 = positions[p] - positions[v];
    const Vector2d a(a3.dot(e1), a3.dot(e2)), b(b3.dot(e1), b3.dot(e2));
    double angle = std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b));
    if (angle < 0.0) angle += 2.0 * std::numbers::pi;
    return angle;
  };
  // The walk follows hole edges as a path; whenever it reaches a vertex already on the path,
  // the part from there on is a simple closed loop, which is filled (when small) and cut off.
  std::vector<std::uint32_t> position(n, kNone);
  std::vector<std::uint32_t> path, cycle, seen;
  std::size_t filled = 0;
  for (const std::uint32_t start : starts) {
    while (hole_out[start][0] != kNone) {
      path.assign(1, start);
      position[start] = 0;
      while (!path.empty()) {
        const std::uint32_t v = path.back();
        const std::uint32_t from = path.size() >= 2 ? path[path.size() - 2] : kNone;
        std::array<std::uint32_t, kSlots>& slots = hole_out[v];
        std::size_t pick = kSlots;
        double tightest = INFINITY;
        for (std::size_t s = 0; s < kSlots; ++s) {
          if (slots[s] == kNone) continue;
          const double angle = from == kNone ? 0.0 : turn(from, v, slots[s]);
          if (pick == kSlots || angle < tightest) {
            pick = s;
            tightest = angle;
          }
        }
        if (pick == kSlots) break;  // dead end: the hole edges around it were left out
        const std::uint32_t w = slots[pick];
        for (std::size_t s = pick; s + 1 < kSlots; ++s) slots[s] = slots[s + 1];
        slots[kSlots - 1] = kNone;
        if (position[w] == kNone) {
          position[w] = static_cast<std::uint32_t>(path.size());
          path.push_back(w);
          continue;
        }
        const std::size_t first = position[w];
        cycle.assign(path.begin() + std::ptrdiff_t(first), path.end());
        for (std::size_t i = first + 1; i < path.size(); ++i) position[path[i]] = kNone;
        path.resize(first + 1);
        if (first == 0 && hole_out[w][0] == kNone) path.clear();
        if (cycle.size() < 3 || cycle.size() > kMaxHoleCorners) continue;
        if (!blocked.empty() && std::any_of(cycle.begin(), cycle.end(), [&](std::uint32_t x) { return blocked[x] != 0; })) continue;
        double perimeter = 0.0, spacing_sum = 0.0;
        bool grown = false;
        for (std::size_t i = 0; i < cycle.size(); ++i) {
          perimeter += (positions[cycle[(i + 1) % cycle.size()]] - positions[cycle[i]]).norm();
          spacing_sum += local_spacing[cycle[i]];
          grown = grown || repaired[cycle[i]];
        }
        // A hole that the repair grew from a small one keeps being closed up to twice the limit.
        double limit = (grown ? kRepairedPerimeterFactor : 1.0) * max_perimeter_in_spacings;
        // A loop within its limit only by limit_factor is left as it is when it has no valid
        // filling, unless the factor says otherwise.
        bool leave_if_unfilled = false;
        if (perimeter > limit * spacing_sum / double(cycle.size()) && limit_factor) {
          const LoopLimit given = limit_factor(cycle);
          limit *= given.factor;
          leave_if_unfilled = !given.open_if_unfilled;
        }
        if (perimeter > limit * spacing_sum / double(cycle.size())) continue;
        const std::size_t before = sel.triangles.size();
        if (filler.fill(cycle, positions, normals, sel)) ++filled;
        else {
          const std::uint32_t beside = sel.edges.find(cycle[1], cycle[0]);
          const bool tiny_piece = beside < triangle_total && piece_at_most(sel, beside, triangle_total, 2 * cycle.size(), seen);
          if (!tiny_piece && !leave_if_unfilled)
            for (std::uint32_t x : cycle) reopen[x] = 1;
        }
        added += sel.triangles.size() - before;
      }
      for (std::uint32_t x : path) position[x] = kNone;
      position[start] = kNone;
    }
  }
  return filled;
}

// The fans of the triangles `local` around v (triangle s has the corner v -> next[s] ->
// prev[s], counter-clockwise): fan_of[s] labels them, fan_angle sums each fan's angles at v
// when `angles` is set. Returns the number of fans. Neighbours are found in `local` itself, not
// in the half-edge map: the lists are short and this keeps the scan in cache.
std::size_t label_fans(const std::vector<Vector3d>& positions, std::uint32_t v, const std::vector<std::uint32_t>& next,
                       const std::vector<std::uint32_t>& prev, bool angles, std::vector<std::uint32_t>& fan_of,
                       std::vector<double>& fan_angle) {
  const std::size_t m = next.size();
  fan_of.assign(m, kNone);
  fan_angle.clear();
  // The triangle with the directed edge v -> w (next == w) and the one with w -> v (prev == w).
  const auto with_next = [&](std::uint32_t w) { return std::size_t(std::find(next.begin(), next.end(), w) - next.begin()); };
  const auto with_prev = [&](std::uint32_t w) { return std::size_t(std::find(prev.begin(), prev.end(), w) - prev.begin()); };
  // Label chains from their first triangle (none before it across an edge); what is left are
  // closed fans.
  for (int pass = 0; pass < 2; ++pass)
    for (std::size_t s = 0; s < m; ++s) {
      if (fan_of[s] != kNone) continue;
      if (pass == 0 && with_next(prev[s]) < m) continue;
      const auto fan = static_cast<std::uint32_t>(fan_angle.size());
      fan_angle.push_back(0.0);
      for (std::size_t at = s; at < m && fan_of[at] == kNone; at = with_prev(next[at])) {
        fan_of[at] = fan;
        if (!angles) continue;
        const Vector3d a = positions[next[at]] - positions[v], b = positions[prev[at]] - positions[v];
        fan_angle[fan] += std::atan2(a.cross(b).norm(), a.dot(b));
      }
    }
  return fan_angle.size();
}

// Per-thread buffers of the fan labelling.
struct FanBuffers {
  std::vector<std::uint32_t> local, next, prev, fan_of;
  std::vector<double> fan_angle;
};

// Opens what the hole filling could not close: removes the triangles with two corners flagged
// in `reopen` (those along a small hole that had no valid filling, e.g. at a fold), so that
// the next pass sees one larger, simpler hole; at a vertex whose triangles form more than one fan
// (fronts that met there only), keeps the fan with the largest angle at the vertex and removes
// the others. Clears `reopen`; returns the number of triangles removed. The vertices are visited
// in order as if each were examined after the removals at the ones before it, but only those
// with several fans, found in parallel, and those that lost a triangle are looked at again.
// `hole` holds the hole half-edges before the call and, when triangles were removed, after it.
std::size_t open_pinches(const std::vector<Vector3d>& positions, std::vector<std::uint8_t>& reopen, std::vector<std::uint8_t>& repaired,
                         Selection& sel, std::vector<HoleEdge>& hole) {
  const std::size_t n = positions.size(), f = sel.triangles.size();
  std::vector<std::uint32_t> offset(n + 1, 0), around(3 * f);
  for (const Triangle& t : sel.triangles)
    for (int c = 0; c < 3; ++c) ++offset[std::size_t(t[c]) + 1];
  for (std::size_t v = 0; v < n; ++v) offset[v + 1] += offset[v];
  {
    std::vector<std::uint32_t> cursor(offset.begin(), offset.end() - 1);
    for (std::size_t t = 0; t < f; ++t)
      for (int c = 0; c < 3; ++c) around[cursor[std::size_t(sel.triangles[t][c])]++] = static_cast<std::uint32_t>(t);
  }
  std::vector<std::uint8_t> removed(f, 0);
  std::size_t count = 0;
  for (std::size_t t = 0; t < f; ++t) {
    const Triangle& tri = sel.triangles[t];
    if (int(reopen[std::size_t(tri[0])]) + reopen[std::size_t(tri[1])] + reopen[std::size_t(tri[2])] >= 2) {
      removed[t] = 1;
      ++count;
    }
  }
  std::fill(reopen.begin(), reopen.end(), std::uint8_t{0});
  // The live triangles around v with their corners at v.
  const auto gather = [&](std::uint32_t v, FanBuffers& b) {
    b.local.clear();
    b.next.clear();
    b.prev.clear();
    for (std::uint32_t i = offset[v]; i < offset[v + 1]; ++i) {
      const std::uint32_t t = around[i];
      if (removed[t]) continue;
      const Triangle& tri = sel.triangles[t];
      const int c = std::uint32_t(tri[0]) == v ? 0 : std::uint32_t(tri[1]) == v ? 1 : 2;
      b.local.push_back(t);
      b.next.push_back(std::uint32_t(tri[(c + 1) % 3]));
      b.prev.push_back(std::uint32_t(tri[(c + 2) % 3]));
    }
  };
  std::vector<std::uint8_t> pinched(n, 0);
  {
    tbb::enumerable_thread_specific<FanBuffers> buffers;
    tbb::parallel_for(tbb::blocked_range<std::uint32_t>(0, std::uint32_t(n), 2048), [&](const tbb::blocked_range<std::uint32_t>& r) {
      FanBuffers& b = buffers.local();
      for (std::uint32_t v = r.begin(); v != r.end(); ++v) {
        if (offset[v + 1] - offset[v] < 2) continue;
        gather(v, b);
        if (b.local.size() >= 2 && label_fans(positions, v, b.next, b.prev, false, b.fan_of, b.fan_angle) >= 2) pinched[v] = 1;
      }
    });
  }
  FanBuffers b;
  for (std::uint32_t v = 0; v < n; ++v) {
    if (!pinched[v]) continue;
    gather(v, b);
    if (b.local.size() < 2 || label_fans(positions, v, b.next, b.prev, true, b.fan_of, b.fan_angle) < 2) continue;
    const auto keep = static_cast<std::uint32_t>(std::max_element(b.fan_angle.begin(), b.fan_angle.end()) - b.fan_angle.begin());
    for (std::size_t s = 0; s < b.local.size(); ++s) {
      if (b.fan_of[s] == keep) continue;
      removed[b.local[s]] = 1;
      ++count;
      // A later corner that lost a triangle may have split into fans.
      for (std::uint32_t w : {b.next[s], b.prev[s]})
        if (w > v) pinched[w] = 1;
    }
  }
  if (count == 0) return 0;
  // The hole edges after the removal start at the vertices of the old ones or at a corner of a
  // removed triangle.
  std::vector<std::uint32_t> touched;
  for (const HoleEdge& e : hole) touched.push_back(e.y);
  for (std::size_t t = 0; t < f; ++t)
    if (removed[t])
      for (int c = 0; c < 3; ++c) {
        const auto v = std::uint32_t(sel.triangles[t][c]);
        touched.push_back(v);
        repaired[v] = 1;
      }
  std::sort(touched.begin(), touched.end());
  touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
  std::vector<std::uint32_t> new_id;
  sel.remove(removed, new_id);
  hole.clear();
  for (const std::uint32_t y : touched)
    for (std::uint32_t i = offset[y]; i < offset[y + 1]; ++i) {
      const std::uint32_t t = around[i];
      if (removed[t]) continue;
      const Triangle& tri = sel.triangles[new_id[t]];
      const int c = std::uint32_t(tri[1]) == y ? 0 : std::uint32_t(tri[2]) == y ? 1 : 2;  // the edge x -> y
      const auto x = std::uint32_t(tri[c]);
      if (!sel.edges.contains(y, x)) hole.push_back({y, new_id[t], x});
    }
  return count;
}

}  // namespace

void close_holes(const std::vector<Vector3d>& positions, const std::vector<Vector3d>& normals,
                 const std::vector<double>& local_spacing, double max_perimeter_in_spacings, Selection& sel,
                 const std::vector<std::uint8_t>& blocked, HoleClosing& counts, const std::function<void(int)>& on_round,
                 const LoopLimitFactor& limit_factor) {
  if (!(max_perimeter_in_spacings > 0.0)) return;
  const std::size_t n = positions.size();
  LoopFiller filler;
  std::vector<std::uint8_t> reopen(n, 0), repaired(n, 0);
  // Only the first round scans every triangle for hole edges; the repair reports the ones it leaves.
  std::vector<HoleEdge> hole = all_hole_edges(sel);
  for (int round = 0;; ++round) {
    counts.holes_filled += fill_small_holes(positions, normals, local_spacing, max_perimeter_in_spacings, sel, filler, hole, repaired,
                                            blocked, reopen, counts.fill_triangles, limit_factor);
    if (on_round) on_round(round);
    if (round == kRepairRounds) break;
    const std::size_t removed = open_pinches(positions, reopen, repaired, sel, hole);
    counts.pinch_triangles_removed += removed;
    if (removed == 0) break;
  }
}

}  // namespace detail

const FieldTable<HoleFillParams>& HoleFillParams::fields() {
  static const FieldTable<HoleFillParams> table = [] {
    FieldTable<HoleFillParams> t;
    t.number("max_perimeter_in_spacings", &HoleFillParams::max_perimeter_in_spacings, "Close holes up to this perimeter; 0: none")
        .unit("local spacings")
        .non_negative();
    return t;
  }();
  return table;
}

void HoleFillParams::validate() const {
  if (!(max_perimeter_in_spacings >= 0.0) || !std::isfinite(max_perimeter_in_spacings))
    throw UsageError(fmt::format("fill_holes: max_perimeter_in_spacings = {}, expected a finite value >= 0 (0: none closed)",
                                 max_perimeter_in_spacings));
  fields().validate(*this, "fill_holes");
}

namespace detail {

HoleFillStats fill_mesh_holes(TriangleMesh& mesh, const HoleFillParams& params) {
  HoleFillStats stats;
  const std::size_t n = mesh.vertices.positions.size();
  if (!(params.max_perimeter_in_spacings > 0.0) || mesh.triangles.empty()) return stats;
  // Local origin: georeferenced coordinates keep their precision in the cross products.
  const Vector3d origin = bounding_box(mesh.vertices.positions).center();
  std::vector<Vector3d> p(n);
  for (std::size_t v = 0; v < n; ++v) p[v] = mesh.vertices.positions[v] - origin;
  // Degenerate triangles (a repeated index) stay as they are, outside the filler.
  std::vector<Triangle> kept_aside;
  // Vertices on an edge with more than two triangles, or traversed twice the same way, are
  // blocked: no loop through them is filled. Three triangles on one edge traverse it twice the
  // same way, so a directed edge already in the map when its triangle is added finds both.
  std::vector<std::uint8_t> blocked(n, 0);
  // Corner normals and local spacings (mean length of the edges at a vertex).
  std::vector<Vector3d> normals(n, Vector3d::Zero()), face_sum(n, Vector3d::Zero());
  std::vector<double> spacing(n, 0.0);
  std::vector<std::uint32_t> degree(n, 0);
  detail::Selection sel(mesh.triangles.size() + 64);
  sel.triangles.reserve(mesh.triangles.size() + 64);
  sel.normals.reserve(mesh.triangles.size() + 64);
  for (const Triangle& t : mesh.triangles) {
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
      kept_aside.push_back(t);
      continue;
    }
    for (int c = 0; c < 3; ++c) {
      const auto a = std::uint32_t(t[c]), b = std::uint32_t(t[(c + 1) % 3]);
      if (sel.edges.contains(a, b)) blocked[a] = blocked[b] = 1;
    }
    const Vector3d face = (p[std::size_t(t[1])] - p[std::size_t(t[0])]).cross(p[std::size_t(t[2])] - p[std::size_t(t[0])]);
    const double len = face.norm();
    sel.add(std::uint32_t(t[0]), std::uint32_t(t[1]), std::uint32_t(t[2]), len > 0.0 ? Vector3d(face / len) : Vector3d::Zero());
    for (int c = 0; c < 3; ++c) {
      const std::size_t a = std::size_t(t[c]), b = std::size_t(t[(c + 1) % 3]);
      face_sum[a] += face;
      const double e = (p[a] - p[b]).norm();
      spacing[a] += e;
      spacing[b] += e;
      degree[a] += 1;
      degree[b] += 1;
    }
  }
  const bool has_normals = mesh.vertices.normals.size() == n;
  for (std::size_t v = 0; v < n; ++v) {
    if (degree[v] > 0) spacing[v] /= double(degree[v]);
    Vector3d nrm = has_normals ? mesh.vertices.normals[v] : Vector3d::Zero();
    if (!(nrm.norm() > 0.0) || !nrm.allFinite()) nrm = face_sum[v];
    const double len = nrm.norm();
    normals[v] = len > 0.0 ? Vector3d(nrm / len) : Vector3d::Zero();
  }
  detail::HoleClosing closing;
  detail::close_holes(p, normals, spacing, params.max_perimeter_in_spacings, sel, blocked, closing);
  stats.holes_filled = closing.holes_filled;
  stats.triangles_added = closing.fill_triangles;
  stats.triangles_removed = closing.pinch_triangles_removed;
  if (closing.fill_triangles == 0 && closing.pinch_triangles_removed == 0) return stats;
  mesh.triangles = std::move(sel.triangles);
  mesh.triangles.insert(mesh.triangles.end(), kept_aside.begin(), kept_aside.end());
  if (!mesh.face_fields.empty()) {
    mesh.face_fields = FieldSet{};  // a new triangle has no value
    stats.face_fields_dropped = true;
  }
  return stats;
}

}  // namespace detail

HoleFillStats fill_holes(TriangleMesh& mesh, const HoleFillParams& params) {
  params.validate();
  mesh.validate();
  const std::size_t holes_before = analyze_topology(mesh).boundary_loops.size();
  if (holes_before == 0 || !(params.max_perimeter_in_spacings > 0.0)) {
    HoleFillStats stats;
    stats.holes_before = stats.holes_after = holes_before;
    return stats;
  }
  HoleFillStats stats = detail::fill_mesh_holes(mesh, params);
  stats.holes_before = holes_before;
  const bool changed = stats.triangles_added > 0 || stats.triangles_removed > 0;
  stats.holes_after = changed ? analyze_topology(mesh).boundary_loops.size() : holes_before;
  return stats;
}

}  // namespace pointsurf
