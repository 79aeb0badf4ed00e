// SPDX-License-Identifier: GPL-3.0-or-later
// What the cocone reconstruction and the Crust share (reconstruct/detail/delaunay_surface.h): the
// input checks, the first Delaunay triangulation with its poles, and the manifold extraction of
// the candidate triangles (Amenta, Bern, Kamvysselis 1998, section 4.2), on plain arrays, in
// parallel where a pass is per point or per triangle.
#include "reconstruct/detail/delaunay_surface.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <numeric>
#include <utility>
#include <vector>

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "pointsurf/core/error.h"
#include "pointsurf/core/mesh_topology.h"
#include "pointsurf/reconstruct/fill_holes.h"
#include "pointsurf/features/boundary_points.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf {
namespace {

std::uint64_t edge_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
}

/// Candidate triangles with their edge incidences (CSR: edge e has triangles
/// edge_tris[edge_start[e] .. edge_start[e+1])).
using Complex = detail::CandidateComplex;

Complex build_complex(std::vector<std::array<int, 3>> tris) {
  Complex cx;
  cx.tris = std::move(tris);
  const std::size_t nt = cx.tris.size();
  std::vector<std::pair<std::uint64_t, std::uint32_t>> entries(3 * nt);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nt), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t t = r.begin(); t != r.end(); ++t)
      for (int k = 0; k < 3; ++k)
        entries[3 * t + k] = {edge_key(cx.tris[t][k], cx.tris[t][(k + 1) % 3]), std::uint32_t(3 * t + k)};
  });
  tbb::parallel_sort(entries.begin(), entries.end());
  cx.tri_edges.resize(nt);
  cx.edge_tris.resize(3 * nt);
  cx.edge_start.reserve(3 * nt / 2 + 2);
  for (std::size_t i = 0; i < entries.size(); ++i) {
    if (i == 0 || entries[i].first != entries[i - 1].first) {
      cx.edge_start.push_back(i);
      cx.edge_verts.push_back({int(entries[i].first >> 32), int(entries[i].first & 0xffffffffu)});
    }
    const std::uint32_t slot = entries[i].second;
    cx.edge_tris[i] = int(slot / 3);
    cx.tri_edges[slot / 3][slot % 3] = int(cx.edge_verts.size() - 1);
  }
  cx.edge_start.push_back(entries.size());
  return cx;
}

int third_vertex(const std::array<int, 3>& t, int a, int b) {
  for (int v : t)
    if (v != a && v != b) return v;
  return t[0];
}

/// Angles (radians, [0, 2 pi)) of the half-planes of `tris` around the edge a -> b, measured from
/// `reference` (a direction perpendicular-ish to the edge) towards axis x reference.
void edge_angles(const std::vector<Vector3d>& p, int a, int b, const Vector3d& reference, const int* tris,
                 std::size_t count, const Complex& cx, double* out) {
  const Vector3d axis = (p[b] - p[a]).normalized();
  Vector3d e1 = reference - reference.dot(axis) * axis;
  e1.normalize();
  const Vector3d e2 = axis.cross(e1);
  for (std::size_t i = 0; i < count; ++i) {
    const Vector3d w = p[third_vertex(cx.tris[tris[i]], a, b)] - p[a];
    double ang = std::atan2(w.dot(e2), w.dot(e1));
    if (ang < 0) ang += 2 * std::numbers::pi;
    out[i] = ang;
  }
}

