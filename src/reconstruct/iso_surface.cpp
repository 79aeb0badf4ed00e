// SPDX-License-Identifier: GPL-3.0-or-later
// Octree iso-surface extraction (reconstruct/detail/iso_surface.h).
//
// Method: marching cubes on the finest lattice, restricted to the cells the surface crosses.
// Every finest leaf of the octree is a seed; a coarser leaf whose corners change sign along one
// of its edges seeds the finest cells around the finest sub-edge that carries the change (found
// by bisection). From the seeds the surface is followed: every finest cell with a crossed edge
// pulls in the other three cells around that edge, so each crossed edge ends up with all four
// of its cells meshed. The surface is therefore uniform at the finest level wherever it goes
// (inside coarse leaves too), which makes it crack-free by construction: there are no cells of
// two sizes to stitch.
//
// Each cell is meshed without a 256-case table: on each of its six faces the crossings are
// joined by marching squares, ambiguous faces decided by the asymptotic decider evaluated in a
// canonical corner order (both cells sharing a face compute the same expression, so they join the
// same crossings); the oriented face segments close into loops, and each loop is triangulated
// with diagonals between crossings that share no cell face (such a diagonal belongs to this cell
// alone), or fanned around a centre vertex when no such triangulation exists. Each crossing is
// then on exactly one loop per cell and each segment on exactly two cells, so the surface is
// closed, edge- and vertex-manifold and consistently oriented. Corner values equal to the
// iso-value count as outside, so no vertex sits on a corner shared by several crossings.
//
// Vertices are keyed by the finest edge they lie on and numbered in key order; triangles come in
// cell-key order from fixed chunks, so the output is the same for any thread count.
//
// The phases are the members of iso::Extraction (reconstruct/detail/iso_extraction.h).
#include "reconstruct/detail/iso_surface.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <unordered_map>
#include <utility>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "pointsurf/core/error.h"
#include "core/detail/progress_reporter.h"
#include "reconstruct/detail/iso_extraction.h"

namespace pointsurf::detail {
namespace iso {
namespace {

constexpr std::size_t kChunk = 2048;

void sort_unique(std::vector<Key>& keys) {
  tbb::parallel_sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
}

std::vector<Key> gather(tbb::enumerable_thread_specific<std::vector<Key>>& buffers) {
  std::vector<Key> all;
  for (std::vector<Key>& b : buffers) {
    all.insert(all.end(), b.begin(), b.end());
    b.clear();
  }
  sort_unique(all);
  return all;
}

// ---- Cell combinatorics: corner i = x | y << 1 | z << 2; edge a * 4 + bit(a+1) + 2 bit(a+2).
struct CellTables {
  std::array<std::array<int, 2>, 12> edge_corners{};  // low, high corner of each edge
  std::array<std::array<int, 4>, 6> face_corners{};    // face 2a+s: q0..q3 in (u, v) order
  std::array<std::array<int, 4>, 6> face_edges{};      // q_k -> q_k+1
  std::array<std::array<bool, 12>, 12> share_face{};

