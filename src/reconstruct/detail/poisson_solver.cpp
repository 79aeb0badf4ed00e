// SPDX-License-Identifier: GPL-3.0-or-later
// The screened Poisson system on a sparse octree, degree-2 B-splines (see poisson_solver.h).
//
// Basis. At level l (n = 2^l cells per axis) the 1-D function i is the quadratic B-spline
// centred on cell i (support: cells i-1..i+1). The two functions that stick out of [0, 1]
// are folded back onto the first and last: B~0 = B0 + s B-1, B~n-1 = B~n-1 + s Bn, with s = +1
// (Neumann: zero slope at the wall) or -1 (Dirichlet: zero value), as PoissonRecon does. The
// folded functions still refine exactly: a coarse function is 1/4, 3/4, 3/4, 1/4 of four fine
// ones, folded the same way, so the sum of all levels is a function of the finest level.
//
// System. Minimising  int |V - grad f|^2 + alpha 2^depth sum_p A_p f(p)^2  over the sum of
// the levels' functions gives, per level, (L + S) x = b - (what the coarser levels already
// contribute), L the Laplacian (a 5^3 stencil of products of 1-D mass and stiffness
// integrals), S the screening through the samples (matrix-free: 27 functions per sample),
// b_i = int V . grad B_i with V the normals splatted into the finest level (weight A_p, the
// sample's share of the surface from the density estimate). b is computed at the finest level
// and restricted to the coarser ones exactly (the transpose of the refinement). The coarser
// levels' contribution to a level's equations: their function, as coefficients of the level
// above (kept cumulatively, F), against the fine functions through cross-level 1-D integrals,
// and their value at each sample (kept per sample, G). Cascadic: one pass coarse to fine, each
// level solved by Jacobi-preconditioned conjugate gradients.
//
// Which nodes exist (poisson_solver.h): level l has the children of the cells of level l-1
// within 2 cells of a sample's cell (all cells for l <= full_depth; within 1 cell for the
// finest level). Then every level holds the 5^3 neighbours of the nodes whose supports hold
// samples, the coarser level holds the 4^3 coarse functions that overlap each fine node, and F
// is exact on every node: checked by the chain  children(S(l-1) + 2) contains S(l) + 4
// (S(l): sample cells at level l). The finest level's b reaches S(depth) + 3, beyond its
// nodes, so the level above takes its b from V directly rather than by restriction.
#include "reconstruct/detail/poisson_solver.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cassert>
#include <cmath>
#include <limits>
#include <numeric>
#include <type_traits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include "pointsurf/core/error.h"
#include "spatial/detail/morton.h"

namespace pointsurf::detail {
namespace {

using Key = std::uint64_t;
constexpr Key kNoKey = ~Key{0};
// The progress of PoissonFunction's construction, by phase: shares of its time measured on 1M
// samples (bench/notes/progress.md); a level's solve is split into set-up, iterations and the
// carried normals.
// the sorted samples and the octree 16 % (of which the sort 4 %), the splatting 34 %
constexpr double kSortShare = 0.04, kOctreeShare = 0.16, kSplatShare = 0.34, kSampleValueShare = 0.02;
constexpr double kScreeningCostInNodes = 2.0;  // a level's work per screening point (a cell with samples), in nodes
constexpr double kLevelSetupShare = 0.4, kLevelSolveShare = 0.5;

Key morton(int x, int y, int z) { return detail::morton_code(std::uint64_t(x), std::uint64_t(y), std::uint64_t(z)); }
// The hash key of a cell: cheaper than its Morton code, which orders the arrays.
Key pack(int x, int y, int z) { return Key(std::uint32_t(x)) | Key(std::uint32_t(y)) << 21 | Key(std::uint32_t(z)) << 42; }

// Open addressing, keys known up front (built once, then read concurrently).
class KeyIndex {
 public:
  void build(const std::vector<Key>& keys) {
    std::size_t cap = 16;
    while (cap < 2 * keys.size()) cap <<= 1;
    keys_.assign(cap, kNoKey);
    values_.assign(cap, -1);
    mask_ = cap - 1;
    for (std::size_t i = 0; i < keys.size(); ++i) {
      std::size_t h = slot(keys[i]);
      while (keys_[h] != kNoKey) h = (h + 1) & mask_;
      keys_[h] = keys[i];
      values_[h] = std::int32_t(i);
    }
  }
  std::int32_t find(Key k) const {
    if (keys_.empty()) return -1;
    std::size_t h = slot(k);
    while (true) {
      if (keys_[h] == k) return values_[h];
      if (keys_[h] == kNoKey) return -1;
      h = (h + 1) & mask_;
    }
  }
  std::size_t bytes() const { return keys_.size() * (sizeof(Key) + sizeof(std::int32_t)); }

 private:
  std::size_t slot(Key k) const { return std::size_t((k * 0x9E3779B97F4A7C15ULL) >> 20) & mask_; }
  std::vector<Key> keys_;
  std::vector<std::int32_t> values_;
  std::size_t mask_ = 0;
};

// The quadratic B-spline centred on 0, support (-1.5, 1.5), and its derivative.
double beta(double u) {
  const double a = std::abs(u);
  if (a < 0.5) return 0.75 - u * u;
  if (a < 1.5) return 0.5 * (a - 1.5) * (a - 1.5);
  return 0.0;
}
double dbeta(double u) {
  const double a = std::abs(u);
  if (a < 0.5) return -2.0 * u;
  if (a < 1.5) return (u > 0 ? 1.0 : -1.0) * (a - 1.5);
  return 0.0;
}

// Folded function i of level with n cells, value (or derivative in unit-cube units) at x.
double folded(int n, int i, double x, double s, bool derivative) {
  const double t = x * n;
  auto f = [&](int j) { return derivative ? dbeta(t - j - 0.5) * n : beta(t - j - 0.5); };
  double v = f(i);
  if (i == 0) v += s * f(-1);
  if (i == n - 1) v += s * f(n);
  return v;
}

// int_0^1 of a product of two folded functions (levels n1 >= n2 cells), exact: 3-point Gauss
// on each cell of the finer level within both supports.
double integrate(int n1, int i1, bool d1, int n2, int i2, bool d2, double s) {
  static const double gx[3] = {-std::sqrt(0.6), 0.0, std::sqrt(0.6)}, gw[3] = {5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0};
  const int lo = std::max(0, i1 - 2), hi = std::min(n1, i1 + 3);
  double sum = 0.0;
  for (int c = lo; c < hi; ++c)
    for (int g = 0; g < 3; ++g) {
      const double x = (c + 0.5 + 0.5 * gx[g]) / n1;
      sum += gw[g] * 0.5 / n1 * folded(n1, i1, x, s, d1) * folded(n2, i2, x, s, d2);
    }
  return sum;
}

// One sample's three 1-D weights at a level: nodes c-1, c, c+1, folded (index, signed weight).
struct Weights1D {
  std::array<int, 3> idx;
  std::array<double, 3> w, dw;
};
Weights1D weights_1d(double q, int n, double s) {
  Weights1D r;
  const int c = std::clamp(int(std::floor(q * n)), 0, n - 1);
  const double u = q * n - c - 0.5;
  for (int t = 0; t < 3; ++t) {
    int j = c + t - 1;
    double sign = 1.0;
    if (j < 0) j = 0, sign = s;
    if (j >= n) j = n - 1, sign = s;
    r.idx[std::size_t(t)] = j;
    r.w[std::size_t(t)] = sign * beta(u - (t - 1));
    r.dw[std::size_t(t)] = sign * dbeta(u - (t - 1)) * n;
  }
  return r;
}

struct Level {
  int l = 0, n = 1;
  std::vector<std::array<int, 3>> block_cells;  // the parent cells (level l-1), Morton order
  KeyIndex block_index;
  std::vector<std::array<std::int32_t, 27>> nb;  // neighbour blocks (dx+1) + 3(dy+1) + 9(dz+1)
  std::vector<double> x, F, b;                   // per node (8 per block): solution, cumulative, rhs
  std::vector<std::uint32_t> first, last;        // per node: its cell's samples
  // 1-D tables: [i][o + 2] for the function i + o, o in -2..2: mass, stiffness, int B_{i+o} B_i'.
  std::vector<std::array<double, 5>> M, K, D;
  // Cross-level: [i][t] against the coarse function k = (i >> 1) - 2 + (i & 1) + t, t in 0..3.
  std::vector<std::array<double, 4>> Mc, Kc, Gc, Hc;  // Gc: int B_i (B^c_k)', Hc: int B_i' B^c_k
  // Refinement: fine function i gets w0 of coarse k0 and w1 of coarse k1 (k1 < 0: none).
  std::vector<std::array<int, 2>> pk;
  std::vector<std::array<double, 2>> pw;