/// Repeatedly removes the triangles at sharp edges (see CoconeParams::sharp_edge_angle_deg); when
/// `rim_is_sharp`, an edge with a single triangle is sharp too. Returns the number removed.
std::size_t prune_sharp(const Complex& cx, const std::vector<Vector3d>& p, std::vector<char>& alive,
                        double max_gap_rad, bool rim_is_sharp) {
  const std::size_t ne = cx.edge_verts.size();
  std::vector<int> queue(ne);
  std::iota(queue.begin(), queue.end(), 0);
  std::vector<char> queued(ne, 1);
  std::vector<int> live;
  std::vector<double> ang;
  std::size_t removed = 0;
  // FIFO over a growing vector: deterministic, each edge re-queued only when a triangle of it dies.
  for (std::size_t head = 0; head < queue.size(); ++head) {
    const int e = queue[head];
    queued[e] = 0;
    live.clear();
    for (std::size_t i = cx.edge_start[e]; i < cx.edge_start[e + 1]; ++i)
      if (alive[cx.edge_tris[i]]) live.push_back(cx.edge_tris[i]);
    if (live.empty()) continue;
    bool sharp = false;
    if (live.size() == 1) {
      sharp = rim_is_sharp;
    } else if (max_gap_rad < 2 * std::numbers::pi) {
      const int a = cx.edge_verts[e][0], b = cx.edge_verts[e][1];
      const Vector3d ref = p[third_vertex(cx.tris[live[0]], a, b)] - p[a];
      ang.resize(live.size());
      edge_angles(p, a, b, ref, live.data(), live.size(), cx, ang.data());
      std::sort(ang.begin(), ang.end());
      double gap = 2 * std::numbers::pi - (ang.back() - ang.front());
      for (std::size_t i = 1; i < ang.size(); ++i) gap = std::max(gap, ang[i] - ang[i - 1]);
      sharp = gap > max_gap_rad;
    }
    if (!sharp) continue;
    for (int t : live) {
      alive[t] = 0;
      ++removed;
      for (int k = 0; k < 3; ++k) {
        const int f = cx.tri_edges[t][k];
        if (!queued[f]) {
          queued[f] = 1;
          queue.push_back(f);
        }
      }
    }
  }
  return removed;
}

/// Connected components of the alive triangles (sharing an edge); -1 for dead triangles.
/// Components are numbered in the order of their smallest triangle index.
std::vector<int> components(const Complex& cx, const std::vector<char>& alive, int& count) {
  const std::size_t nt = cx.tris.size();
  std::vector<int> comp(nt, -1);
  std::vector<int> stack;
  count = 0;
  for (std::size_t s = 0; s < nt; ++s) {
    if (!alive[s] || comp[s] >= 0) continue;
    comp[s] = count;
    stack.push_back(int(s));
    while (!stack.empty()) {
      const int t = stack.back();
      stack.pop_back();
      for (int k = 0; k < 3; ++k) {
        const int e = cx.tri_edges[t][k];
        for (std::size_t i = cx.edge_start[e]; i < cx.edge_start[e + 1]; ++i) {
          const int u = cx.edge_tris[i];
          if (alive[u] && comp[u] < 0) {
            comp[u] = count;
            stack.push_back(u);
          }
        }
      }
    }
    ++count;
  }
  return comp;
}

}  // namespace

const EnumNames<DelaunayBoundary>& delaunay_boundary_names() {
  static const EnumNames<DelaunayBoundary> names{{{DelaunayBoundary::Auto, "auto"}, {DelaunayBoundary::Closed, "closed"}, {DelaunayBoundary::Open, "open"}}};
  return names;
}

const FieldTable<DelaunaySurfaceParams>& DelaunaySurfaceParams::fields() {
  static const FieldTable<DelaunaySurfaceParams> table = [] {
    FieldTable<DelaunaySurfaceParams> t;
    detail::add_delaunay_fields(t);
    return t;
  }();
  return table;
}