  CellTables() {
    auto edge_of = [](int c0, int c1) {
      const int axis = c0 ^ c1 ? (((c0 ^ c1) == 1) ? 0 : ((c0 ^ c1) == 2 ? 1 : 2)) : -1;
      const int lo = std::min(c0, c1);
      const int b = (axis + 1) % 3, c = (axis + 2) % 3;
      return axis * 4 + ((lo >> b) & 1) + 2 * ((lo >> c) & 1);
    };
    for (int e = 0; e < 12; ++e) {
      const int axis = e / 4, b = (axis + 1) % 3, c = (axis + 2) % 3;
      const int lo = (((e & 3) & 1) << b) | (((e & 3) >> 1) << c);
      edge_corners[e] = {lo, lo | (1 << axis)};
    }
    for (int a = 0; a < 3; ++a) {
      const int u = (a + 1) % 3, v = (a + 2) % 3;
      for (int s = 0; s < 2; ++s) {
        const int f = 2 * a + s;
        const int uv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
        for (int k = 0; k < 4; ++k) face_corners[f][k] = (s << a) | (uv[k][0] << u) | (uv[k][1] << v);
        for (int k = 0; k < 4; ++k) face_edges[f][k] = edge_of(face_corners[f][k], face_corners[f][(k + 1) % 4]);
        for (int i = 0; i < 4; ++i)
          for (int j = 0; j < 4; ++j) share_face[face_edges[f][i]][face_edges[f][j]] = true;
      }
    }
  }
};
const CellTables& tables() {
  static const CellTables t;
  return t;
}

int corner_local(int cell, int k) {
  return (cell % kB + (k & 1)) + kC * ((cell / kB) % kB + ((k >> 1) & 1)) + kC * kC * (cell / (kB * kB) + ((k >> 2) & 1));
}
int brick_mask(const Brick& b, int cell) {
  int mask = 0;
  for (int k = 0; k < 8; ++k) mask |= (b.w[corner_local(cell, k)] > 0.0) << k;
  return mask;
}

}  // namespace

/// The oriented face segments of one cell closed into loops of local edge ids, each loop
/// counter-clockwise seen from outside the surface. `w` holds corner values minus the iso-value,
/// sign-adjusted so that inside is positive.
int cell_loops(const std::array<double, 8>& w, std::array<int, 12>& loop_edges, std::array<int, 5>& loop_start) {
  const CellTables& t = tables();
  std::array<int, 12> next;
  next.fill(-1);
  for (int f = 0; f < 6; ++f) {
    const bool outward_positive = (f & 1) != 0;  // s = 1: looking from +axis sees q0..q3 CCW
    std::array<bool, 4> in;
    for (int k = 0; k < 4; ++k) in[k] = w[t.face_corners[f][k]] > 0.0;
    auto add = [&](int from_k, int to_k) {  // segment entering edge -> leaving edge for s = 1
      const int a = t.face_edges[f][from_k], b = t.face_edges[f][to_k];
      if (outward_positive) next[a] = b;
      else next[b] = a;
    };
    const int count = int(in[0]) + int(in[1]) + int(in[2]) + int(in[3]);
    if (count == 0 || count == 4) continue;
    if (count == 2 && in[0] == in[2]) {  // ambiguous face: asymptotic decider, canonical order
      const double q0 = w[t.face_corners[f][0]], q1 = w[t.face_corners[f][1]];
      const double q2 = w[t.face_corners[f][2]], q3 = w[t.face_corners[f][3]];
      const bool inside_02 = in[0];
      const double inside_product = inside_02 ? q0 * q2 : q1 * q3;
      const double outside_product = inside_02 ? q1 * q3 : q0 * q2;
      const bool inside_connected = inside_product > outside_product;
      for (int k = 0; k < 4; ++k) {
        const int prev = (k + 3) % 4;
        if (inside_connected && !in[k]) add(k, prev);  // around an outside corner
        if (!inside_connected && in[k]) add(prev, k);  // around an inside corner
      }
      continue;
    }
    int entering = -1, leaving = -1;
    for (int k = 0; k < 4; ++k) {
      if (!in[k] && in[(k + 1) % 4]) entering = k;
      if (in[k] && !in[(k + 1) % 4]) leaving = k;
    }
    add(entering, leaving);
  }
  int loops = 0, n = 0;
  std::array<bool, 12> used{};
  for (int e = 0; e < 12; ++e) {
    if (next[e] < 0 || used[e]) continue;
    loop_start[loops++] = n;
    for (int x = e; !used[x]; x = next[x]) {
      used[x] = true;
      loop_edges[n++] = x;
    }
  }
  loop_start[loops] = n;
  return loops;
}

// The root in [0, 1] of the quadratic through (0, wa), (1/2, wm), (1, wb), where wa and wb have
// opposite signs (so exactly one root lies in [0, 1]); the linear root when the quadratic
// degenerates or its root falls outside (rounding).
double quadratic_root(double wa, double wm, double wb) {
  const double linear = wa / (wa - wb);
  const double qa = 2.0 * wa - 4.0 * wm + 2.0 * wb, qb = -3.0 * wa + 4.0 * wm - wb, qc = wa;
  const double disc = qb * qb - 4.0 * qa * qc;
  if (!(disc >= 0.0) || std::abs(qa) <= 1e-12 * (std::abs(qb) + std::abs(qc))) return linear;
  const double q = -0.5 * (qb + std::copysign(std::sqrt(disc), qb));  // no cancellation
  for (const double t : {q != 0.0 ? qc / q : -1.0, qa != 0.0 ? q / qa : -1.0})
    if (t >= 0.0 && t <= 1.0) return t;
  return linear;
}

Brick::Brick() { w.fill(std::numeric_limits<double>::quiet_NaN()); }

void append_chunks(std::vector<ChunkOutput>& chunks, IsoSurface& out) {
  std::size_t triangle_count = 0, vertex_count = out.vertices.size();
  for (const ChunkOutput& o : chunks) triangle_count += o.triangles.size(), vertex_count += o.centres.size();
  out.triangles.reserve(triangle_count);
  out.vertices.reserve(vertex_count);
  out.normals.reserve(vertex_count);
  for (ChunkOutput& o : chunks) {
    const auto offset = static_cast<std::uint32_t>(out.vertices.size());
    for (auto tri : o.triangles) {
      for (std::uint32_t& x : tri)
        if (x & kCentre) x = offset + (x & ~kCentre);
      out.triangles.push_back(tri);
    }
    out.vertices.insert(out.vertices.end(), o.centres.begin(), o.centres.end());
    out.normals.insert(out.normals.end(), o.centre_normals.begin(), o.centre_normals.end());
    o = ChunkOutput();
  }
}

Extraction::Extraction(const IsoFunction& f, const IsoLattice& lattice, const IsoSurfaceParams& params)
    : f_(f), lattice_(lattice), params_(params), depth_(lattice.depth) {
  if (depth_ < 0 || depth_ > kMaxDepth)
    throw UsageError("extract_iso_surface: lattice depth " + std::to_string(depth_) + " outside [0, " +
                     std::to_string(kMaxDepth) + "]");
  if (!(lattice.size > 0.0) || !std::isfinite(lattice.size))
    throw UsageError("extract_iso_surface: lattice size must be positive and finite");
  cells_per_side_ = std::uint32_t{1} << depth_;
  h_ = lattice.size / static_cast<double>(cells_per_side_);
}

Eigen::Vector3d Extraction::position(Key corner) const {
  const auto c = unpack(corner);
  return Eigen::Vector3d(lattice_.origin + h_ * Eigen::Vector3d(c[0], c[1], c[2]));
}

// Values at finest-lattice corners, evaluated in batches.
void Extraction::evaluate(const std::vector<Key>& corners, std::vector<double>& out, ProgressReporter* reporter) const {
  out.resize(corners.size());
  const std::size_t chunks = (corners.size() + kChunk - 1) / kChunk;
  tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
    const std::size_t begin = c * kChunk, end = std::min(corners.size(), begin + kChunk);
    std::vector<std::uint32_t> triples(3 * (end - begin));
    for (std::size_t i = begin; i < end; ++i) {
      const auto p = unpack(corners[i]);
      std::copy(p.begin(), p.end(), triples.begin() + 3 * (i - begin));
    }
    f_.corner_values(depth_, triples.data(), end - begin, out.data() + begin);
    if (reporter) reporter->advance(end - begin);
  });
}