  std::size_t nodes() const { return 8 * block_cells.size(); }
  std::int32_t block(int bx, int by, int bz) const {
    const int nb_ = n / 2;
    if (bx < 0 || by < 0 || bz < 0 || bx >= nb_ || by >= nb_ || bz >= nb_) return -1;
    return block_index.find(pack(bx, by, bz));
  }
  std::int32_t node(int x, int y, int z) const {
    if (x < 0 || y < 0 || z < 0 || x >= n || y >= n || z >= n) return -1;
    const std::int32_t b = block_index.find(pack(x >> 1, y >> 1, z >> 1));
    return b < 0 ? -1 : 8 * b + ((x & 1) | (y & 1) << 1 | (z & 1) << 2);
  }
  // The node at (x, y, z) seen from block `b` (cell bc): its block must be within 1 of b.
  std::int32_t near(std::int32_t b, const std::array<int, 3>& bc, int x, int y, int z) const {
    if (x < 0 || y < 0 || z < 0 || x >= n || y >= n || z >= n) return -1;
    const int dx = (x >> 1) - bc[0], dy = (y >> 1) - bc[1], dz = (z >> 1) - bc[2];
    assert(std::abs(dx) <= 1 && std::abs(dy) <= 1 && std::abs(dz) <= 1);
    const std::int32_t nbk = nb[std::size_t(b)][std::size_t((dx + 1) + 3 * (dy + 1) + 9 * (dz + 1))];
    return nbk < 0 ? -1 : 8 * nbk + ((x & 1) | (y & 1) << 1 | (z & 1) << 2);
  }
  std::array<int, 3> node_cell(std::size_t i) const {
    const auto& bc = block_cells[i >> 3];
    return {2 * bc[0] + int(i & 1), 2 * bc[1] + int(i >> 1 & 1), 2 * bc[2] + int(i >> 2 & 1)};
  }
  std::size_t bytes() const {
    return block_cells.size() * (sizeof(block_cells[0]) + sizeof(nb[0])) + block_index.bytes() +
           nodes() * (3 * sizeof(double) + 2 * sizeof(std::uint32_t)) + (M.size() * 3 * 5 + Mc.size() * 2 * 4) * sizeof(double);
  }
};

double dot(const std::vector<double>& a, const std::vector<double>& b) {
  return tbb::parallel_deterministic_reduce(
      tbb::blocked_range<std::size_t>(0, a.size(), 4096), 0.0,
      [&](const tbb::blocked_range<std::size_t>& r, double acc) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) acc += a[i] * b[i];
        return acc;
      },
      std::plus<double>());
}

// The values of `v` on the 6^3 cells around the children of block b (zero where no node):
// everything the 5^3 stencils of the block's 8 nodes read.
void load_window(const Level& L, std::size_t b, const std::vector<double>& v, double* win) {
  std::fill(win, win + 216, 0.0);
  const auto& nbs = L.nb[b];
  for (int d = 0; d < 27; ++d) {
    const std::int32_t n = nbs[std::size_t(d)];
    if (n < 0) continue;
    const int dx = d % 3, dy = d / 3 % 3, dz = d / 9;
    const double* src = &v[8 * std::size_t(n)];
    for (int k = 0; k < 8; ++k) win[(2 * dx + (k & 1)) + 6 * (2 * dy + (k >> 1 & 1)) + 36 * (2 * dz + (k >> 2))] = src[k];
  }
}

// out[k] = sum over the 5^3 neighbours j of child k of the block:
//   Kx My Mz + Mx Ky Mz + Mx My Kz (the Laplacian), or with `single`, Tx Ty Tz (one product),
// computed separably on the window: about 150 multiplications per node instead of 1000.
using Table = std::vector<std::array<double, 5>>;
void stencil_block(const std::array<int, 3>& bc, const Table& Mx_, const Table& Kx_, const Table& My_, const Table& Ky_, const Table& Mz_,
                   const Table& Kz_, const double* win, double* out, bool single) {
  double MX[2][6][6], KX[2][6][6];
  for (int ax = 0; ax < 2; ++ax) {
    const auto& m = Mx_[std::size_t(2 * bc[0] + ax)];
    const auto& k = Kx_[std::size_t(2 * bc[0] + ax)];
    for (int wz = 0; wz < 6; ++wz)
      for (int wy = 0; wy < 6; ++wy) {
        const double* row = win + 6 * wy + 36 * wz + ax;
        double sm = 0.0, sk = 0.0;
        for (int o = 0; o < 5; ++o) sm += m[std::size_t(o)] * row[o], sk += k[std::size_t(o)] * row[o];
        MX[ax][wy][wz] = sm;
        KX[ax][wy][wz] = sk;
      }
  }
  double MM[2][2][6], KM[2][2][6], MK[2][2][6];
  for (int ax = 0; ax < 2; ++ax)
    for (int ay = 0; ay < 2; ++ay) {
      const auto& m = My_[std::size_t(2 * bc[1] + ay)];
      const auto& k = Ky_[std::size_t(2 * bc[1] + ay)];
      for (int wz = 0; wz < 6; ++wz) {
        double mm = 0.0, km = 0.0, mk = 0.0;
        for (int o = 0; o < 5; ++o) {
          mm += m[std::size_t(o)] * MX[ax][ay + o][wz];
          km += m[std::size_t(o)] * KX[ax][ay + o][wz];
          mk += k[std::size_t(o)] * MX[ax][ay + o][wz];
        }
        MM[ax][ay][wz] = mm, KM[ax][ay][wz] = km, MK[ax][ay][wz] = mk;
      }
    }
  for (int az = 0; az < 2; ++az) {
    const auto& m = Mz_[std::size_t(2 * bc[2] + az)];
    const auto& k = Kz_[std::size_t(2 * bc[2] + az)];
    for (int ay = 0; ay < 2; ++ay)
      for (int ax = 0; ax < 2; ++ax) {
        double sum = 0.0;
        if (single)
          for (int o = 0; o < 5; ++o) sum += m[std::size_t(o)] * MM[ax][ay][az + o];
        else
          for (int o = 0; o < 5; ++o) sum += m[std::size_t(o)] * (KM[ax][ay][az + o] + MK[ax][ay][az + o]) + k[std::size_t(o)] * MM[ax][ay][az + o];
        out[ax | ay << 1 | az << 2] = sum;
      }
  }
}

}  // namespace

struct PoissonFunction::Impl {
  PoissonSystemParams params;
  double s = 1.0;  // fold sign
  std::vector<Level> levels;  // levels[l], l = 1..depth (levels[0] unused)
  std::vector<Eigen::Vector3d> q;  // samples, sorted
  std::vector<Eigen::Vector3d> normals_;
  double alpha = 0.0;  // point_weight 2^depth
  std::vector<double> area;        // A_p
  std::vector<double> density;     // kernel-level unit-weight splat, per node of kernel level
  std::vector<std::uint32_t> order;  // sorted position -> given index