void DelaunaySurfaceParams::validate(const char* method) const {
  const DelaunaySurfaceParams& params = *this;
  if (!(params.normal_filter_angle_deg > 0.0 && params.normal_filter_angle_deg <= 90.0))
    throw UsageError(fmt::format("{}: normal_filter_angle_deg = {}, expected a value in (0, 90]",
                                 method, params.normal_filter_angle_deg));
  if (!(params.sharp_edge_angle_deg >= 180.0 && params.sharp_edge_angle_deg <= 360.0))
    throw UsageError(fmt::format("{}: sharp_edge_angle_deg = {}, expected a value in [180, 360]", method,
                                 params.sharp_edge_angle_deg));
  if (!(params.max_boundary_edge_in_spacings >= 0.0) || !std::isfinite(params.max_boundary_edge_in_spacings))
    throw UsageError(fmt::format("{}: max_boundary_edge_in_spacings = {}, expected a finite value >= 0 (0: off)", method,
                                 params.max_boundary_edge_in_spacings));
  if (!(params.max_hole_perimeter_in_spacings >= 0.0) || !std::isfinite(params.max_hole_perimeter_in_spacings))
    throw UsageError(fmt::format("{}: max_hole_perimeter_in_spacings = {}, expected a finite value >= 0 (0: off)", method,
                                 params.max_hole_perimeter_in_spacings));
  fields().validate(*this, method);
}

namespace detail {

DelaunaySetup prepare_delaunay(const PointCloud& cloud, const char* method, DelaunaySurfaceStats& stats,
                               ProgressReporter& reporter) {
  cloud.validate();
  const std::size_t n = cloud.size();
  if (n < 4) throw UsageError(fmt::format("{}: the cloud has {} points, expected at least 4", method, n));
  if (n > std::size_t(std::numeric_limits<int>::max() / 4))
    throw UsageError(fmt::format("{}: the cloud has {} points, expected at most {}", method, n,
                                 std::numeric_limits<int>::max() / 4));
  for (std::size_t i = 0; i < n; ++i)
    if (!cloud.positions[i].allFinite())
      throw InputError(fmt::format("{}: point {} has a non-finite coordinate, expected finite x, y, z", method, i));
  stats.input_points = n;
  reporter.report(0.0);
  reporter.throw_if_cancelled();

  DelaunaySetup setup;
  // Local origin: the bounding-box centre, so that georeferenced coordinates keep their precision.
  setup.origin = bounding_box(cloud.positions).center();
  std::vector<Vector3d>& p = setup.p;
  p.resize(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) p[i] = cloud.positions[i] - setup.origin;
  });
  const KdTree tree(p);
  setup.spacing = mean_spacing(tree);

  const auto t0 = std::chrono::steady_clock::now();
  setup.cells = delaunay_cells(p);
  stats.seconds_delaunay = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  reporter.report(0.45);
  reporter.throw_if_cancelled();
  const int dim = setup.cells.dimension;
  if (dim < 3) {
    const char* what = dim == 2 ? "coplanar" : dim == 1 ? "collinear" : "identical";
    throw ComputeError(fmt::format(
        "{}: all {} points are {} (Delaunay dimension {}), expected points spread in 3D; use ball pivoting "
        "for a planar patch",
        method, n, what, dim));
  }
  stats.duplicate_points = setup.cells.duplicates;
  stats.delaunay_cells = setup.cells.finite_cells;
  setup.poles = voronoi_poles(setup.cells, p, tree);
  stats.hull_points = setup.poles.hull_points;
  reporter.report(0.55);
  reporter.throw_if_cancelled();
  return setup;
}

DelaunayExtraction::DelaunayExtraction(const PointCloud& cloud, const DelaunaySetup& setup,
                                       std::vector<std::array<int, 3>> candidates, const DelaunaySurfaceParams& params,
                                       DelaunaySurfaceStats& stats)
    : cloud(cloud), setup(setup), params(params), stats(stats), max_gap(params.sharp_edge_angle_deg * std::numbers::pi / 180.0),
      candidates(std::move(candidates)) {}