double Extraction::value_at(std::uint32_t x, std::uint32_t y, std::uint32_t z) const {
  const std::uint32_t c[3] = {x, y, z};
  double v = 0.0;
  f_.corner_values(depth_, c, 1, &v);
  return v;
}

// 1. Leaves of the octree, level by level in key order.
void Extraction::find_leaves() {
  std::vector<Key> nodes{pack(0, 0, 0)};
  for (int level = 0; level < depth_ && !nodes.empty(); ++level) {
    std::vector<char> refined(nodes.size());
    tbb::parallel_for(std::size_t(0), nodes.size(), [&](std::size_t i) { refined[i] = f_.refined(level, unpack(nodes[i])); });
    std::vector<Key> children;
    for (std::size_t i = 0; i < nodes.size(); ++i) {
      if (!refined[i]) {
        coarse_leaves_.emplace_back(level, nodes[i]);
        continue;
      }
      const auto c = unpack(nodes[i]);
      for (int k = 0; k < 8; ++k)
        children.push_back(pack(2 * c[0] + (k & 1), 2 * c[1] + ((k >> 1) & 1), 2 * c[2] + ((k >> 2) & 1)));
    }
    nodes = std::move(children);
  }
  seeds_ = std::move(nodes);
  if (seeds_.empty() && !coarse_leaves_.empty()) {
    // No leaf at the lattice's depth (an adaptive octree stopped earlier): mesh at the deepest
    // level that has leaves, whose leaves are then the finest cells.
    depth_ = coarse_leaves_.back().first;
    while (!coarse_leaves_.empty() && coarse_leaves_.back().first == depth_) {
      seeds_.push_back(coarse_leaves_.back().second);
      coarse_leaves_.pop_back();
    }
    cells_per_side_ = std::uint32_t{1} << depth_;
    h_ = lattice_.size / static_cast<double>(cells_per_side_);
  }
}

// The finest cells around the finest edge from `corner` along `axis`, inside the lattice.
void Extraction::cells_around_edge(Key corner, int axis, std::vector<Key>& out) const {
  const auto p = unpack(corner);
  const int b = (axis + 1) % 3, c = (axis + 2) % 3;
  for (int k = 0; k < 4; ++k) {
    std::array<std::int64_t, 3> q = {p[0], p[1], p[2]};
    q[b] -= (k & 1);
    q[c] -= (k >> 1);
    bool inside = true;
    for (int i = 0; i < 3; ++i) inside = inside && q[i] >= 0 && q[i] < std::int64_t{cells_per_side_};
    if (inside) out.push_back(pack(std::uint32_t(q[0]), std::uint32_t(q[1]), std::uint32_t(q[2])));
  }
}