  std::vector<Key> keys;                // Morton codes of the samples' finest cells, sorted
  std::vector<std::uint8_t> level_of;   // the level each sample's normal is splatted at
  void build_level(int l);
  std::vector<Eigen::Vector3d> splat(int l) const;
  void build_tables(Level& L) const;
  void estimate_density();
  // The level at which a node holds samples_per_node samples, from the splatted unit weights
  // w at the kernel level: a surface through a node holds about w / 0.55 samples there (the
  // mean over offsets of the sum of squared B-spline weights across it is int beta^2 = 11/20),
  // and 4 times fewer per level finer.
  double depth_of(double w) const { return params.kernel_depth + 0.5 * std::log2(w / (0.55 * params.samples_per_node)); }
  void splat_and_restrict();
  std::vector<Eigen::Vector3d> VF;  // the normals splatted at the levels solved so far, as coefficients of the last
  struct LevelSolve;  // solve_level's phases
  PoissonLevelReport solve_level(int l);
  std::function<void(double)> level_progress;  // the finished fraction of the level being solved (may throw CancelledError)
  void level_done(double f) const {
    if (level_progress) level_progress(f);
  }
  // body(k) for k in [0, n) in parallel, in consecutive parts of at least 32768, with
  // level_done from `begin` to `end` after each: a long loop keeps the progress alive.
  template <class Body>
  void parallel_steps(std::size_t n, double begin, double end, const Body& body) const {
    const std::size_t steps = std::clamp<std::size_t>(n / 32768, 1, 32);
    for (std::size_t step = 0; step < steps; ++step) {
      tbb::parallel_for(n * step / steps, n * (step + 1) / steps, body);
      level_done(begin + (end - begin) * double(step + 1) / double(steps));
    }
  }
  // Sum over t of the level's coefficients `c` around p times the weights (derivative per
  // axis `d`: 0 none, 1..3); `complete` set false where a node is missing (counted as 0).
  double gather(const Level& L, const std::vector<double>& c, const Eigen::Vector3d& p, int d, bool& complete) const;
  double evaluate(const Eigen::Vector3d& p, int d) const { return evaluate_all(p, d, d)[d]; }
  // the value (0) and the gradient (1..3) from `first` to `last`
  Eigen::Vector4d evaluate_all(const Eigen::Vector3d& p, int first, int last) const;
};

void PoissonFunction::Impl::build_tables(Level& L) const {
  const int n = L.n;
  L.M.assign(std::size_t(n), {});
  L.K.assign(std::size_t(n), {});
  L.D.assign(std::size_t(n), {});
  for (int i = 0; i < n; ++i)
    for (int o = -2; o <= 2; ++o) {
      const int j = i + o;
      if (j < 0 || j >= n) continue;
      L.M[std::size_t(i)][std::size_t(o + 2)] = integrate(n, i, false, n, j, false, s);
      L.K[std::size_t(i)][std::size_t(o + 2)] = integrate(n, i, true, n, j, true, s);
      L.D[std::size_t(i)][std::size_t(o + 2)] = integrate(n, i, true, n, j, false, s);
    }
  L.pk.assign(std::size_t(n), {-1, -1});
  L.pw.assign(std::size_t(n), {0.0, 0.0});
  if (L.l == 1) return;
  const int nc = n / 2;
  L.Mc.assign(std::size_t(n), {});
  L.Kc.assign(std::size_t(n), {});
  L.Gc.assign(std::size_t(n), {});
  L.Hc.assign(std::size_t(n), {});
  for (int i = 0; i < n; ++i) {
    for (int t = 0; t < 4; ++t) {
      const int k = (i >> 1) - 2 + (i & 1) + t;
      if (k < 0 || k >= nc) continue;
      L.Mc[std::size_t(i)][std::size_t(t)] = integrate(n, i, false, nc, k, false, s);
      L.Kc[std::size_t(i)][std::size_t(t)] = integrate(n, i, true, nc, k, true, s);
      L.Gc[std::size_t(i)][std::size_t(t)] = integrate(n, i, false, nc, k, true, s);
      L.Hc[std::size_t(i)][std::size_t(t)] = integrate(n, i, true, nc, k, false, s);
    }
    const int m = i >> 1;
    int k0 = m, k1 = (i & 1) ? m + 1 : m - 1;
    double w0 = 0.75, w1 = 0.25;
    if (k1 < 0 || k1 >= nc) w0 += s * 0.25, k1 = -1, w1 = 0.0;
    L.pk[std::size_t(i)] = {k0, k1};
    L.pw[std::size_t(i)] = {w0, w1};
  }
}

namespace {

// The 27 nodes around p at level L (weights w): false when some is missing (-1 there).
bool nodes_around(const Level& L, const std::array<Weights1D, 3>& w, std::array<std::int32_t, 27>& out) {
  int base[3];
  for (int a = 0; a < 3; ++a) base[a] = w[std::size_t(a)].idx[0] >> 1;
  std::int32_t blocks[2][2][2];
  bool looked[2][2][2] = {};
  bool complete = true;
  for (int t = 0; t < 27; ++t) {
    const int ix = w[0].idx[std::size_t(t % 3)], iy = w[1].idx[std::size_t(t / 3 % 3)], iz = w[2].idx[std::size_t(t / 9)];
    const int dx = (ix >> 1) - base[0], dy = (iy >> 1) - base[1], dz = (iz >> 1) - base[2];
    if (!looked[dz][dy][dx]) {
      blocks[dz][dy][dx] = L.block(ix >> 1, iy >> 1, iz >> 1);
      looked[dz][dy][dx] = true;
    }
    const std::int32_t b = blocks[dz][dy][dx];
    out[std::size_t(t)] = b < 0 ? -1 : 8 * b + ((ix & 1) | (iy & 1) << 1 | (iz & 1) << 2);
    complete = complete && b >= 0;
  }
  return complete;
}

double weighted_sum(const std::array<Weights1D, 3>& w, const std::array<std::int32_t, 27>& nodes, const std::vector<double>& c, int d) {
  const auto& ax = d == 1 ? w[0].dw : w[0].w;
  const auto& ay = d == 2 ? w[1].dw : w[1].w;
  const auto& az = d == 3 ? w[2].dw : w[2].w;
  double sum = 0.0;
  for (int t = 0; t < 27; ++t)
    if (nodes[std::size_t(t)] >= 0)
      sum += c[std::size_t(nodes[std::size_t(t)])] * ax[std::size_t(t % 3)] * ay[std::size_t(t / 3 % 3)] * az[std::size_t(t / 9)];
  return sum;
}

std::array<int, 3> decode(Key k, int level) {
  int c[3] = {0, 0, 0};
  for (int bit = 0; bit < level; ++bit)
    for (int a = 0; a < 3; ++a) c[a] |= int((k >> (3 * bit + a)) & 1) << bit;
  return {c[0], c[1], c[2]};
}

}  // namespace