void DelaunayExtraction::filter_by_normals() {
  const std::vector<Vector3d>& p = setup.p;
  const std::vector<Vector3d>& pole = setup.poles.axis;
  stats.candidate_triangles = candidates.size();
  const double cos_filter = std::cos(params.normal_filter_angle_deg * std::numbers::pi / 180.0);
  std::vector<char> drop(candidates.size(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, candidates.size()), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t t = r.begin(); t != r.end(); ++t) {
      const auto [a, b, d] = candidates[t];
      Vector3d normal = (p[b] - p[a]).cross(p[d] - p[a]);
      const double len = normal.norm();
      bool filtered = !(len > 0.0);
      if (!filtered && cos_filter > 0.0) {
        normal /= len;
        for (int q : {a, b, d})
          if (pole[q] != Vector3d::Zero() && std::abs(normal.dot(pole[q])) < cos_filter) filtered = true;
      }
      drop[t] = filtered ? 1 : 0;
    }
  });
  std::size_t w = 0;
  for (std::size_t t = 0; t < candidates.size(); ++t)
    if (!drop[t]) candidates[w++] = candidates[t];
  stats.normal_filtered = candidates.size() - w;
  candidates.resize(w);
}

void DelaunayExtraction::index_edges() {
  cx = build_complex(std::move(candidates));
  alive.assign(cx.tris.size(), 1);
}

void DelaunayExtraction::prune_sharp_edges() {
  const std::vector<Vector3d>& p = setup.p;
  const std::size_t nt = cx.tris.size();
  if (params.boundary == DelaunayBoundary::Closed) {
    stats.pruned = prune_sharp(cx, p, alive, max_gap, true);
    return;
  }
  stats.pruned = prune_sharp(cx, p, alive, max_gap, false);
  if (params.boundary != DelaunayBoundary::Auto) return;
  // Auto: a piece is closed when the closed pruning (rims sharp too) keeps at least half of it.
  std::vector<char> closed = alive;
  prune_sharp(cx, p, closed, max_gap, true);
  int count = 0;
  const std::vector<int> comp = components(cx, alive, count);
  std::vector<std::size_t> open_count(count, 0), closed_count(count, 0);
  for (std::size_t t = 0; t < nt; ++t)
    if (alive[t]) {
      ++open_count[comp[t]];
      if (closed[t]) ++closed_count[comp[t]];
    }
  std::vector<char> use_closed(count, 0);
  for (int k = 0; k < count; ++k) {
    use_closed[k] = 2 * closed_count[k] >= open_count[k] ? 1 : 0;
    ++(use_closed[k] ? stats.closed_pieces : stats.open_pieces);
  }
  for (std::size_t t = 0; t < nt; ++t)
    if (alive[t] && use_closed[comp[t]] && !closed[t]) {
      alive[t] = 0;
      ++stats.pruned;
    }
}

void DelaunayExtraction::split_pieces() {
  const std::size_t nt = cx.tris.size();
  piece_count = 0;
  const std::vector<int> piece = components(cx, alive, piece_count);
  if (params.boundary == DelaunayBoundary::Closed) stats.closed_pieces = std::size_t(piece_count);
  if (params.boundary == DelaunayBoundary::Open) stats.open_pieces = std::size_t(piece_count);
  piece_start.assign(std::size_t(piece_count) + 1, 0);
  for (std::size_t t = 0; t < nt; ++t)
    if (piece[t] >= 0) ++piece_start[piece[t] + 1];
  for (int k = 0; k < piece_count; ++k) piece_start[k + 1] += piece_start[k];
  piece_tris.assign(piece_start[piece_count], 0);
  std::vector<std::size_t> fill(piece_start.begin(), piece_start.end() - 1);
  for (std::size_t t = 0; t < nt; ++t)
    if (piece[t] >= 0) piece_tris[fill[piece[t]]++] = int(t);
}

void DelaunayExtraction::walk_pieces() {
  const std::size_t nt = cx.tris.size();
  edge_used.assign(cx.edge_verts.size(), {-1, -1});
  oriented.assign(nt, {});
  state.assign(nt, 0);
  out_tris.clear();
  out_piece.clear();
  out_src.clear();
  for (int k = 0; k < piece_count; ++k) {
    const int seed = seed_of(k);
    std::array<int, 3> o = cx.tris[seed];
    const std::vector<Vector3d>& p = setup.p;
    if ((p[o[1]] - p[o[0]]).cross(p[o[2]] - p[o[0]]).x() < 0) std::swap(o[1], o[2]);
    if (!try_accept(seed, o)) continue;
    walk_from(k, seed);
  }
  stats.walk_dropped = 0;
  for (std::size_t t = 0; t < nt; ++t)
    if (alive[t] && state[t] != 1) ++stats.walk_dropped;
}

