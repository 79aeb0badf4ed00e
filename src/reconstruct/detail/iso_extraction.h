// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The phases of extract_iso_surface (reconstruct/iso_surface.cpp, method described there), as
// an object whose members hold what one phase hands to the next, so that each phase can be run
// and checked alone (tests/reconstruct/iso_extraction_phases_test.cpp).
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <unordered_map>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "core/detail/progress_reporter.h"
#include "reconstruct/detail/iso_surface.h"

namespace pointsurf::detail::iso {

using Key = std::uint64_t;
constexpr int kMaxDepth = 19;  // 20 bits per coordinate of a corner (up to 2^depth)
constexpr int kBits = 20;
constexpr Key kMask = (Key{1} << kBits) - 1;

inline Key pack(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
  return Key{x} | (Key{y} << kBits) | (Key{z} << (2 * kBits));
}
inline std::array<std::uint32_t, 3> unpack(Key k) {
  return {static_cast<std::uint32_t>(k & kMask), static_cast<std::uint32_t>((k >> kBits) & kMask),
          static_cast<std::uint32_t>((k >> (2 * kBits)) & kMask)};
}

constexpr int kB = 8;       // finest cells per brick side
constexpr int kC = kB + 1;  // corners per brick side
constexpr std::uint8_t kQueued = 1, kActive = 2;

/// 8^3 finest cells and their corners' values (minus the iso-value, inside positive; NaN until
/// evaluated), with the cells' state and the crossed edges the brick owns. Cell (x, y, z) of the
/// brick is x + kB y + kB^2 z, corner (x, y, z) is x + kC y + kC^2 z.
struct Brick {
  Brick();
  Key key = 0;  // brick coordinates, packed
  std::array<double, kC * kC * kC> w;  // double: a float rounding flip moved vertices by 1e-9 of the diagonal under a 1e6 m shift
  std::array<std::uint8_t, kB * kB * kB> state{};
  std::vector<std::uint16_t> pending;
  std::vector<Key> outbox;           // cells of other bricks reached in the last round
  std::vector<std::uint16_t> edges;  // owned crossed edges: 3 x local corner + axis, sorted
  std::uint32_t first_vertex = 0;
};

/// One brick's triangles, and the centre vertices of the loops it fanned.
struct ChunkOutput {
  std::vector<std::array<std::uint32_t, 3>> triangles;  // centre vertices flagged with kCentre
  std::vector<Eigen::Vector3d> centres, centre_normals;
};
constexpr std::uint32_t kCentre = 0x80000000u;

/// The oriented face segments of one cell closed into loops of local edge ids (corner
/// i = x | y << 1 | z << 2; edge a * 4 + bit(a+1) + 2 bit(a+2)), each loop counter-clockwise
/// seen from outside the surface; returns the number of loops, loop l being
/// loop_edges[loop_start[l] .. loop_start[l + 1]). `w` holds corner values minus the iso-value,
/// sign-adjusted so that inside is positive.
int cell_loops(const std::array<double, 8>& w, std::array<int, 12>& loop_edges, std::array<int, 5>& loop_start);

/// The root in [0, 1] of the quadratic through (0, wa), (1/2, wm), (1, wb), where wa and wb have
/// opposite signs; the linear root when the quadratic degenerates or its root falls outside.
double quadratic_root(double wa, double wm, double wb);

/// Appends the chunks' centre vertices to `out` after its edge vertices, chunk by chunk, and
/// their triangles with each kCentre-flagged index made the centre's final index.
void append_chunks(std::vector<ChunkOutput>& chunks, IsoSurface& out);

/// extract_iso_surface, phase by phase. Construct (checks the lattice), then call
/// find_leaves, seed_coarse_crossings, queue_seeds, follow_round until it returns false, index_bricks,
/// collect_crossed_edges, place_vertices, triangulate_cells, and take the result.
class Extraction {
 public:
  /// Throws UsageError for a lattice depth outside [0, kMaxDepth] or a size not positive and finite.
  Extraction(const IsoFunction& f, const IsoLattice& lattice, const IsoSurfaceParams& params);