void PoissonFunction::Impl::build_level(int l) {
  const int depth = params.depth;
  Level& L = levels[std::size_t(l)];
  L.l = l;
  L.n = 1 << l;
  const int np = L.n / 2;  // cells of the parent level
  std::vector<Key> blocks;
  if (l - 1 < params.full_depth) {
    blocks.reserve(std::size_t(np) * np * np);
    for (int z = 0; z < np; ++z)
      for (int y = 0; y < np; ++y)
        for (int x = 0; x < np; ++x) blocks.push_back(morton(x, y, z));
  } else {
    // the level l-1 cells of the samples that reach level l, dilated by 2 (the finest level:
    // by 1, see splat_and_restrict), separably (x, then y, then z)
    const int radius = l == depth ? 1 : 2;
    std::vector<std::array<int, 3>> set;
    const int shift = 3 * (depth - l + 1);
    Key last = kNoKey;
    for (std::size_t p = 0; p < keys.size(); ++p)
      if (level_of[p] >= l && (keys[p] >> shift) != last) {
        last = keys[p] >> shift;
        set.push_back(decode(last, l - 1));
      }
    for (int a = 0; a < 3; ++a) {
      std::vector<std::array<int, 3>> grown;
      grown.reserve(set.size() * 3);
      for (const auto& c : set)
        for (int o = -radius; o <= radius; ++o) {
          auto d = c;
          d[std::size_t(a)] += o;
          if (d[std::size_t(a)] >= 0 && d[std::size_t(a)] < np) grown.push_back(d);
        }
      tbb::parallel_sort(grown.begin(), grown.end());
      grown.erase(std::unique(grown.begin(), grown.end()), grown.end());
      set.swap(grown);
    }
    blocks.reserve(set.size());
    for (const auto& c : set) blocks.push_back(morton(c[0], c[1], c[2]));
  }
  level_done(0.4);
  tbb::parallel_sort(blocks.begin(), blocks.end());
  L.block_cells.resize(blocks.size());
  for (std::size_t b = 0; b < blocks.size(); ++b) L.block_cells[b] = decode(blocks[b], l - 1);
  for (std::size_t b = 0; b < blocks.size(); ++b) blocks[b] = pack(L.block_cells[b][0], L.block_cells[b][1], L.block_cells[b][2]);
  L.block_index.build(blocks);
  L.nb.resize(blocks.size());
  tbb::parallel_for(std::size_t(0), blocks.size(), [&](std::size_t b) {
    const auto& c = L.block_cells[b];
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx)
          L.nb[b][std::size_t((dx + 1) + 3 * (dy + 1) + 9 * (dz + 1))] = L.block(c[0] + dx, c[1] + dy, c[2] + dz);
  });
  level_done(0.7);
  const std::size_t nodes = L.nodes();
  L.x.assign(nodes, 0.0);
  L.F.assign(nodes, 0.0);
  L.b.assign(nodes, 0.0);
  L.first.assign(nodes, 0);
  L.last.assign(nodes, 0);
  // the samples of each cell that one of them reaches: consecutive in Morton order
  const int shift = 3 * (depth - l);
  for (std::size_t p = 0; p < keys.size();) {
    const Key cell = keys[p] >> shift;
    std::size_t e = p + 1;
    bool reached = level_of[p] >= l;
    while (e < keys.size() && (keys[e] >> shift) == cell) reached = reached || level_of[e] >= l, ++e;
    if (reached) {
      const auto c = decode(cell, l);
      const std::int32_t i = L.node(c[0], c[1], c[2]);
      if (i < 0) throw ComputeError("reconstruct_poisson: internal error: a sample's cell is not in the octree");
      L.first[std::size_t(i)] = std::uint32_t(p);
      L.last[std::size_t(i)] = std::uint32_t(e);
    }
    p = e;
  }
  build_tables(L);
}

// The normals of the samples splatted at level l into its B-splines (area-weighted).
std::vector<Eigen::Vector3d> PoissonFunction::Impl::splat(int l) const {
  const Level& L = levels[std::size_t(l)];
  std::vector<Eigen::Vector3d> v(L.nodes(), Eigen::Vector3d::Zero());
  for (std::size_t p = 0; p < q.size(); ++p) {
    if (level_of[p] != l) continue;
    const std::array<Weights1D, 3> w = {weights_1d(q[p].x(), L.n, s), weights_1d(q[p].y(), L.n, s), weights_1d(q[p].z(), L.n, s)};
    std::array<std::int32_t, 27> nodes;
    nodes_around(L, w, nodes);
    const Eigen::Vector3d n = area[p] * normals_[p];
    for (int t = 0; t < 27; ++t)
      v[std::size_t(nodes[std::size_t(t)])] += w[0].w[std::size_t(t % 3)] * w[1].w[std::size_t(t / 3 % 3)] * w[2].w[std::size_t(t / 9)] * n;
  }
  return v;
}

double PoissonFunction::Impl::gather(const Level& L, const std::vector<double>& c, const Eigen::Vector3d& p, int d, bool& complete) const {
  const std::array<Weights1D, 3> w = {weights_1d(p.x(), L.n, s), weights_1d(p.y(), L.n, s), weights_1d(p.z(), L.n, s)};
  std::array<std::int32_t, 27> nodes;
  complete = nodes_around(L, w, nodes) && complete;
  return weighted_sum(w, nodes, c, d);
}

Eigen::Vector4d PoissonFunction::Impl::evaluate_all(const Eigen::Vector3d& p, int first, int last) const {
  // from the finest level down: where all 27 nodes exist, the cumulative coefficients F hold
  // every coarser level; above that, each level's own part (x) where its nodes exist
  Eigen::Vector4d sum = Eigen::Vector4d::Zero();  // value, d/dx, d/dy, d/dz
  std::array<std::int32_t, 27> nodes;
  for (int l = params.depth; l >= 1; --l) {
    const Level& L = levels[std::size_t(l)];
    if (L.block_cells.empty()) continue;  // no sample reaches it
    const std::array<Weights1D, 3> w = {weights_1d(p.x(), L.n, s), weights_1d(p.y(), L.n, s), weights_1d(p.z(), L.n, s)};
    const bool complete = nodes_around(L, w, nodes);
    for (int d = first; d <= last; ++d) sum[d] += weighted_sum(w, nodes, complete ? L.F : L.x, d);
    if (complete) break;
  }
  return sum;
}

void PoissonFunction::Impl::estimate_density() {
  // unit weights splatted at the kernel level, evaluated at each sample (PoissonRecon)
  const Level& L = levels[std::size_t(params.kernel_depth)];
  density.assign(L.nodes(), 0.0);
  for (const Eigen::Vector3d& p : q) {
    const Weights1D wx = weights_1d(p.x(), L.n, s), wy = weights_1d(p.y(), L.n, s), wz = weights_1d(p.z(), L.n, s);
    for (int tz = 0; tz < 3; ++tz)
      for (int ty = 0; ty < 3; ++ty)
        for (int tx = 0; tx < 3; ++tx) {
          const std::int32_t i = L.node(wx.idx[std::size_t(tx)], wy.idx[std::size_t(ty)], wz.idx[std::size_t(tz)]);
          // Dirichlet folds with a negative sign: a count is a count
          if (i >= 0) density[std::size_t(i)] += std::abs(wx.w[std::size_t(tx)] * wy.w[std::size_t(ty)] * wz.w[std::size_t(tz)]);
        }
  }
  const double hk = 1.0 / L.n;
  area.resize(q.size());
  level_of.resize(q.size());
  std::vector<double> at(q.size());
  tbb::parallel_for(std::size_t(0), q.size(), [&](std::size_t p) {
    bool complete = true;
    at[p] = std::max(gather(L, density, q[p], 0, complete), 1e-3);
    // PoissonRecon's adaptive depth: the normal goes to the level where a node holds about
    // samples_per_node samples (4 times fewer per level finer on a surface), so sparse parts
    // of the cloud are not refined beyond what their samples support
    level_of[p] = std::uint8_t(std::clamp(int(std::lround(depth_of(at[p]))), params.kernel_depth, params.depth));
  });
  // A sample's share of the surface: inverse to the density where it is denser than the
  // median, the median's share where sparser. Without the cap an isolated outlier would weigh
  // as much as all the samples of a node and raise a blob the size of a kernel cell.
  std::vector<double> sorted = at;
  std::nth_element(sorted.begin(), sorted.begin() + std::ptrdiff_t(sorted.size() / 2), sorted.end());
  const double median = sorted[sorted.size() / 2];
  tbb::parallel_for(std::size_t(0), q.size(), [&](std::size_t p) { area[p] = hk * hk / std::max(at[p], median); });
}

// b_i = int V . grad B_i = sum_j v_j . int B_j grad B_i: per axis a product of the 1-D tables
void add_divergence(Level& L, const std::vector<Eigen::Vector3d>& v) {
  std::vector<double> va(L.nodes());
  for (int a = 0; a < 3; ++a) {
    for (std::size_t i = 0; i < va.size(); ++i) va[i] = v[i][a];
    tbb::parallel_for(std::size_t(0), L.block_cells.size(), [&](std::size_t b) {
      double win[216], out[8];
      load_window(L, b, va, win);
      const auto& bc = L.block_cells[b];
      stencil_block(bc, a == 0 ? L.D : L.M, L.K, a == 1 ? L.D : L.M, L.K, a == 2 ? L.D : L.M, L.K, win, out, true);
      for (int k = 0; k < 8; ++k) L.b[8 * b + std::size_t(k)] += out[k];
    });
  }
}