// Seed: at the piece's vertex of largest x, its triangle most facing +x.
int DelaunayExtraction::seed_of(int k) const {
  const std::vector<Vector3d>& p = setup.p;
  int top = -1;
  for (std::size_t j = piece_start[k]; j < piece_start[k + 1]; ++j)
    for (int v : cx.tris[piece_tris[j]])
      if (top < 0 || p[v].x() > p[top].x() || (p[v].x() == p[top].x() && v < top)) top = v;
  int seed = -1;
  double best = -1.0;
  for (std::size_t j = piece_start[k]; j < piece_start[k + 1]; ++j) {
    const auto& t = cx.tris[piece_tris[j]];
    if (t[0] != top && t[1] != top && t[2] != top) continue;
    const Vector3d nrm = (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]);
    const double score = std::abs(nrm.x()) / std::max(nrm.norm(), 1e-300);
    if (score > best) best = score, seed = piece_tris[j];
  }
  return seed;
}

// Breadth-first from the accepted `seed` over the edges of piece k.
void DelaunayExtraction::walk_from(int k, int seed) {
  bfs_.assign(1, seed);
  for (std::size_t head = 0; head < bfs_.size(); ++head) {
    const int t = bfs_[head];
    const std::array<int, 3> ot = oriented[t];
    out_tris.emplace_back(ot[0], ot[1], ot[2]);
    out_piece.push_back(k);
    out_src.push_back(t);
    for (int j = 0; j < 3; ++j) join_across(t, ot, j);
  }
}

// The edge of triangle t between vertices a and b.
int DelaunayExtraction::edge_of(int t, int a, int b) const {
  int e = -1;
  for (int m = 0; m < 3; ++m)
    if (cx.edge_verts[cx.tri_edges[t][m]] == std::array<int, 2>{std::min(a, b), std::max(a, b)}) e = cx.tri_edges[t][m];
  return e;
}

// Joins the outer neighbour of the accepted triangle t (orientation ot) across its edge j.
void DelaunayExtraction::join_across(int t, const std::array<int, 3>& ot, int j) {
  const std::vector<Vector3d>& p = setup.p;
  const int a = ot[j], b = ot[(j + 1) % 3];
  const int e = edge_of(t, a, b);
  if (edge_used[e][1] >= 0) return;
  live_.clear();
  for (std::size_t i = cx.edge_start[e]; i < cx.edge_start[e + 1]; ++i) {
    const int u = cx.edge_tris[i];
    if (u != t && alive[u]) live_.push_back(u);
  }
  if (live_.empty()) return;
  // The first triangle met turning around a -> b from t towards t's outer (normal) side:
  // with e1 along t's half-plane and e2 = axis x e1 = the normal side, the smallest angle.
  ang_.resize(live_.size());
  edge_angles(p, a, b, p[ot[(j + 2) % 3]] - p[a], live_.data(), live_.size(), cx, ang_.data());
  // edge_angles measures towards axis x e1; t's normal is along (b - a) x (c - a), the
  // same side, so the smallest angle is the outer neighbour.
  // If the outer neighbour cannot join (one of its other edges is taken, or it would be
  // traversed the wrong way), the next ones in angular order are tried, so that a conflict
  // far away does not leave a hole here; try_accept keeps the result edge-manifold and
  // oriented whichever one joins.
  rank_.resize(live_.size());
  std::iota(rank_.begin(), rank_.end(), std::size_t{0});
  std::sort(rank_.begin(), rank_.end(), [&](std::size_t x, std::size_t y) {
    return ang_[x] < ang_[y] || (ang_[x] == ang_[y] && live_[x] < live_[y]);
  });
  // A fold (s turns back onto t's outer side within the wedge that makes an edge sharp)
  // is taken only where nothing else can join, as at the tip of a spike: through a fold the
  // walk would orient what it reaches inside out, and where that meets the rest a seam of
  // holes opens that no filling closes (on thin parts, a few spacings across).
  const double min_turn = 2 * std::numbers::pi - max_gap;
  for (int pass = 0; pass < 2; ++pass)
    for (std::size_t i : rank_) {
      const int s = live_[i];
      if (state[s] == 1) return;
      if (state[s] == -1 || (ang_[i] < min_turn) != (pass == 1)) continue;
      const int d = third_vertex(cx.tris[s], a, b);
      if (try_accept(s, {b, a, d})) {
        bfs_.push_back(s);
        return;
      }
      state[s] = -1;
    }
}