// The seeds of one coarse leaf: for each of its edges whose ends differ in sign, the cells
// around the finest sub-edge where the sign changes. `corners` (sorted) and `values`: the
// coarse leaves' corners.
void Extraction::seeds_of_leaf(int level, Key cell, const std::vector<Key>& corners, const std::vector<double>& values,
                               std::vector<Key>& found) const {
  auto lookup = [&](Key k) { return values[std::lower_bound(corners.begin(), corners.end(), k) - corners.begin()]; };
  const CellTables& t = tables();
  const auto c = unpack(cell);
  const int shift = depth_ - level;
  const std::uint32_t span = std::uint32_t{1} << shift;
  for (int e = 0; e < 12; ++e) {
    const int lo = t.edge_corners[e][0], axis = e / 4;
    std::array<std::uint32_t, 3> p = {(c[0] + (lo & 1)) << shift, (c[1] + ((lo >> 1) & 1)) << shift,
                                      (c[2] + ((lo >> 2) & 1)) << shift};
    std::array<std::uint32_t, 3> q = p;
    q[axis] += span;
    const bool in_p = sign(lookup(pack(p[0], p[1], p[2]))) > 0.0;
    const bool in_q = sign(lookup(pack(q[0], q[1], q[2]))) > 0.0;
    if (in_p == in_q) continue;
    std::uint32_t a = p[axis], b = q[axis];  // invariant: inside(a) == in_p != inside(b)
    while (b - a > 1) {
      const std::uint32_t m = a + (b - a) / 2;
      std::array<std::uint32_t, 3> r = p;
      r[axis] = m;
      if ((sign(value_at(r[0], r[1], r[2])) > 0.0) == in_p) a = m;
      else b = m;
    }
    p[axis] = a;
    cells_around_edge(pack(p[0], p[1], p[2]), axis, found);
  }
}

// 2. Coarse leaves whose edges change sign seed the finest cells at the change.
void Extraction::seed_coarse_crossings(const ProgressCallback& progress, double begin, double end) {
  if (!coarse_leaves_.empty()) {
    std::vector<Key> corners;
    corners.reserve(8 * coarse_leaves_.size());
    for (const auto& [level, cell] : coarse_leaves_) {
      const auto c = unpack(cell);
      const int shift = depth_ - level;
      for (int k = 0; k < 8; ++k)
        corners.push_back(pack((c[0] + (k & 1)) << shift, (c[1] + ((k >> 1) & 1)) << shift, (c[2] + ((k >> 2) & 1)) << shift));
    }
    sort_unique(corners);
    std::vector<double> corner_values;
    // progress: a corner evaluated and a leaf searched count the same
    ProgressReporter reporter(progress, begin, end, corners.size() + coarse_leaves_.size());
    evaluate(corners, corner_values, &reporter);
    reporter.throw_if_cancelled();
    tbb::enumerable_thread_specific<std::vector<Key>> found;
    tbb::parallel_for(std::size_t(0), coarse_leaves_.size(), [&](std::size_t i) {
      seeds_of_leaf(coarse_leaves_[i].first, coarse_leaves_[i].second, corners, corner_values, found.local());
      reporter.advance(1);
    });
    reporter.throw_if_cancelled();
    std::vector<Key> more = gather(found);
    seeds_.insert(seeds_.end(), more.begin(), more.end());
  }
  coarse_leaves_ = {};
  sort_unique(seeds_);
}

// 3. Follow the surface brick by brick: a brick holds 8^3 finest cells and its 9^3 corner
//    values (evaluated on first use); each round processes every brick with pending cells in
//    parallel, following crossed edges inside the brick and posting cells of other bricks.
Brick& Extraction::brick_at(Key brick_key) {
  const auto [it, inserted] = brick_of_.emplace(brick_key, static_cast<std::uint32_t>(bricks_.size()));
  if (inserted) {
    bricks_.push_back(std::make_unique<Brick>());
    bricks_.back()->key = brick_key;
  }
  return *bricks_[it->second];
}

void Extraction::enqueue(Key cell) {
  const auto c = unpack(cell);
  Brick& b = brick_at(pack(c[0] / kB, c[1] / kB, c[2] / kB));
  const int local = int(c[0] % kB) + kB * int(c[1] % kB) + kB * kB * int(c[2] % kB);
  if (b.state[local] & kQueued) return;
  b.state[local] |= kQueued;
  b.pending.push_back(static_cast<std::uint16_t>(local));
}