// b at each level from the normals splatted at that level and finer ones (the coarser ones'
// part is added level by level in solve_level, from their cumulative coefficients).
void PoissonFunction::Impl::splat_and_restrict() {
  const int depth = params.depth;
  Level& L = levels[std::size_t(depth)];
  // the shares: the finest level's normals and divergence to 28 %, the level above's to 46 %,
  // the restriction to the coarser levels the rest by their nodes (hand 400k: 2.3 s and 2.6 s)
  const std::vector<Eigen::Vector3d> v = splat(depth);
  level_done(0.2);
  add_divergence(L, v);
  level_done(0.28);
  // The level above the finest directly from V: the finest level's b reaches 3 cells beyond
  // the samples, one more than its nodes, so restricting it would lose a part.
  if (depth >= 2) {
    Level& C = levels[std::size_t(depth - 1)];
    parallel_steps(C.nodes(), 0.28, 0.34, [&](std::size_t k) {
      const auto c = C.node_cell(k);
      std::int32_t fine_blocks[27];  // the finest level's blocks at cells c-1..c+1
      for (int d = 0; d < 27; ++d) fine_blocks[d] = L.block(c[0] + d % 3 - 1, c[1] + d / 3 % 3 - 1, c[2] + d / 9 - 1);
      double sum = 0.0;
      for (int jz = 2 * c[2] - 2; jz <= 2 * c[2] + 3; ++jz) {
        if (jz < 0 || jz >= L.n) continue;
        const std::size_t tz = std::size_t(c[2] - ((jz >> 1) - 2 + (jz & 1)));
        for (int jy = 2 * c[1] - 2; jy <= 2 * c[1] + 3; ++jy) {
          if (jy < 0 || jy >= L.n) continue;
          const std::size_t ty = std::size_t(c[1] - ((jy >> 1) - 2 + (jy & 1)));
          for (int jx = 2 * c[0] - 2; jx <= 2 * c[0] + 3; ++jx) {
            if (jx < 0 || jx >= L.n) continue;
            const std::int32_t fb = fine_blocks[((jx >> 1) - c[0] + 1) + 3 * ((jy >> 1) - c[1] + 1) + 9 * ((jz >> 1) - c[2] + 1)];
            if (fb < 0) continue;
            const Eigen::Vector3d& vj = v[8 * std::size_t(fb) + std::size_t((jx & 1) | (jy & 1) << 1 | (jz & 1) << 2)];
            if (vj.isZero()) continue;
            const std::size_t tx = std::size_t(c[0] - ((jx >> 1) - 2 + (jx & 1)));
            const double mx = L.Mc[std::size_t(jx)][tx], my = L.Mc[std::size_t(jy)][ty], mz = L.Mc[std::size_t(jz)][tz];
            sum += vj.x() * L.Gc[std::size_t(jx)][tx] * my * mz + vj.y() * mx * L.Gc[std::size_t(jy)][ty] * mz + vj.z() * mx * my * L.Gc[std::size_t(jz)][tz];
          }
        }
      }
      C.b[k] = sum;
    });
    add_divergence(C, splat(depth - 1));
  }
  level_done(0.46);
  double restricted = 0.0, to_restrict = 0.0;
  for (int l = depth - 1; l >= 2; --l) to_restrict += double(levels[std::size_t(l - 1)].nodes());
  // restriction: b(coarse k) = sum over fine j of P(j, k) b(fine j)
  for (int l = depth - 1; l >= 2; --l) {
    const Level& Fl = levels[std::size_t(l)];
    Level& C = levels[std::size_t(l - 1)];
    const auto share = [&](double nodes) { return 0.46 + 0.54 * nodes / std::max(to_restrict, 1.0); };
    parallel_steps(C.nodes(), share(restricted), share(restricted + 0.8 * double(C.nodes())), [&](std::size_t k) {
      const auto c = C.node_cell(k);
      double sum = 0.0;
      for (int jz = 2 * c[2] - 1; jz <= 2 * c[2] + 2; ++jz) {
        if (jz < 0 || jz >= Fl.n) continue;
        const double wz = Fl.pk[std::size_t(jz)][0] == c[2] ? Fl.pw[std::size_t(jz)][0] : Fl.pk[std::size_t(jz)][1] == c[2] ? Fl.pw[std::size_t(jz)][1] : 0.0;
        if (wz == 0.0) continue;
        for (int jy = 2 * c[1] - 1; jy <= 2 * c[1] + 2; ++jy) {
          if (jy < 0 || jy >= Fl.n) continue;
          const double wy = Fl.pk[std::size_t(jy)][0] == c[1] ? Fl.pw[std::size_t(jy)][0] : Fl.pk[std::size_t(jy)][1] == c[1] ? Fl.pw[std::size_t(jy)][1] : 0.0;
          if (wy == 0.0) continue;
          for (int jx = 2 * c[0] - 1; jx <= 2 * c[0] + 2; ++jx) {
            if (jx < 0 || jx >= Fl.n) continue;
            const double wx = Fl.pk[std::size_t(jx)][0] == c[0] ? Fl.pw[std::size_t(jx)][0] : Fl.pk[std::size_t(jx)][1] == c[0] ? Fl.pw[std::size_t(jx)][1] : 0.0;
            if (wx == 0.0) continue;
            const std::int32_t j = Fl.node(jx, jy, jz);
            if (j >= 0) sum += wx * wy * wz * Fl.b[std::size_t(j)];
          }
        }
      }
      C.b[k] = sum;
    });
    if (l - 1 >= params.kernel_depth) add_divergence(C, splat(l - 1));
    restricted += double(C.nodes());
    level_done(share(restricted));
  }
}

double merge_samples(const std::vector<Eigen::Vector3d>& q, const std::vector<double>& area,
                     const std::vector<std::uint8_t>& level_of, std::uint32_t first, std::uint32_t last, int level,
                     Eigen::Vector3d& mean) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double w = 0.0;
  for (std::uint32_t p = first; p < last; ++p)
    if (level_of[p] >= level) sum += area[p] * q[p], w += area[p];  // the samples that reach this level
  mean = sum / w;
  return w;
}

std::array<std::vector<std::uint32_t>, 27> colour_classes(const std::vector<std::array<int, 3>>& cells) {
  std::array<std::vector<std::uint32_t>, 27> colours;
  for (std::size_t k = 0; k < cells.size(); ++k) {
    const auto& c = cells[k];
    colours[std::size_t(c[0] % 3 + 3 * (c[1] % 3) + 9 * (c[2] % 3))].push_back(std::uint32_t(k));
  }
  return colours;
}

PcgResult jacobi_pcg(const std::function<void(const std::vector<double>&, std::vector<double>&)>& apply,
                     std::vector<double>& r, const std::vector<double>& diag, std::vector<double>& x, int max_iterations,
                     double tolerance, const std::function<void(int iteration)>& on_iteration) {
  const std::size_t nodes = r.size();
  PcgResult result;
  std::fill(x.begin(), x.end(), 0.0);
  std::vector<double> z(nodes), d(nodes), Ad(nodes);
  for (std::size_t i = 0; i < nodes; ++i) z[i] = r[i] / diag[i];
  d = z;
  double rz = dot(r, z);
  const double r0 = std::sqrt(dot(r, r));
  result.initial_residual = r0;
  double rn = r0;
  int it = 0;
  while (it < max_iterations && rn > tolerance * r0 && rn > 0.0) {
    apply(d, Ad);
    const double dAd = dot(d, Ad);
    if (!(dAd > 0.0)) break;
    const double a = rz / dAd;
    tbb::parallel_for(std::size_t(0), nodes, [&](std::size_t i) {
      x[i] += a * d[i];
      r[i] -= a * Ad[i];
      z[i] = r[i] / diag[i];
    });
    const double rz_new = dot(r, z);
    const double beta_ = rz_new / rz;
    rz = rz_new;
    tbb::parallel_for(std::size_t(0), nodes, [&](std::size_t i) { d[i] = z[i] + beta_ * d[i]; });
    rn = std::sqrt(dot(r, r));
    ++it;
    if (on_iteration) on_iteration(it);
  }
  result.iterations = it;
  result.final_residual = rn;
  return result;
}