// Whether triangle t, as oriented, traverses a -> b.
bool DelaunayExtraction::directed(int t, int a, int b) const {
  const auto& o = oriented[t];
  for (int k = 0; k < 3; ++k)
    if (o[k] == a && o[(k + 1) % 3] == b) return true;
  return false;
}

// Accepts triangle t in orientation o if each of its edges has a free slot and, when already
// used once, is traversed the other way by that triangle.
bool DelaunayExtraction::try_accept(int t, const std::array<int, 3>& o) {
  oriented[t] = o;
  for (int k = 0; k < 3; ++k) {
    const int a = o[k], b = o[(k + 1) % 3];
    const auto& used = edge_used[edge_of(t, a, b)];
    if (used[1] >= 0) return false;
    if (used[0] >= 0 && directed(used[0], a, b)) return false;
  }
  for (int j = 0; j < 3; ++j) {
    auto& used = edge_used[cx.tri_edges[t][j]];
    (used[0] < 0 ? used[0] : used[1]) = t;
  }
  state[t] = 1;
  return true;
}

// Where an open surface's rim is concave, the Delaunay triangulation fills it with long thin
// triangles that pass the cocone test (they lie in the surface); they are peeled from the
// boundary inward while their boundary edge is too long and one of its ends is on the cloud's
// border (the angular-gap test of features/boundary_points.h). Closed pieces have no boundary
// edge and are untouched; the rim of a hole in a closed surface (a thin part the candidates
// missed) is not on the border, and peeling it would only widen the hole.
void DelaunayExtraction::peel_rim() {
  if (!(params.max_boundary_edge_in_spacings > 0.0) || out_tris.empty()) return;
  const std::vector<Vector3d>& p = setup.p;
  const double max_len2 = std::pow(params.max_boundary_edge_in_spacings * setup.spacing, 2);
  std::vector<int> out_of(cx.tris.size(), -1);  // candidate -> output triangle
  for (std::size_t j = 0; j < out_src.size(); ++j) out_of[out_src[j]] = int(j);
  std::vector<char> keep(out_tris.size(), 1);
  std::vector<std::uint8_t> border;  // computed when a long boundary edge is met
  auto peelable = [&](int e) {
    const auto [a, b] = cx.edge_verts[e];
    if (!((p[a] - p[b]).squaredNorm() > max_len2)) return false;
    if (border.empty()) border = detect_boundary_points(cloud).boundary;
    return border[std::size_t(a)] != 0 || border[std::size_t(b)] != 0;
  };
  auto other_on = [&](int e, int t) { return edge_used[e][0] == t ? edge_used[e][1] : edge_used[e][0]; };
  std::vector<int> peel;
  for (std::size_t j = 0; j < out_src.size(); ++j)
    for (int e : cx.tri_edges[out_src[j]])
      if (edge_used[e][1] < 0 && peelable(e)) {
        peel.push_back(int(j));
        break;
      }
  while (!peel.empty()) {
    const int j = peel.back();
    peel.pop_back();
    if (!keep[j]) continue;
    keep[j] = 0;
    ++stats.rim_peeled;
    const int t = out_src[j];
    for (int e : cx.tri_edges[t]) {
      const int u = other_on(e, t);
      edge_used[e] = {u, -1};
      if (u >= 0 && keep[out_of[u]] && peelable(e)) peel.push_back(out_of[u]);
    }
  }
  std::size_t w = 0;
  for (std::size_t j = 0; j < out_tris.size(); ++j)
    if (keep[j]) {
      out_tris[w] = out_tris[j];
      out_piece[w] = out_piece[j];
      out_src[w] = out_src[j];
      ++w;
    }
  out_tris.resize(w);
  out_piece.resize(w);
  out_src.resize(w);
}