void Extraction::queue_seeds() {
  for (Key cell : seeds_) enqueue(cell);
  seeds_ = {};
}

// The values of the corners of the wave's cells not evaluated yet.
void Extraction::evaluate_missing_corners(Brick& b, const std::vector<std::uint16_t>& wave) const {
  const auto origin = unpack(b.key);
  const std::array<std::uint32_t, 3> base = {origin[0] * kB, origin[1] * kB, origin[2] * kB};
  std::vector<std::uint16_t> missing;
  for (std::uint16_t cell : wave)
    for (int k = 0; k < 8; ++k) {
      const int corner = corner_local(cell, k);
      if (std::isnan(b.w[corner])) {
        b.w[corner] = 0.0f;  // claimed; written below
        missing.push_back(static_cast<std::uint16_t>(corner));
      }
    }
  std::vector<std::uint32_t> triples(3 * missing.size());
  for (std::size_t i = 0; i < missing.size(); ++i) {
    const int m = missing[i];
    triples[3 * i] = base[0] + m % kC, triples[3 * i + 1] = base[1] + (m / kC) % kC, triples[3 * i + 2] = base[2] + m / (kC * kC);
  }
  std::vector<double> values(missing.size());
  if (!missing.empty()) f_.corner_values(depth_, triples.data(), missing.size(), values.data());
  for (std::size_t i = 0; i < missing.size(); ++i) b.w[missing[i]] = sign(values[i]);
}

// A crossed cell: active, and the four cells around each of its crossed edges queued (into
// next_wave inside the brick, into the outbox outside).
void Extraction::follow_crossed_edges(Brick& b, std::uint16_t cell, std::vector<std::uint16_t>& next_wave) const {
  const int mask = brick_mask(b, cell);
  if (mask == 0 || mask == 255) return;
  b.state[cell] |= kActive;
  const CellTables& t = tables();
  const auto origin = unpack(b.key);
  const std::array<std::uint32_t, 3> base = {origin[0] * kB, origin[1] * kB, origin[2] * kB};
  const std::array<std::uint32_t, 3> c = {base[0] + cell % kB, base[1] + (cell / kB) % kB, base[2] + cell / (kB * kB)};
  for (int e = 0; e < 12; ++e) {
    const int lo = t.edge_corners[e][0], hi = t.edge_corners[e][1];
    if (((mask >> lo) & 1) == ((mask >> hi) & 1)) continue;
    const int axis = e / 4, u = (axis + 1) % 3, v = (axis + 2) % 3;
    const std::array<std::uint32_t, 3> corner = {c[0] + (lo & 1), c[1] + ((lo >> 1) & 1), c[2] + ((lo >> 2) & 1)};
    for (int k = 0; k < 4; ++k) {
      std::array<std::uint32_t, 3> q = corner;
      if ((k & 1) && q[u] == 0) continue;
      if ((k >> 1) && q[v] == 0) continue;
      q[u] -= (k & 1), q[v] -= (k >> 1);
      if (q[u] >= cells_per_side_ || q[v] >= cells_per_side_) continue;
      bool inside_brick = true;
      for (int i = 0; i < 3; ++i) inside_brick = inside_brick && q[i] >= base[i] && q[i] < base[i] + kB;
      if (!inside_brick) {
        b.outbox.push_back(pack(q[0], q[1], q[2]));
        continue;
      }
      const int local = int(q[0] - base[0]) + kB * int(q[1] - base[1]) + kB * kB * int(q[2] - base[2]);
      if (b.state[local] & kQueued) continue;
      b.state[local] |= kQueued;
      next_wave.push_back(static_cast<std::uint16_t>(local));
    }
  }
}

std::size_t Extraction::process(Brick& b) const {
  std::vector<std::uint16_t> wave = std::move(b.pending), next_wave;
  b.pending.clear();
  std::size_t cells = 0;
  while (!wave.empty()) {
    cells += wave.size();
    evaluate_missing_corners(b, wave);
    next_wave.clear();
    for (std::uint16_t cell : wave) follow_crossed_edges(b, cell, next_wave);
    std::swap(wave, next_wave);
  }
  return cells;
}

bool Extraction::follow_round(const std::function<void(std::size_t cells)>& brick_done) {
  std::vector<Brick*> busy;
  for (const auto& b : bricks_)
    if (!b->pending.empty()) busy.push_back(b.get());
  if (busy.empty()) return false;
  tbb::parallel_for(std::size_t(0), busy.size(), [&](std::size_t i) {
    const std::size_t cells = process(*busy[i]);
    if (brick_done) brick_done(cells);
  });
  for (Brick* b : busy) {
    std::vector<Key> outbox = std::move(b->outbox);
    b->outbox.clear();
    for (Key cell : outbox) enqueue(cell);
  }
  return true;
}