// One level's solve, phase by phase (solve_level calls them in the order declared).
struct PoissonFunction::Impl::LevelSolve {
  LevelSolve(Impl& impl, int level);
  /// Reads each node's samples and the coarser levels' F; produces the screening points (the
  /// samples of a cell merged), their weights, 1-D weights and 27 nodes, and the coarser function there (G).
  void merge_screening_points();
  /// Reads the screening points' cells; produces their 27 colour classes.
  void colour_points();
  /// Reads b, the coarser levels' F and VF; produces r = b + (coarser normals) - (coarser
  /// Laplacian) and the Laplacian's diagonal.
  void coarse_right_hand_side();
  /// Reads G; subtracts the coarser levels' screening from r and adds the screening to the diagonal.
  void add_screening();
  /// Solves (L + S) x = r into L.x; produces the report's iterations and residuals.
  void solve();
  /// Reads x and the coarser level's F; produces this level's cumulative coefficients F.
  void accumulate_coefficients();
  /// Reads VF (the coarser levels' normals); replaces it by the normals splatted up to this
  /// level, as coefficients of this level (for the next level's right-hand side).
  void carry_normals();

  Impl& m;
  const int l;
  Level& L;
  const Level* C;  // the coarser level; null at level 1
  const std::size_t nodes, nblocks;
  PoissonLevelReport report;

 private:
  double sample_value(std::size_t p, const std::vector<double>& c) const;
  template <class Value>
  void scatter(const Value& sv, std::vector<double>& out, bool squared) const;
  void coarse_terms(const std::array<int, 3>& c, std::int32_t cb, double& cross, double& up) const;
  void apply(const std::vector<double>& v, std::vector<double>& out);

  std::vector<std::int32_t> cells;  // the nodes whose cells hold samples of this level
  std::vector<Eigen::Vector3d> pos;  // per screening point
  std::vector<double> weight, G;
  std::vector<std::array<Weights1D, 3>> sw;
  std::vector<std::array<std::int32_t, 27>> snode;
  std::array<std::vector<std::uint32_t>, 27> colours;
  std::vector<double> r, diag;  // right-hand side, then residual; Jacobi diagonal
  std::vector<double> sv;       // apply's values at the screening points
};

PoissonFunction::Impl::LevelSolve::LevelSolve(Impl& impl, int level)
    : m(impl), l(level), L(impl.levels[std::size_t(level)]), C(level > 1 ? &impl.levels[std::size_t(level - 1)] : nullptr),
      nodes(L.nodes()), nblocks(L.block_cells.size()) {
  report.level = l;
  report.nodes = nodes;
}

// The screening points of this level: the samples of each cell merged into their area-weighted
// mean (PoissonRecon's approximate point interpolation). At the finest level a cell holds one or
// two samples; at coarse levels this keeps the work per iteration at the number of cells.
void PoissonFunction::Impl::LevelSolve::merge_screening_points() {
  for (std::size_t i = 0; i < nodes; ++i)
    if (L.first[i] < L.last[i]) cells.push_back(std::int32_t(i));
  const std::size_t ns = cells.size();
  pos.resize(ns);
  weight.resize(ns);
  G.assign(ns, 0.0);
  sw.resize(ns);
  snode.resize(ns);
  tbb::parallel_for(std::size_t(0), ns, [&](std::size_t k) {
    const std::size_t cell = std::size_t(cells[k]);
    weight[k] = merge_samples(m.q, m.area, m.level_of, L.first[cell], L.last[cell], l, pos[k]);
    for (int a = 0; a < 3; ++a) sw[k][std::size_t(a)] = weights_1d(pos[k][a], L.n, m.s);
    const auto& ww = sw[k];
    for (int t = 0; t < 27; ++t) snode[k][std::size_t(t)] = L.node(ww[0].idx[std::size_t(t % 3)], ww[1].idx[std::size_t(t / 3 % 3)], ww[2].idx[std::size_t(t / 9)]);
    if (C) {  // the coarser levels' function there
      bool complete = true;
      G[k] = m.gather(*C, C->F, pos[k], 0, complete);
      assert(complete);
    }
  });
}

// The screening, sample by sample into its 27 nodes: the cells are coloured by their
// coordinates mod 3, and two cells of one colour share no node, so each colour scatters in
// parallel without races (and in the same order for any thread count).
void PoissonFunction::Impl::LevelSolve::colour_points() {
  std::vector<std::array<int, 3>> at(cells.size());
  for (std::size_t k = 0; k < cells.size(); ++k) at[k] = L.node_cell(std::size_t(cells[k]));
  colours = colour_classes(at);
}

double PoissonFunction::Impl::LevelSolve::sample_value(std::size_t p, const std::vector<double>& c) const {
  const auto& w = sw[p];
  double v = 0.0;
  for (int t = 0; t < 27; ++t)
    v += c[std::size_t(snode[p][std::size_t(t)])] * w[0].w[std::size_t(t % 3)] * w[1].w[std::size_t(t / 3 % 3)] * w[2].w[std::size_t(t / 9)];
  return v;
}

// out_i += alpha sum_p A_p B_i(p) sv(p) (squared: B_i(p)^2 per function, the diagonal)
template <class Value>
void PoissonFunction::Impl::LevelSolve::scatter(const Value& value, std::vector<double>& out, bool squared) const {
  for (const auto& points : colours)
    tbb::parallel_for(std::size_t(0), points.size(), [&](std::size_t k) {
      const std::size_t p = points[k];
      const double f = m.alpha * weight[p] * value(p);
      const auto& w = sw[p];
      for (int t = 0; t < 27; ++t) {
        const double wt = w[0].w[std::size_t(t % 3)] * w[1].w[std::size_t(t / 3 % 3)] * w[2].w[std::size_t(t / 9)];
        out[std::size_t(snode[p][std::size_t(t)])] += f * (squared ? wt * wt : wt);
      }
    });
}

// The coarser levels' part in the equation of the node at cell c (coarse block cb around it):
// their function against its Laplacian (cross), their normals against its gradient (up).
void PoissonFunction::Impl::LevelSolve::coarse_terms(const std::array<int, 3>& c, std::int32_t cb, double& cross, double& up) const {
  const auto& cbc = C->block_cells[std::size_t(cb)];
  for (int tz = 0; tz < 4; ++tz) {
    const int kz = (c[2] >> 1) - 2 + (c[2] & 1) + tz;
    for (int ty = 0; ty < 4; ++ty) {
      const int ky = (c[1] >> 1) - 2 + (c[1] & 1) + ty;
      for (int tx = 0; tx < 4; ++tx) {
        const int kx = (c[0] >> 1) - 2 + (c[0] & 1) + tx;
        const std::int32_t j = C->near(cb, cbc, kx, ky, kz);
        if (j < 0) continue;
        const auto &Mx = L.Mc[std::size_t(c[0])], &My = L.Mc[std::size_t(c[1])], &Mz = L.Mc[std::size_t(c[2])];
        const auto &Kx = L.Kc[std::size_t(c[0])], &Ky = L.Kc[std::size_t(c[1])], &Kz = L.Kc[std::size_t(c[2])];
        const std::size_t ux = std::size_t(tx), uy = std::size_t(ty), uz = std::size_t(tz);
        cross += C->F[std::size_t(j)] * (Kx[ux] * My[uy] * Mz[uz] + Mx[ux] * Ky[uy] * Mz[uz] + Mx[ux] * My[uy] * Kz[uz]);
        if (!m.VF.empty()) {  // the coarser levels' normals: int V . grad B_i
          const Eigen::Vector3d& vf = m.VF[std::size_t(j)];
          const auto &Hx = L.Hc[std::size_t(c[0])], &Hy = L.Hc[std::size_t(c[1])], &Hz = L.Hc[std::size_t(c[2])];
          up += vf.x() * Hx[ux] * My[uy] * Mz[uz] + vf.y() * Mx[ux] * Hy[uy] * Mz[uz] + vf.z() * Mx[ux] * My[uy] * Hz[uz];
        }
      }
    }
  }
}