  /// Reads f.refined level by level; produces the finest leaves (seeds) and the coarser leaves,
  /// and lowers the meshing depth to the deepest level with leaves when the lattice's has none.
  void find_leaves();
  /// Reads the coarse leaves' corner values; adds to the seeds the finest cells around the finest
  /// sub-edge of each coarse-leaf edge whose ends differ in sign (bisection); sorts the seeds.
  /// Reports its corners evaluated and leaves searched to `progress` as [begin, end] (throws CancelledError).
  void seed_coarse_crossings(const ProgressCallback& progress = {}, double begin = 0.0, double end = 1.0);
  /// Reads the seeds; produces the bricks that hold them, the seeds pending in them (and clears the seeds).
  void queue_seeds();
  /// Processes every brick with pending cells once (their corner values, the crossed cells made
  /// active, the cells around their crossed edges queued, other bricks' through the outboxes);
  /// returns false when no brick had pending cells.
  /// `brick_done`, when given, is called (from any worker) after each brick processed, with the
  /// cells it processed.
  bool follow_round(const std::function<void(std::size_t cells)>& brick_done = {});
  /// Sorts the bricks by key and re-indexes them.
  void index_bricks();
  /// Reads the active cells; produces each brick's sorted owned crossed edges and first vertex.
  void collect_crossed_edges();
  /// Reads the owned edges; produces one vertex and unit normal per edge, in brick order.
  void place_vertices(const std::function<void()>& brick_done = {});
  /// Reads the active cells and the vertices; produces each brick's triangles and centres.
  void triangulate_cells(const std::function<void()>& brick_done = {});
  /// The surface: edge vertices, then the centres and triangles of the bricks in key order.
  IsoSurface result() &&;

  int depth() const { return depth_; }
  const std::vector<Key>& seeds() const { return seeds_; }
  const std::vector<std::pair<int, Key>>& coarse_leaves() const { return coarse_leaves_; }
  const std::vector<std::unique_ptr<Brick>>& bricks() const { return bricks_; }
  const IsoSurface& surface() const { return out_; }
  const std::vector<ChunkOutput>& chunks() const { return chunks_; }

 private:
  Eigen::Vector3d position(Key corner) const;
  void evaluate(const std::vector<Key>& corners, std::vector<double>& out, ProgressReporter* reporter = nullptr) const;
  double value_at(std::uint32_t x, std::uint32_t y, std::uint32_t z) const;
  double sign(double v) const { return params_.inside_positive ? v - params_.iso_value : params_.iso_value - v; }
  void seeds_of_leaf(int level, Key cell, const std::vector<Key>& corners, const std::vector<double>& values,
                     std::vector<Key>& found) const;
  void cells_around_edge(Key corner, int axis, std::vector<Key>& out) const;
  Brick& brick_at(Key brick_key);
  void enqueue(Key cell);
  std::size_t process(Brick& b) const;  // the cells processed
  void evaluate_missing_corners(Brick& b, const std::vector<std::uint16_t>& wave) const;
  void follow_crossed_edges(Brick& b, std::uint16_t cell, std::vector<std::uint16_t>& next_wave) const;
  const Brick* owner_and_edge(const Brick& b, int cell, int e, std::uint16_t& local_edge) const;
  Eigen::Vector3d unit_normal(const Eigen::Vector3d& p, const Eigen::Vector3d& fallback) const;
  void place_vertex(const Brick& b, std::size_t j);
  void triangulate_brick(const Brick& b, ChunkOutput& o) const;
  bool triangulate_loop(const int* L, int n, const std::array<std::uint32_t, 12>& v, ChunkOutput& o) const;
  void fan_loop(int n, const std::array<std::uint32_t, 12>& v, ChunkOutput& o) const;

  const IsoFunction& f_;
  const IsoLattice& lattice_;
  const IsoSurfaceParams& params_;
  int depth_;  // lowered by find_leaves to the deepest level that has leaves
  std::uint32_t cells_per_side_;
  double h_;
  std::vector<Key> seeds_;  // finest cells
  std::vector<std::pair<int, Key>> coarse_leaves_;
  std::vector<std::unique_ptr<Brick>> bricks_;
  std::unordered_map<Key, std::uint32_t> brick_of_;
  IsoSurface out_;
  std::vector<ChunkOutput> chunks_;
};

}  // namespace pointsurf::detail::iso