void Extraction::index_bricks() {
  std::sort(bricks_.begin(), bricks_.end(), [](const auto& a, const auto& b) { return a->key < b->key; });
  for (std::uint32_t i = 0; i < bricks_.size(); ++i) brick_of_[bricks_[i]->key] = i;
}

// 4. One vertex per crossed finest edge, owned by the brick of the cell at the edge's lower
//    corner (clamped into the lattice); numbered brick by brick in key order.
const Brick* Extraction::owner_and_edge(const Brick& b, int cell, int e, std::uint16_t& local_edge) const {
  const auto origin = unpack(b.key);
  const int lo = tables().edge_corners[e][0];
  std::array<std::uint32_t, 3> corner = {origin[0] * kB + cell % kB + (lo & 1), origin[1] * kB + (cell / kB) % kB + ((lo >> 1) & 1),
                                         origin[2] * kB + cell / (kB * kB) + ((lo >> 2) & 1)};
  std::array<std::uint32_t, 3> owner;
  for (int i = 0; i < 3; ++i) owner[i] = std::min(corner[i], cells_per_side_ - 1) / kB;
  const Brick* o = &b;
  if (owner != origin) o = bricks_[brick_of_.at(pack(owner[0], owner[1], owner[2]))].get();
  const int x = int(corner[0] - owner[0] * kB), y = int(corner[1] - owner[1] * kB), z = int(corner[2] - owner[2] * kB);
  local_edge = static_cast<std::uint16_t>(3 * (x + kC * y + kC * kC * z) + e / 4);
  return o;
}

void Extraction::collect_crossed_edges() {
  const CellTables& t = tables();
  tbb::parallel_for(std::size_t(0), bricks_.size(), [&](std::size_t i) {
    Brick& b = *bricks_[i];
    for (int cell = 0; cell < kB * kB * kB; ++cell) {
      if (!(b.state[cell] & kActive)) continue;
      const int mask = brick_mask(b, cell);
      for (int e = 0; e < 12; ++e) {
        const int lo = t.edge_corners[e][0], hi = t.edge_corners[e][1];
        if (((mask >> lo) & 1) == ((mask >> hi) & 1)) continue;
        std::uint16_t local_edge;
        if (owner_and_edge(b, cell, e, local_edge) == &b) b.edges.push_back(local_edge);
      }
    }
    std::sort(b.edges.begin(), b.edges.end());
    b.edges.erase(std::unique(b.edges.begin(), b.edges.end()), b.edges.end());
    b.edges.shrink_to_fit();
  });
  std::size_t edge_count = 0;
  for (auto& b : bricks_) b->first_vertex = static_cast<std::uint32_t>(edge_count), edge_count += b->edges.size();
  if (edge_count >= kCentre) throw ComputeError("extract_iso_surface: more than 2^31 vertices");
}

Eigen::Vector3d Extraction::unit_normal(const Eigen::Vector3d& p, const Eigen::Vector3d& fallback) const {
  const Eigen::Vector3d g = f_.gradient(p);
  const Eigen::Vector3d n = params_.inside_positive ? Eigen::Vector3d(-g) : g;
  const double len = n.norm();
  return len > 0.0 && std::isfinite(len) ? Eigen::Vector3d(n / len) : fallback;
}

// The vertex of brick b's owned edge j: the crossing, refined; and its normal.
void Extraction::place_vertex(const Brick& b, std::size_t j) {
  const auto origin = unpack(b.key);
  const int c0 = b.edges[j] / 3, axis = b.edges[j] % 3, c1 = c0 + (axis == 0 ? 1 : axis == 1 ? kC : kC * kC);
  const Key k0 = pack(origin[0] * kB + c0 % kC, origin[1] * kB + (c0 / kC) % kC, origin[2] * kB + c0 / (kC * kC));
  Eigen::Vector3d a = position(k0), bb = a;
  bb[axis] += h_;
  double wa = b.w[c0], wb = b.w[c1];
  Eigen::Vector3d outward = Eigen::Vector3d::Zero();
  outward[axis] = wa > 0.0 ? 1.0 : -1.0;
  Eigen::Vector3d p = a + (wa / (wa - wb)) * (bb - a);
  if (params_.root_refinement_steps > 0) {
    // Step 1: the quadratic through both ends and the edge's midpoint. Exact for a degree-2
    // B-spline function whose knots are lattice corners (Poisson: along an edge it is one
    // quadratic piece), and it evaluates at fixed places, so the vertex depends smoothly on
    // the function (no branch on a sign near the root, unlike bracketing steps).
    const double wm = sign(f_.value(0.5 * (a + bb)));
    if (std::isfinite(wm)) p = a + quadratic_root(wa, wm, wb) * (bb - a);
  }
  int kept = 0;  // further steps: Illinois false position, halving the value of an end kept twice
  for (int step = 1; step < params_.root_refinement_steps; ++step) {
    const double wp = sign(f_.value(p));
    if (!std::isfinite(wp) || wp == 0.0) break;
    if ((wp > 0.0) == (wa > 0.0)) {
      a = p, wa = wp;
      if (kept == 2) wb *= 0.5;
      kept = 2;
    } else {
      bb = p, wb = wp;
      if (kept == 1) wa *= 0.5;
      kept = 1;
    }
    p = a + (wa / (wa - wb)) * (bb - a);
  }
  out_.vertices[b.first_vertex + j] = p;
  out_.normals[b.first_vertex + j] = unit_normal(p, outward);
}