// right-hand side: b minus the coarser levels' part
void PoissonFunction::Impl::LevelSolve::coarse_right_hand_side() {
  r.assign(nodes, 0.0);
  diag.assign(nodes, 0.0);
  m.parallel_steps(nblocks, kLevelSetupShare * 0.12, kLevelSetupShare * 0.88, [&](std::size_t b) {
    const auto& bc = L.block_cells[b];
    const std::int32_t cb = C ? C->block(bc[0] >> 1, bc[1] >> 1, bc[2] >> 1) : -1;
    for (std::size_t k = 0; k < 8; ++k) {
      const std::size_t i = 8 * b + k;
      const auto c = L.node_cell(i);
      double cross = 0.0, up = 0.0;
      if (cb >= 0) coarse_terms(c, cb, cross, up);
      r[i] = L.b[i] + up - cross;
      diag[i] = L.K[std::size_t(c[0])][2] * L.M[std::size_t(c[1])][2] * L.M[std::size_t(c[2])][2] +
                L.M[std::size_t(c[0])][2] * L.K[std::size_t(c[1])][2] * L.M[std::size_t(c[2])][2] +
                L.M[std::size_t(c[0])][2] * L.M[std::size_t(c[1])][2] * L.K[std::size_t(c[2])][2];
    }
  });
}

void PoissonFunction::Impl::LevelSolve::add_screening() {
  std::vector<double> tmp(nodes, 0.0);
  scatter([&](std::size_t p) { return G[p]; }, tmp, false);
  for (std::size_t i = 0; i < nodes; ++i) r[i] -= tmp[i];
  scatter([](std::size_t) { return 1.0; }, diag, true);
}

// (L + S) v
void PoissonFunction::Impl::LevelSolve::apply(const std::vector<double>& v, std::vector<double>& out) {
  tbb::parallel_for(std::size_t(0), sv.size(), [&](std::size_t p) { sv[p] = sample_value(p, v); });
  tbb::parallel_for(std::size_t(0), nblocks, [&](std::size_t b) {
    double win[216];
    load_window(L, b, v, win);
    stencil_block(L.block_cells[b], L.M, L.K, L.M, L.K, L.M, L.K, win, &out[8 * b], false);
  });
  scatter([&](std::size_t p) { return sv[p]; }, out, false);
}

// Jacobi-preconditioned conjugate gradients from x = 0
void PoissonFunction::Impl::LevelSolve::solve() {
  sv.resize(cells.size());
  const int max_it = l <= m.params.full_depth ? std::max(m.params.max_iterations, 100) : m.params.max_iterations;
  // the iterations take the level's share between the set-up and the carried normals; the
  // tolerance may end them early (a jump, never a gap)
  const PcgResult cg = jacobi_pcg([&](const std::vector<double>& v, std::vector<double>& out) { apply(v, out); }, r, diag, L.x, max_it,
                                  m.params.tolerance, [&](int it) { m.level_done(kLevelSetupShare + kLevelSolveShare * it / max_it); });
  report.initial_residual = cg.initial_residual;
  report.iterations = cg.iterations;
  report.final_residual = cg.final_residual;
}

// the cumulative coefficients: the coarser levels' F prolonged, plus x
void PoissonFunction::Impl::LevelSolve::accumulate_coefficients() {
  tbb::parallel_for(std::size_t(0), nblocks, [&](std::size_t b) {
    const auto& bc = L.block_cells[b];
    const std::int32_t cb = C ? C->block(bc[0] >> 1, bc[1] >> 1, bc[2] >> 1) : -1;
    for (std::size_t k = 0; k < 8; ++k) {
      const std::size_t i = 8 * b + k;
      double pro = 0.0;
      if (cb >= 0) {
        const auto c = L.node_cell(i);
        const auto& cbc = C->block_cells[std::size_t(cb)];
        for (int uz = 0; uz < 2; ++uz) {
          const int kz = L.pk[std::size_t(c[2])][std::size_t(uz)];
          if (kz < 0) continue;
          for (int uy = 0; uy < 2; ++uy) {
            const int ky = L.pk[std::size_t(c[1])][std::size_t(uy)];
            if (ky < 0) continue;
            for (int ux = 0; ux < 2; ++ux) {
              const int kx = L.pk[std::size_t(c[0])][std::size_t(ux)];
              if (kx < 0) continue;
              const std::int32_t j = C->near(cb, cbc, kx, ky, kz);
              if (j < 0) continue;
              pro += C->F[std::size_t(j)] * L.pw[std::size_t(c[0])][std::size_t(ux)] * L.pw[std::size_t(c[1])][std::size_t(uy)] *
                     L.pw[std::size_t(c[2])][std::size_t(uz)];
            }
          }
        }
      }
      L.F[i] = pro + L.x[i];
    }
  });
}

// the normals splatted so far, as coefficients of this level: for the next level's b
void PoissonFunction::Impl::LevelSolve::carry_normals() {
  std::vector<Eigen::Vector3d> vf = m.splat(l);
  if (!m.VF.empty())
    tbb::parallel_for(std::size_t(0), nblocks, [&](std::size_t b) {
      const auto& bc = L.block_cells[b];
      const std::int32_t cb = C->block(bc[0] >> 1, bc[1] >> 1, bc[2] >> 1);
      if (cb < 0) return;
      const auto& cbc = C->block_cells[std::size_t(cb)];
      for (std::size_t k = 0; k < 8; ++k) {
        const std::size_t i = 8 * b + k;
        const auto c = L.node_cell(i);
        for (int uz = 0; uz < 2; ++uz)
          for (int uy = 0; uy < 2; ++uy)
            for (int ux = 0; ux < 2; ++ux) {
              const int kx = L.pk[std::size_t(c[0])][std::size_t(ux)], ky = L.pk[std::size_t(c[1])][std::size_t(uy)],
                        kz = L.pk[std::size_t(c[2])][std::size_t(uz)];
              if (kx < 0 || ky < 0 || kz < 0) continue;
              const std::int32_t j = C->near(cb, cbc, kx, ky, kz);
              if (j < 0) continue;
              vf[i] += m.VF[std::size_t(j)] * (L.pw[std::size_t(c[0])][std::size_t(ux)] * L.pw[std::size_t(c[1])][std::size_t(uy)] *
                                               L.pw[std::size_t(c[2])][std::size_t(uz)]);
            }
      }
    });
  m.VF.swap(vf);
}

PoissonLevelReport PoissonFunction::Impl::solve_level(int l) {
  LevelSolve level(*this, l);
  if (level.nodes == 0) {
    VF.clear();
    return level.report;
  }
  // the set-up's shares (level 9 of hand 400k: 0.13, 0.02, 1.7 and 0.18 s)
  level.merge_screening_points();
  level_done(kLevelSetupShare * 0.08);
  level.colour_points();
  level_done(kLevelSetupShare * 0.12);
  level.coarse_right_hand_side();
  level.add_screening();
  level_done(kLevelSetupShare);
  level.solve();
  level.accumulate_coefficients();
  level_done(kLevelSetupShare + kLevelSolveShare);
  level.carry_normals();
  level_done(1.0);
  return level.report;
}