void DelaunayExtraction::orient_pieces() {
  std::vector<std::size_t> start(std::size_t(piece_count) + 1, 0);
  for (int k : out_piece) ++start[k + 1];
  for (int k = 0; k < piece_count; ++k) start[k + 1] += start[k];
  // out_tris is grouped by piece (pieces are walked one after another).
  std::vector<char> flip(std::size_t(piece_count), 0);
  tbb::parallel_for(0, piece_count, [&](int k) {
    if (start[k] == start[k + 1]) return;
    flip[k] = orientation_score(start[k], start[k + 1]) < 0.0 ? 1 : 0;
  });
  for (std::size_t j = 0; j < out_tris.size(); ++j)
    if (flip[out_piece[j]]) std::swap(out_tris[j][1], out_tris[j][2]);
  stats.flipped_pieces = std::size_t(std::count(flip.begin(), flip.end(), char(1)));
}

// How much the output triangles [begin, end) (one piece) face outwards; negative: inwards.
double DelaunayExtraction::orientation_score(std::size_t begin, std::size_t end) const {
  const std::vector<Vector3d>& p = setup.p;
  double score = 0.0;
  if (cloud.has_normals()) {
    for (std::size_t j = begin; j < end; ++j) {
      const Triangle& t = out_tris[j];
      const Vector3d nrm = (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]);
      score += nrm.dot(cloud.normals[t[0]] + cloud.normals[t[1]] + cloud.normals[t[2]]);
    }
    return score;
  }
  // Closed: signed volume. Open: agreement with the hull pole vectors (outward by
  // construction) when they decide, else facing away from the piece's centroid.
  const std::vector<Vector3d>& hull_normal = setup.poles.hull_normal;
  const std::vector<char>& on_hull = setup.poles.on_hull;
  bool closed = true;
  Vector3d centroid = Vector3d::Zero();
  for (std::size_t j = begin; j < end; ++j) {
    const Triangle& t = out_tris[j];
    centroid += (p[t[0]] + p[t[1]] + p[t[2]]) / 3.0;
    for (int e : cx.tri_edges[out_src[j]])
      if (edge_used[e][1] < 0) closed = false;
  }
  centroid /= double(end - begin);
  double volume = 0.0, hull_score = 0.0, hull_abs = 0.0, centroid_score = 0.0;
  for (std::size_t j = begin; j < end; ++j) {
    const Triangle& t = out_tris[j];
    const Vector3d a = p[t[0]] - centroid, b = p[t[1]] - centroid, c = p[t[2]] - centroid;
    const Vector3d nrm = (b - a).cross(c - a);
    volume += a.dot(b.cross(c));
    centroid_score += nrm.dot(a + b + c);
    for (int m = 0; m < 3; ++m)
      if (on_hull[t[m]]) {
        hull_score += nrm.dot(hull_normal[t[m]]);
        hull_abs += std::abs(nrm.dot(hull_normal[t[m]]));
      }
  }
  if (closed) return volume;
  if (std::abs(hull_score) > 0.2 * hull_abs) return hull_score;
  return centroid_score;
}