void Extraction::place_vertices(const std::function<void()>& brick_done) {
  const std::size_t edge_count = bricks_.empty() ? 0 : bricks_.back()->first_vertex + bricks_.back()->edges.size();
  out_.vertices.resize(edge_count);
  out_.normals.resize(edge_count);
  tbb::parallel_for(std::size_t(0), bricks_.size(), [&](std::size_t i) {
    const Brick& b = *bricks_[i];
    for (std::size_t j = 0; j < b.edges.size(); ++j) place_vertex(b, j);
    if (brick_done) brick_done();
  });
}

// 5. Triangles cell by cell, each brick into its own buffer.
// The loop L[0..n) (vertices v) by the triangulation of minimum total diagonal length that uses
// only diagonals joining crossings on no common cell face; false when there is none.
bool Extraction::triangulate_loop(const int* L, int n, const std::array<std::uint32_t, 12>& v, ChunkOutput& o) const {
  const CellTables& t = tables();
  constexpr double kInf = std::numeric_limits<double>::infinity();
  double cost[12][12] = {};
  int split[12][12] = {};
  auto chord = [&](int a, int b) {
    if (b == a + 1 || (a == 0 && b == n - 1)) return 0.0;
    if (t.share_face[L[a]][L[b]]) return kInf;
    return (out_.vertices[v[a]] - out_.vertices[v[b]]).squaredNorm();
  };
  for (int len = 1; len < n; ++len)
    for (int a = 0; a + len < n; ++a) {
      const int b = a + len;
      cost[a][b] = len == 1 ? 0.0 : kInf;
      split[a][b] = -1;
      if (len == 1) continue;
      const double own = chord(a, b);
      if (own == kInf) continue;
      for (int k = a + 1; k < b; ++k) {
        const double c = cost[a][k] + cost[k][b] + own;
        if (c < cost[a][b]) cost[a][b] = c, split[a][b] = k;
      }
    }
  if (!(cost[0][n - 1] < kInf)) return false;
  int stack[24][2], top = 0;
  stack[top][0] = 0, stack[top][1] = n - 1, ++top;
  while (top > 0) {
    --top;
    const int a = stack[top][0], b = stack[top][1];
    if (b - a < 2) continue;
    const int k = split[a][b];
    o.triangles.push_back({v[a], v[k], v[b]});
    stack[top][0] = a, stack[top][1] = k, ++top;
    stack[top][0] = k, stack[top][1] = b, ++top;
  }
  return true;
}

// The loop v[0..n) fanned around a centre vertex: the loop's mean moved one Newton step
// (at most half a cell) towards the surface.
void Extraction::fan_loop(int n, const std::array<std::uint32_t, 12>& v, ChunkOutput& o) const {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero(), normal_sum = Eigen::Vector3d::Zero();
  for (int j = 0; j < n; ++j) centre += out_.vertices[v[j]], normal_sum += out_.normals[v[j]];
  centre /= n;
  const Eigen::Vector3d g = f_.gradient(centre);
  const double wc = f_.value(centre) - params_.iso_value;
  if (g.squaredNorm() > 0.0 && std::isfinite(wc)) {
    Eigen::Vector3d step = wc * g / g.squaredNorm();
    if (step.norm() > 0.5 * h_) step *= 0.5 * h_ / step.norm();
    if (step.allFinite()) centre -= step;
  }
  const double sum_len = normal_sum.norm();
  const std::uint32_t id = kCentre | static_cast<std::uint32_t>(o.centres.size());
  o.centres.push_back(centre);
  o.centre_normals.push_back(unit_normal(centre, sum_len > 0.0 ? Eigen::Vector3d(normal_sum / sum_len) : Eigen::Vector3d::UnitZ()));
  for (int j = 0; j < n; ++j) o.triangles.push_back({v[j], v[(j + 1) % n], id});
}