PoissonFunction::PoissonFunction(std::vector<PoissonSample> samples, const PoissonSystemParams& params, const IsoLattice& frame,
                                 const ProgressCallback& progress,
                                 const std::function<void(const std::vector<std::size_t>& nodes_per_level)>& on_octree)
    : impl_(std::make_unique<Impl>()), frame_(frame) {
  Impl& m = *impl_;
  m.params = params;
  m.params.full_depth = std::clamp(params.full_depth, 1, params.depth);
  m.params.kernel_depth = std::clamp(params.kernel_depth, 1, params.depth);
  m.s = params.dirichlet ? -1.0 : 1.0;
  m.alpha = params.point_weight * double(std::uint64_t{1} << params.depth);
  const int depth = params.depth;
  const int n = 1 << depth;
  report_phase(progress, "octree");
  // Morton order of the finest cells, ties by position: independent of the input order
  const std::size_t ns = samples.size();
  std::vector<Key> keys(ns);
  for (std::size_t p = 0; p < ns; ++p) {
    const auto& x = samples[p].position;
    keys[p] = morton(std::clamp(int(std::floor(x.x() * n)), 0, n - 1), std::clamp(int(std::floor(x.y() * n)), 0, n - 1),
                     std::clamp(int(std::floor(x.z() * n)), 0, n - 1));
  }
  m.order.resize(ns);
  std::iota(m.order.begin(), m.order.end(), 0u);
  tbb::parallel_sort(m.order.begin(), m.order.end(), [&](std::uint32_t a, std::uint32_t b) {
    if (keys[a] != keys[b]) return keys[a] < keys[b];
    const auto &pa = samples[a].position, &pb = samples[b].position;
    if (pa.x() != pb.x()) return pa.x() < pb.x();
    if (pa.y() != pb.y()) return pa.y() < pb.y();
    if (pa.z() != pb.z()) return pa.z() < pb.z();
    const auto &na = samples[a].normal, &nb = samples[b].normal;
    return std::tie(na.x(), na.y(), na.z()) < std::tie(nb.x(), nb.y(), nb.z());
  });
  std::vector<Key>& sorted = m.keys;
  sorted.resize(ns);
  m.q.resize(ns);
  m.normals_.resize(ns);
  for (std::size_t p = 0; p < ns; ++p) {
    sorted[p] = keys[m.order[p]];
    m.q[p] = samples[m.order[p]].position;
    m.normals_[p] = samples[m.order[p]].normal;
  }
  samples.clear();
  samples.shrink_to_fit();
  auto report = [&](double f) {
    if (progress && !progress(f)) throw CancelledError("reconstruct_poisson: cancelled");
  };
  report(kSortShare);
  m.levels.assign(std::size_t(depth + 1), Level{});
  m.level_of.assign(ns, std::uint8_t(depth));  // every sample reaches the kernel level
  // the octree's shares: the levels to the kernel level 20 % (the kernel level most), the
  // density 15 %, the finer levels the rest by the samples that reach them (hand 400k: 0.4,
  // 0.36 and 1.3 s)
  const auto octree_at = [&](double f) { report(kSortShare + (kOctreeShare - kSortShare) * f); };
  const auto build = [&](int l, double begin, double end) {
    m.level_progress = [&](double f) { octree_at(begin + (end - begin) * f); };
    m.build_level(l);
    m.level_progress = nullptr;
    octree_at(end);
  };
  for (int l = 1; l <= m.params.kernel_depth; ++l) build(l, l == m.params.kernel_depth ? 0.05 : 0.0, l == m.params.kernel_depth ? 0.2 : 0.05);
  m.estimate_density();
  octree_at(0.35);
  {
    std::vector<double> reach(std::size_t(depth + 1), 0.0);  // samples reaching each level and all finer
    for (const std::uint8_t l : m.level_of) reach[std::min<std::size_t>(l, std::size_t(depth))] += 1.0;
    for (int l = depth - 1; l >= 0; --l) reach[std::size_t(l)] += reach[std::size_t(l + 1)];
    double total = 0.0, done = 0.0;
    for (int l = m.params.kernel_depth + 1; l <= depth; ++l) total += reach[std::size_t(l)];
    for (int l = m.params.kernel_depth + 1; l <= depth; ++l) {
      const double w = reach[std::size_t(l)] / std::max(total, 1.0);
      build(l, 0.35 + 0.65 * done, 0.35 + 0.65 * (done + w));
      done += w;
    }
  }
  report(kOctreeShare);
  if (on_octree) {
    std::vector<std::size_t> nodes(std::size_t(depth), 0);
    for (int l = 1; l <= depth; ++l) nodes[std::size_t(l - 1)] = m.levels[std::size_t(l)].nodes();
    on_octree(nodes);
  }
  report_phase(progress, "splatting");
  m.level_progress = [&](double f) { report(kOctreeShare + kSplatShare * f); };
  m.splat_and_restrict();
  report(kOctreeShare + kSplatShare);
  // A level's solve costs about its nodes per iteration plus its screening points' set-up and
  // carried normals: its share of the rest follows that cost (bench/notes/progress.md).
  std::vector<double> level_cost(std::size_t(depth + 1), 0.0);
  double total_cost = 0.0;
  for (int l = 1; l <= depth; ++l) {
    const std::size_t nodes = m.levels[std::size_t(l)].nodes();
    // a level holds at most one screening point per sample
    level_cost[std::size_t(l)] = double(nodes) + kScreeningCostInNodes * double(std::min(nodes, ns));
    total_cost += level_cost[std::size_t(l)];
  }
  double cost_done = 0.0;
  const double solve_begin = kOctreeShare + kSplatShare, solve_share = 1.0 - solve_begin - kSampleValueShare;
  std::size_t bytes = 0;
  for (const Level& L : m.levels) bytes += L.bytes();
  bytes += ns * (2 * sizeof(Eigen::Vector3d) + sizeof(double) * 2 + sizeof(std::uint32_t) + sizeof(Key));
  std::size_t largest = 0;
  for (int l = 1; l <= depth; ++l) {
    report_phase(progress, "solve level " + std::to_string(l) + "/" + std::to_string(depth));
    const double cost = level_cost[std::size_t(l)];
    m.level_progress = [&](double f) { report(solve_begin + solve_share * (cost_done + cost * f) / std::max(total_cost, 1.0)); };
    reports_.push_back(m.solve_level(l));
    cost_done += cost;
    // the level's solver work arrays: 27 nodes and 9 weights per sample, 5 doubles per node
    largest = std::max(largest, ns * (27 * sizeof(std::int32_t) + sizeof(std::array<Weights1D, 3>) + sizeof(double)) +
                                    m.levels[std::size_t(l)].nodes() * 5 * sizeof(double));
  }
  m.level_progress = nullptr;
  report(1.0 - kSampleValueShare);
  report_phase(progress, "iso value");
  peak_bytes_ = bytes + largest;
  for (int l = 1; l <= depth; ++l)
    if (m.levels[std::size_t(l)].nodes() > 0) finest_level_ = l;
  std::vector<double> G(ns);
  tbb::parallel_for(std::size_t(0), ns, [&](std::size_t p) { G[p] = m.evaluate(m.q[p], 0); });
  double wsum = 0.0, vsum = 0.0;
  for (std::size_t p = 0; p < ns; ++p) wsum += m.area[p], vsum += m.area[p] * G[p];
  iso_value_ = wsum > 0.0 ? vsum / wsum : 0.0;
  sample_values_.resize(ns);
  for (std::size_t p = 0; p < ns; ++p) sample_values_[m.order[p]] = G[p];
  // evaluation reads the coefficients, the octree and the density only: the rest goes before
  // the extraction allocates
  auto release = [](auto& v) { std::decay_t<decltype(v)>().swap(v); };
  for (Level& L : m.levels) release(L.b), release(L.first), release(L.last);
  release(m.q), release(m.normals_), release(m.area), release(m.keys), release(m.level_of), release(m.order), release(m.VF);
  report(1.0);
}

PoissonFunction::~PoissonFunction() = default;

void PoissonFunction::corner_values(int level, const std::uint32_t* corners, std::size_t n, double* values) const {
  const double h = 1.0 / double(std::uint64_t{1} << level);
  for (std::size_t i = 0; i < n; ++i)
    values[i] = impl_->evaluate(Eigen::Vector3d(corners[3 * i] * h, corners[3 * i + 1] * h, corners[3 * i + 2] * h), 0);
}

double PoissonFunction::value(const Eigen::Vector3d& p) const { return impl_->evaluate((p - frame_.origin) / frame_.size, 0); }

Eigen::Vector3d PoissonFunction::gradient(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d q = (p - frame_.origin) / frame_.size;
  return impl_->evaluate_all(q, 1, 3).tail<3>() / frame_.size;
}

bool PoissonFunction::refined(int level, const std::array<std::uint32_t, 3>& cell) const {
  if (level >= impl_->params.depth) return false;
  if (level < impl_->params.full_depth) return true;
  return impl_->levels[std::size_t(level + 1)].block(int(cell[0]), int(cell[1]), int(cell[2])) >= 0;
}

double PoissonFunction::density_depth(const Eigen::Vector3d& world) const {
  const Impl& m = *impl_;
  const Eigen::Vector3d p = (world - frame_.origin) / frame_.size;
  const Level& L = m.levels[std::size_t(m.params.kernel_depth)];
  bool complete = true;
  const double w = m.gather(L, m.density, p, 0, complete);
  if (!(w > 0.0)) return 0.0;
  return std::clamp(m.depth_of(w), 0.0, double(m.params.depth));
}

}  // namespace pointsurf::detail