void DelaunayExtraction::build_mesh() {
  reconstruction.mean_spacing = setup.spacing;
  if (cloud.has_normals()) {
    reconstruction.mesh = TriangleMesh{cloud, std::move(out_tris), {}};
    return;
  }
  // Area-weighted face normals per vertex decide the sign of each pole vector; samples without
  // a finite pole (hull samples) take the face normal itself when they have triangles.
  const std::vector<Vector3d>& p = setup.p;
  const std::vector<int>& rep = setup.cells.representative;
  const std::vector<Vector3d>& pole = setup.poles.axis;
  const std::vector<char>& finite_pole = setup.poles.finite_pole;
  const std::size_t n = p.size();
  std::vector<Vector3d> face_sum(n, Vector3d::Zero());
  for (const Triangle& t : out_tris) {
    const Vector3d nrm = (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]);
    for (int m = 0; m < 3; ++m) face_sum[t[m]] += nrm;
  }
  std::vector<Vector3d> normals(n, Vector3d::Zero());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const int v = rep[i];
      Vector3d nrm = pole[v];
      const double f = face_sum[v].norm();
      if (!finite_pole[v] && f > 0.0)
        nrm = face_sum[v] / f;
      else if (f > 0.0 && nrm.dot(face_sum[v]) < 0.0)
        nrm = -nrm;
      normals[i] = nrm;
    }
  });
  PointCloud copy = cloud;
  copy.normals = std::move(normals);
  reconstruction.mesh = TriangleMesh{std::move(copy), std::move(out_tris), {}};
}

// Undersampled spots (random samples, thin parts) leave holes where the candidates missed a
// triangle or the walk met a conflict: the hole filler every reconstruction shares closes those
// up to the perimeter limit, by the vertex normals of build_mesh.
void DelaunayExtraction::fill_small_holes() {
  const HoleFillStats filled = fill_holes(reconstruction.mesh, HoleFillParams{params.max_hole_perimeter_in_spacings});
  stats.holes_filled = filled.holes_filled;
  stats.fill_triangles = filled.triangles_added;
  stats.fill_triangles_removed = filled.triangles_removed;
  reconstruction.topology = analyze_topology(reconstruction.mesh);
  reconstruction.unused_points = reconstruction.topology.isolated_vertices;
}

ReconstructionResult extract_delaunay_surface(const PointCloud& cloud, const DelaunaySetup& setup,
                                              std::vector<std::array<int, 3>> candidates,
                                              const DelaunaySurfaceParams& params, DelaunaySurfaceStats& stats,
                                              ProgressReporter& reporter) {
  DelaunayExtraction x(cloud, setup, std::move(candidates), params, stats);
  x.filter_by_normals();
  reporter.report(0.7);
  reporter.throw_if_cancelled();
  x.index_edges();
  x.prune_sharp_edges();
  reporter.report(0.8);
  reporter.throw_if_cancelled();
  x.split_pieces();
  x.walk_pieces();
  x.peel_rim();
  reporter.report(0.9);
  reporter.throw_if_cancelled();
  x.orient_pieces();
  x.build_mesh();
  x.fill_small_holes();
  return std::move(x).result();
}


ReconstructionStats common_stats(const DelaunaySurfaceStats& stats, std::vector<std::pair<std::string, std::size_t>> extra) {
  ReconstructionStats out;
  out.input_points = stats.input_points;
  out.duplicate_points = stats.duplicate_points;
  out.candidate_triangles = stats.candidate_triangles;
  out.holes_filled = stats.holes_filled;
  out.fill_triangles = stats.fill_triangles;
  out.seconds = stats.seconds_total;
  out.counts = {{"delaunay_cells", stats.delaunay_cells}, {"hull_points", stats.hull_points},
                {"normal_filtered", stats.normal_filtered},  {"pruned", stats.pruned},
                {"open_pieces", stats.open_pieces},          {"closed_pieces", stats.closed_pieces},
                {"walk_dropped", stats.walk_dropped},        {"rim_peeled", stats.rim_peeled},
                {"flipped_pieces", stats.flipped_pieces},    {"fill_triangles_removed", stats.fill_triangles_removed}};
  out.counts.insert(out.counts.end(), extra.begin(), extra.end());
  out.figures = {{"seconds_delaunay", stats.seconds_delaunay}};
  return out;
}

}  // namespace detail
}  // namespace pointsurf