void Extraction::triangulate_brick(const Brick& b, ChunkOutput& o) const {
  for (int cell = 0; cell < kB * kB * kB; ++cell) {
    if (!(b.state[cell] & kActive)) continue;
    std::array<double, 8> w;
    for (int k = 0; k < 8; ++k) w[k] = b.w[corner_local(cell, k)];
    std::array<int, 12> loop_edges;
    std::array<int, 5> loop_start;
    const int loops = cell_loops(w, loop_edges, loop_start);
    for (int l = 0; l < loops; ++l) {
      const int n = loop_start[l + 1] - loop_start[l];
      const int* L = loop_edges.data() + loop_start[l];
      std::array<std::uint32_t, 12> v;
      for (int j = 0; j < n; ++j) {
        std::uint16_t local_edge;
        const Brick* owner = owner_and_edge(b, cell, L[j], local_edge);
        v[j] = owner->first_vertex +
               static_cast<std::uint32_t>(std::lower_bound(owner->edges.begin(), owner->edges.end(), local_edge) - owner->edges.begin());
      }
      if (!triangulate_loop(L, n, v, o)) fan_loop(n, v, o);
    }
  }
}

void Extraction::triangulate_cells(const std::function<void()>& brick_done) {
  chunks_.resize(bricks_.size());
  tbb::parallel_for(std::size_t(0), bricks_.size(), [&](std::size_t bi) {
    triangulate_brick(*bricks_[bi], chunks_[bi]);
    if (brick_done) brick_done();
  });
}

IsoSurface Extraction::result() && {
  append_chunks(chunks_, out_);
  return std::move(out_);
}

}  // namespace iso

IsoSurface extract_iso_surface(const IsoFunction& f, const IsoLattice& lattice, const IsoSurfaceParams& params,
                               const ProgressCallback& progress) {
  auto report = [&](double fraction) {
    if (progress && !progress(fraction)) throw CancelledError();
  };
  iso::Extraction x(f, lattice, params);
  report_phase(progress, "extraction: leaves");
  x.find_leaves();
  report(0.02);
  const double seeded = params.seed_share > 0.0 ? std::clamp(params.seed_share, 0.05, 0.9) : 0.5;
  x.seed_coarse_crossings(progress, 0.02, seeded);
  report(seeded);
  // Following the surface takes rounds of unknown number: round r ends at share
  // s + 0.7 (1 - s) (1 - 1 / (1 + r / 8)), s the share of the seeds, and within a round the
  // bricks done move it on; the vertices and triangles take the rest.
  report_phase(progress, "extraction: surface cells");
  x.queue_seeds();
  const double cells_end = seeded + 0.7 * (1.0 - seeded), vertices_end = seeded + 0.92 * (1.0 - seeded);
  const auto round_end = [&](double r) { return seeded + (cells_end - seeded) * (1.0 - 1.0 / (1.0 + r / 8.0)); };
  if (params.expected_cells > 0.0) {
    ProgressReporter reporter(progress, seeded, cells_end, std::size_t(std::max(1.0, params.expected_cells)));
    while (x.follow_round([&](std::size_t cells) { reporter.advance(cells); })) reporter.throw_if_cancelled();
  } else {
    for (std::size_t round = 0;; ++round) {
      std::size_t pending = 0;
      for (const auto& b : x.bricks()) pending += b->pending.empty() ? 0 : 1;
      ProgressReporter reporter(progress, round_end(double(round)), round_end(double(round + 1)), pending);
      if (!x.follow_round([&](std::size_t) { reporter.advance(1); })) break;
      reporter.throw_if_cancelled();
    }
  }
  x.index_bricks();
  report(cells_end);
  report_phase(progress, "extraction: vertices");
  x.collect_crossed_edges();
  {
    ProgressReporter reporter(progress, cells_end, vertices_end, x.bricks().size());
    x.place_vertices([&] { reporter.advance(1); });
    reporter.throw_if_cancelled();
  }
  report(vertices_end);
  report_phase(progress, "extraction: triangles");
  {
    ProgressReporter reporter(progress, vertices_end, 0.995, x.bricks().size());
    x.triangulate_cells([&] { reporter.advance(1); });
    reporter.throw_if_cancelled();
  }
  report(0.995);
  IsoSurface out = std::move(x).result();
  report(1.0);
  return out;
}

}  // namespace pointsurf::detail
