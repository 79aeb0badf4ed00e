// SPDX-License-Identifier: GPL-3.0-or-later
// Ball pivoting (Bernardini et al. 1999). The front is advanced serially: every pivot depends
// on the triangles made before it. What can run in parallel (duplicate detection, normal
// normalisation, the neighbour lists of the first pass) does; the serial part allocates nothing
// per point: edges live in one array with intrusive per-vertex lists, and neighbour queries
// reuse one buffer.
#include "pointsurf/reconstruct/ball_pivot.h"
#include "pointsurf/reconstruct/fill_holes.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <optional>
#include <span>
#include <vector>

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "core/detail/progress_reporter.h"
#include "reconstruct/detail/exact_copies.h"
#include "reconstruct/detail/hole_filling.h"
#include "pointsurf/core/error.h"
#include "pointsurf/core/mesh_topology.h"

namespace pointsurf {
namespace {

// Points closer than this fraction of the mean spacing to a point of lower index are duplicates
// and are left out (a triangle through two of them would be degenerate).
constexpr double kDuplicateInSpacings = 1e-6;
// A triangle whose sine of its angle at the shared vertex is below this is treated as collinear.
constexpr double kCollinearSine = 1e-9;
// A point is inside a ball when its squared distance to the centre is below (1 - this) r^2:
// points exactly on the sphere (co-circular grids) do not block it.
constexpr double kInsideTolerance = 1e-9;
// Seeds try pairs among this many nearest unused neighbours of a point (Bernardini et al.
// consider pairs nearest first; the first pairs almost always give the seed when one exists).
constexpr int kSeedNeighbours = 12;

enum class EdgeState : std::uint8_t { Front, Boundary, Inner };

// An edge of the growing mesh. While it has one triangle, that triangle runs v0 -> v1 and
// `opposite` is its third vertex.
struct Edge {
  int v0, v1, opposite;
  EdgeState state;
  int next0, next1;  // next edge in the lists of v0 and v1 (-1 ends)
};

struct PivotCandidate {
  double angle;
  int point;
  Eigen::Vector3d center;
};

// Triangle acceptance rules, as cosines and lengths.
struct Rules {
  double cos_vertex;     // triangle normal against each vertex normal
  double cos_mean;       // triangle normal against the mean of its vertex normals
  double cos_opposite;   // two vertex normals farther apart than this: opposite sides
  double sheet_offset;   // cloud units: see other_sheet()
};
// Vertex normals closer than this are "parallel" for the sheet test, degrees.
constexpr double kSheetNormalDeg = 30.0;
// A chord between parallel-normal points that leaves their common tangent plane by more than
// this angle (and more than kSheetOffsetInSpacings) goes to another sheet, degrees.
constexpr double kSheetChordDeg = 20.0;
constexpr double kSheetOffsetInSpacings = 1.0;
// Two vertex normals more than this apart point to opposite sides, degrees.
constexpr double kOppositeNormalsDeg = 120.0;
// The final pass closes boundary loops of at most this many edges that fit in the largest ball.
// Neighbour lists are precomputed (in parallel) when the first radius is at most this many mean
// spacings.
constexpr double kPrecomputeInSpacings = 3.0;
// Front edges whose neighbourhoods look_ahead() finds at once, and per parallel task.
constexpr std::size_t kPivotWindow = 16384;
constexpr std::size_t kAheadChunk = 512;

class BallPivoter {
public:
  BallPivoter(const KdTree& tree, std::vector<Eigen::Vector3d> local, std::vector<Eigen::Vector3d> normals,
              std::vector<std::uint8_t> skip, const Eigen::Vector3d& origin, const Rules& rules,
              detail::ProgressReporter& reporter)
      : tree_(tree), local_(std::move(local)), normals_(std::move(normals)), skip_(std::move(skip)), origin_(origin),
        rules_(rules), reporter_(reporter), head_(local_.size(), -1), open_(local_.size(), 0),
        used_(local_.size(), 0) {}

  // Neighbour lists of every point within 3 × the first radius, computed in parallel before the
  // first pass (which makes most of the triangles): a pivot around edge (a, b) or a seed at a
  // only needs the points within 2r of a point within r of a.
  void precompute_neighbours(double first_radius) {
    const std::size_t n = local_.size();
    near_radius_ = 3.0 * first_radius;
    constexpr std::size_t kChunk = 2048;
    const std::size_t chunks = (n + kChunk - 1) / kChunk;
    std::vector<std::vector<std::uint32_t>> chunk_index(chunks);
    near_offsets_.assign(n + 1, 0);
    tbb::enumerable_thread_specific<std::vector<Neighbor>> buffers;
    tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
      std::vector<Neighbor>& nbs = buffers.local();
      std::vector<std::uint32_t>& out = chunk_index[c];
      for (std::size_t i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i) {
        if (skip_[i]) continue;
        tree_.radius(global(local_[i]), near_radius_, nbs);
        const std::size_t before = out.size();
        for (const Neighbor& nb : nbs)
          if (!skip_[nb.index]) out.push_back(nb.index);  // skipped points never join a triangle
        near_offsets_[i + 1] = out.size() - before;
      }
    });
    for (std::size_t i = 0; i < n; ++i) near_offsets_[i + 1] += near_offsets_[i];
    near_index_.resize(near_offsets_[n]);
    tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
      std::copy(chunk_index[c].begin(), chunk_index[c].end(), near_index_.begin() + long(near_offsets_[c * kChunk]));
    });
  }

  void run_pass(double radius, std::size_t pass, std::size_t passes) {
    if (pass == 0) near_plane_ = 0.5 * radius;
    radius_ = radius;
    squared_radius_ = radius * radius;
    pass_begin_ = double(pass) / double(passes);
    pass_span_ = 1.0 / double(passes);
    // Edges a smaller ball could not pivot over get a second chance with this one, but only
    // where the larger ball can rest on the edge's triangle without holding another point
    // (Bernardini et al. 1999, section 4.3): a larger ball whose starting position already
    // reaches through a nearby sheet would bridge to it.
    // No triangle is made meanwhile, so the edges are tested in parallel.
    std::vector<std::uint8_t> fits(edges_.size(), 0);
    tbb::enumerable_thread_specific<std::vector<Neighbor>> buffers;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, edges_.size(), 1024), [&](const tbb::blocked_range<std::size_t>& r) {
      std::vector<Neighbor>& nbs = buffers.local();
      for (std::size_t e = r.begin(); e != r.end(); ++e)
        fits[e] = std::uint8_t(edges_[e].state == EdgeState::Boundary && larger_ball_fits(edges_[e], nbs));
    });
    for (std::size_t e = 0; e < edges_.size(); ++e)
      if (fits[e]) {
        edges_[e].state = EdgeState::Front;
        front_.push_back(int(e));
      }
    const std::span<const std::uint32_t> order = tree_.spatial_order();
    std::size_t cursor = 0;
    for (;;) {
      advance_front();
      // Next seed: the first unused point, in spatial order, that has an empty seed ball.
      bool seeded = false;
      while (cursor < order.size() && !seeded) {
        const int v = int(order[cursor++]);
        if (!used_[v] && !skip_[v]) seeded = try_seed(v);
        if ((cursor & 4095) == 0) tick();
      }
      if (!seeded) break;
    }
  }

  std::vector<Triangle> take_triangles() { return std::move(triangles_); }

private:

  void tick() {
    reporter_.report(pass_begin_ + pass_span_ * double(used_count_) / double(local_.size()));
    reporter_.throw_if_cancelled();
  }

  Eigen::Vector3d global(const Eigen::Vector3d& p) const { return p + origin_; }

  // A vertex whose every edge has two triangles: the surface around it is finished. Balls pass
  // through such vertices (neither hit nor blocked by them), so that a larger ball can close a
  // hole whose rim it could otherwise not reach without touching the finished surface around.
  bool inner(int v) const { return used_[v] && open_[v] == 0; }

  int find_edge(int a, int b) const {
    for (int e = head_[a]; e >= 0;) {
      const Edge& edge = edges_[e];
      if (edge.v0 == b || edge.v1 == b) return e;
      e = edge.v0 == a ? edge.next0 : edge.next1;
    }
    return -1;
  }

  // The directed edge from -> to can be added to a triangle: it is new, or its one triangle
  // runs the other way (so the two triangles are consistently oriented).
  bool edge_fits(int from, int to) const {
    const int e = find_edge(from, to);
    if (e < 0) return true;
    const Edge& edge = edges_[e];
    return edge.state != EdgeState::Inner && edge.v0 == to && edge.v1 == from;
  }

  void add_edge_side(int from, int to, int opposite) {
    const int e = find_edge(from, to);
    if (e >= 0) {  // glue: the edge now has its second triangle
      edges_[e].state = EdgeState::Inner;
      --open_[from];
      --open_[to];
      return;
    }
    const int id = int(edges_.size());
    edges_.push_back(Edge{from, to, opposite, EdgeState::Front, head_[from], head_[to]});
    head_[from] = id;
    head_[to] = id;
    ++open_[from];
    ++open_[to];
    front_.push_back(id);
  }

  void add_triangle(int a, int b, int c) {
    add_edge_side(a, b, c);
    add_edge_side(b, c, a);
    add_edge_side(c, a, b);
    for (const int v : {a, b, c})
      if (!used_[v]) {
        used_[v] = 1;
        ++used_count_;
      }
    triangles_.emplace_back(a, b, c);
  }

  // Unit normal of a -> b -> c (counter-clockwise), or nullopt when the triangle is degenerate.
  std::optional<Eigen::Vector3d> triangle_normal(int a, int b, int c) const {
    const Eigen::Vector3d u = local_[b] - local_[a];
    const Eigen::Vector3d v = local_[c] - local_[a];
    const Eigen::Vector3d w = u.cross(v);
    const double norm = w.norm();
    if (!(norm > kCollinearSine * u.norm() * v.norm())) return std::nullopt;
    return Eigen::Vector3d(w / norm);
  }

  // Centre of the ball of radius_ through a, b, c on the side their counter-clockwise normal
  // points to, or nullopt when the triangle is degenerate or its circumcircle is too wide.
  std::optional<Eigen::Vector3d> ball_center(int a, int b, int c) const {
    const Eigen::Vector3d u = local_[b] - local_[a];
    const Eigen::Vector3d v = local_[c] - local_[a];
    const Eigen::Vector3d w = u.cross(v);
    const double w2 = w.squaredNorm();
    if (!(std::sqrt(w2) > kCollinearSine * u.norm() * v.norm())) return std::nullopt;
    const Eigen::Vector3d to_circumcenter = (u.squaredNorm() * v.cross(w) + v.squaredNorm() * w.cross(u)) / (2.0 * w2);
    const double height2 = squared_radius_ - to_circumcenter.squaredNorm();
    if (!(height2 >= 0.0)) return std::nullopt;
    return Eigen::Vector3d(local_[a] + to_circumcenter + w * std::sqrt(height2 / w2));
  }

  // p and q lie on two different sheets: their normals are nearly parallel, but the chord
  // between them leaves their common tangent plane steeply and by more than a spacing (two scans
  // of a thin wall, stacked plates). On one smooth sheet the chord is perpendicular to the sum
  // of the two normals (exactly so on a circle), whatever the curvature.
  bool other_sheet(int p, int q) const {
    static const double cos_parallel = std::cos(kSheetNormalDeg * std::numbers::pi / 180.0);
    static const double sin_chord = std::sin(kSheetChordDeg * std::numbers::pi / 180.0);
    if (!(normals_[p].dot(normals_[q]) > cos_parallel)) return false;
    const Eigen::Vector3d d = local_[q] - local_[p];
    const Eigen::Vector3d m = (normals_[p] + normals_[q]).normalized();
    const double offset = std::abs(m.dot(d));
    return offset > rules_.sheet_offset && offset > sin_chord * d.norm();
  }

  // The triangle's normal agrees with the normals of its three vertices: within the vertex
  // angle of each, within the mean angle of their mean; no two of them opposite; and the
  // triangle does not join two sheets.
  bool normals_agree(const Eigen::Vector3d& n, int a, int b, int c) const {
    const Eigen::Vector3d sum = normals_[a] + normals_[b] + normals_[c];
    if (!(n.dot(sum) >= rules_.cos_mean * sum.norm())) return false;
    if (!(n.dot(normals_[a]) > rules_.cos_vertex && n.dot(normals_[b]) > rules_.cos_vertex &&
          n.dot(normals_[c]) > rules_.cos_vertex))
      return false;
    if (normals_[a].dot(normals_[b]) < rules_.cos_opposite || normals_[b].dot(normals_[c]) < rules_.cos_opposite ||
        normals_[c].dot(normals_[a]) < rules_.cos_opposite)
      return false;
    return !other_sheet(a, b) && !other_sheet(b, c) && !other_sheet(c, a);
  }

  // No neighbour other than a, b, c is strictly inside the ball at `center`. A finished
  // (inner) vertex within `near_plane_` of the triangle's plane does not count: it belongs to
  // the surface around a hole the ball is closing. Farther ones do. A point on another sheet
  // than all three corners (other_sheet) does not count either: a ball wider than the gap
  // between two parallel sheets may reach through one while it rolls on the other.
  bool ball_empty(const Eigen::Vector3d& center, int a, int b, int c, const std::vector<Neighbor>& neighbors) const {
    const double limit = squared_radius_ * (1.0 - kInsideTolerance);
    const std::optional<Eigen::Vector3d> n = triangle_normal(a, b, c);
    for (const Neighbor& nb : neighbors) {
      const int q = int(nb.index);
      if (q == a || q == b || q == c || skip_[q]) continue;
      if ((local_[q] - center).squaredNorm() >= limit) continue;
      if (inner(q) && n && std::abs(n->dot(local_[q] - local_[a])) <= near_plane_) continue;
      if (other_sheet(a, q) && other_sheet(b, q) && other_sheet(c, q)) continue;
      return false;
    }
    return true;
  }

  // The ball of the current radius rests on the edge's triangle and holds no other point.
  // Reads the state only (several edges are tested at once); `buffer` holds the neighbours.
  bool larger_ball_fits(const Edge& edge, std::vector<Neighbor>& buffer) const {
    const std::optional<Eigen::Vector3d> center = ball_center(edge.v0, edge.v1, edge.opposite);
    if (!center) return false;
    tree_.radius(global(*center), radius_, buffer);
    return ball_empty(*center, edge.v0, edge.v1, edge.opposite, buffer);
  }

  // Before the front edges front_[front_head_ ..] are pivoted in turn, the points around their
  // midpoints (which do not depend on the triangles made meanwhile) are looked up in parallel,
  // a window of kPivotWindow edges at a time: pivot() then takes them from ahead_.
  void look_ahead() {
    const std::size_t begin = front_head_, end = std::min(front_.size(), begin + kPivotWindow);
    ahead_begin_ = begin;
    ahead_offsets_.assign(end - begin + 1, 0);
    const std::size_t chunks = (end - begin + kAheadChunk - 1) / kAheadChunk;
    ahead_chunks_.resize(std::max(ahead_chunks_.size(), chunks));
    tbb::enumerable_thread_specific<std::vector<Neighbor>> buffers;
    tbb::parallel_for(std::size_t(0), chunks, [&](std::size_t c) {
      std::vector<Neighbor>& nbs = buffers.local();
      std::vector<std::uint32_t>& out = ahead_chunks_[c];
      out.clear();
      for (std::size_t i = begin + c * kAheadChunk; i < std::min(end, begin + (c + 1) * kAheadChunk); ++i) {
        const Edge& edge = edges_[std::size_t(front_[i])];
        const std::size_t before = out.size();
        if (edge.state == EdgeState::Front) {
          tree_.radius(global(0.5 * (local_[edge.v0] + local_[edge.v1])), 2.0 * radius_, nbs);
          for (const Neighbor& nb : nbs) out.push_back(nb.index);
        }
        ahead_offsets_[i - begin + 1] = out.size() - before;
      }
    });
    for (std::size_t i = 0; i + begin < end; ++i) ahead_offsets_[i + 1] += ahead_offsets_[i];
    ahead_index_.resize(ahead_offsets_.back());
    for (std::size_t c = 0; c < chunks; ++c)
      std::copy(ahead_chunks_[c].begin(), ahead_chunks_[c].end(), ahead_index_.begin() + long(ahead_offsets_[c * kAheadChunk]));
    ahead_end_ = end;
  }

  // neighbors_ = the points within `reach` of `center`, which lies within reach / 2 of point
  // `near`: from near's precomputed list when it covers them, else from the tree.
  void gather(int near, const Eigen::Vector3d& center, double reach) {
    if (!near_offsets_.empty() && 1.5 * reach <= near_radius_ * (1.0 + 1e-12)) {
      neighbors_.clear();
      const double reach2 = reach * reach;
      for (std::size_t k = near_offsets_[near]; k < near_offsets_[near + 1]; ++k) {
        const std::uint32_t q = near_index_[k];
        const double d2 = (local_[q] - center).squaredNorm();
        if (d2 <= reach2) neighbors_.emplace_back(q, d2);
      }
      return;
    }
    tree_.radius(global(center), reach, neighbors_);
  }

  bool try_seed(int v) {
    gather(v, local_[v], 2.0 * radius_);
    seed_candidates_.clear();
    for (const Neighbor& nb : neighbors_) {
      const int q = int(nb.index);
      if (q == v || used_[q] || skip_[q]) continue;
      seed_candidates_.push_back(q);
      if (int(seed_candidates_.size()) == kSeedNeighbours) break;
    }
    for (std::size_t i = 0; i < seed_candidates_.size(); ++i)
      for (std::size_t j = i + 1; j < seed_candidates_.size(); ++j) {
        int a = seed_candidates_[i];
        int b = seed_candidates_[j];
        std::optional<Eigen::Vector3d> n = triangle_normal(v, a, b);
        if (!n) continue;
        if (n->dot(normals_[v] + normals_[a] + normals_[b]) < 0.0) {
          std::swap(a, b);
          *n = -*n;
        }
        if (!normals_agree(*n, v, a, b)) continue;
        const std::optional<Eigen::Vector3d> center = ball_center(v, a, b);
        if (!center || !ball_empty(*center, v, a, b, neighbors_)) continue;
        add_triangle(v, a, b);
        return true;
      }
    return false;
  }

  // Pivots the ball resting on the edge's triangle around the edge, away from that triangle,
  // and returns true when it makes a new triangle.
  bool pivot(const Edge& edge, std::size_t front_position) {
    const int a = edge.v0;
    const int b = edge.v1;
    const int o = edge.opposite;
    const std::optional<Eigen::Vector3d> start = ball_center(a, b, o);
    if (!start) return false;
    const Eigen::Vector3d mid = 0.5 * (local_[a] + local_[b]);
    const Eigen::Vector3d axis = (local_[b] - local_[a]).normalized();
    Eigen::Vector3d from = *start - mid;
    from -= axis * axis.dot(from);
    if (!(from.squaredNorm() > 0.0)) return false;
    from.normalize();
    // The ball rolls over the edge away from the old triangle: rotation about `axis` that
    // first moves `from` towards the side opposite to `o`.
    Eigen::Vector3d towards_o = local_[o] - mid;
    towards_o -= axis * axis.dot(towards_o);
    const double sign = from.cross(-towards_o).dot(axis) >= 0.0 ? 1.0 : -1.0;

    if (front_position >= ahead_begin_ && front_position < ahead_end_) {
      neighbors_.clear();
      for (std::size_t k = ahead_offsets_[front_position - ahead_begin_]; k < ahead_offsets_[front_position - ahead_begin_ + 1]; ++k)
        neighbors_.emplace_back(ahead_index_[k], 0.0);
    } else {
      gather(a, mid, 2.0 * radius_);
    }
    candidates_.clear();
    for (const Neighbor& nb : neighbors_) {
      const int p = int(nb.index);
      if (p == a || p == b || p == o || skip_[p] || inner(p) || (other_sheet(a, p) && other_sheet(b, p))) continue;
      // The new triangle runs b -> a -> p, so the shared edge is traversed the other way.
      const std::optional<Eigen::Vector3d> n = triangle_normal(b, a, p);
      if (!n || n->dot(normals_[a] + normals_[b] + normals_[p]) <= 0.0) continue;
      const std::optional<Eigen::Vector3d> center = ball_center(b, a, p);
      if (!center) continue;
      Eigen::Vector3d to = *center - mid;
      to -= axis * axis.dot(to);
      double angle = std::atan2(sign * from.cross(to).dot(axis), from.dot(to));
      if (angle < -1e-7) angle += 2.0 * std::numbers::pi;  // rounding around 0 stays at 0 (co-circular points)
      candidates_.push_back(PivotCandidate{std::max(angle, 0.0), p, *center});
    }
    std::sort(candidates_.begin(), candidates_.end(),
              [](const PivotCandidate& x, const PivotCandidate& y) { return x.angle < y.angle || (x.angle == y.angle && x.point < y.point); });
    for (const PivotCandidate& c : candidates_) {
      if (!ball_empty(c.center, a, b, c.point, neighbors_)) continue;
      // The first point the ball hits decides: if it cannot take a triangle the edge is a
      // boundary (trying farther points would let the ball pass through this one).
      const int p = c.point;
      const std::optional<Eigen::Vector3d> n = triangle_normal(b, a, p);
      if (!n || !normals_agree(*n, a, b, p)) return false;
      if (!edge_fits(a, p) || !edge_fits(p, b)) return false;
      add_triangle(b, a, p);
      return true;
    }
    return false;
  }

  void advance_front() {
    std::size_t processed = 0;
    while (front_head_ < front_.size()) {
      // Without the precomputed lists (passes after the first) the tree answers for each pivot.
      if (!covered_by_near_lists() && front_head_ >= ahead_end_) look_ahead();
      const std::size_t position = front_head_;
      const int e = front_[front_head_++];
      if (edges_[e].state != EdgeState::Front) continue;
      const Edge edge = edges_[e];
      if (!pivot(edge, position)) {
        // pivot() made no triangle, so edges_ did not move and `e` is still this edge.
        edges_[e].state = EdgeState::Boundary;
      }
      if ((++processed & 4095) == 0) tick();
    }
    front_.clear();
    front_head_ = 0;
    ahead_begin_ = ahead_end_ = 0;
  }

  // gather() for a pivot at the current radius takes the precomputed neighbour lists.
  bool covered_by_near_lists() const { return !near_offsets_.empty() && 3.0 * radius_ <= near_radius_ * (1.0 + 1e-12); }

  const KdTree& tree_;
  std::vector<std::size_t> near_offsets_;   // precompute_neighbours(): CSR rows per point
  std::vector<std::uint32_t> near_index_;   // their points, nearest first
  double near_radius_ = 0.0;
  std::vector<Eigen::Vector3d> local_;    // positions minus origin_
  std::vector<Eigen::Vector3d> normals_;  // unit (zero where undefined)
  std::vector<std::uint8_t> skip_;        // duplicates and points without a usable normal
  Eigen::Vector3d origin_;
  Rules rules_;
  detail::ProgressReporter& reporter_;

  double radius_ = 0.0, squared_radius_ = 0.0;
  double near_plane_ = 0.0;  // half the smallest radius, cloud units
  double pass_begin_ = 0.0, pass_span_ = 1.0;
  std::vector<Edge> edges_;
  std::vector<int> head_;          // first edge of each vertex, -1 if none
  std::vector<int> open_;          // edges with one triangle (front or boundary) at each vertex
  std::vector<std::uint8_t> used_;  // vertex belongs to a triangle
  std::size_t used_count_ = 0;
  std::vector<int> front_;
  std::size_t front_head_ = 0;
  std::vector<Triangle> triangles_;
  std::vector<Neighbor> neighbors_;
  // look_ahead(): the points within 2 radius_ of the midpoints of front_[ahead_begin_, ahead_end_).
  std::size_t ahead_begin_ = 0, ahead_end_ = 0;
  std::vector<std::size_t> ahead_offsets_;
  std::vector<std::uint32_t> ahead_index_;
  std::vector<std::vector<std::uint32_t>> ahead_chunks_;
  std::vector<PivotCandidate> candidates_;
  std::vector<int> seed_candidates_;
};

}  // namespace

const FieldTable<BallPivotParams>& BallPivotParams::fields() {
  static const FieldTable<BallPivotParams> table = [] {
    using P = BallPivotParams;
    FieldTable<P> t;
    // Two lists rather than one list of lengths: a parameter value holds one length, not a list.
    t.numbers("radii", &P::radii, "Ball radii (default: radii_in_spacings x mean spacing)")
        .unit("cloud units")
        .positive()
        .meta("R1,R2,...")
        .when([](const P& p) { return !p.radii.empty(); });
    t.numbers("radii_in_spacings", &P::radii_in_spacings, "Ball radii when radii are not given")
        .unit("mean spacings")
        .positive()
        .when([](const P& p) { return p.radii.empty(); });
    t.number("max_normal_angle_deg", &P::max_normal_angle_deg, "Largest angle between a triangle and each vertex normal")
        .unit("degrees")
        .range(0, 180, true, false);
    t.number("max_mean_normal_angle_deg", &P::max_mean_normal_angle_deg, "Largest angle between a triangle and its mean vertex normal")
        .unit("degrees")
        .range(0, 180, true, false);
    t.number("max_hole_perimeter_in_spacings", &P::max_hole_perimeter_in_spacings, "Close holes up to this perimeter (fill_holes, every interpolating method); 0: none")
        .unit("local spacings")
        .non_negative();
    return t;
  }();
  return table;
}

void BallPivotParams::validate() const {
  const BallPivotParams& params = *this;
  for (const double r : params.radii)
    if (!(r > 0.0 && std::isfinite(r)))
      throw UsageError(fmt::format("reconstruct_ball_pivoting: radii must be > 0 and finite, got {}", r));
  if (params.radii.empty()) {
    if (params.radii_in_spacings.empty())
      throw UsageError("reconstruct_ball_pivoting: radii and radii_in_spacings are both empty; give at least one radius");
    for (const double r : params.radii_in_spacings)
      if (!(r > 0.0 && std::isfinite(r)))
        throw UsageError(fmt::format("reconstruct_ball_pivoting: radii_in_spacings must be > 0 and finite, got {}", r));
  }
  if (!(params.max_normal_angle_deg > 0.0 && params.max_normal_angle_deg <= 180.0))
    throw UsageError(fmt::format("reconstruct_ball_pivoting: max_normal_angle_deg must be in (0, 180], got {}",
                                 params.max_normal_angle_deg));
  if (!(params.max_mean_normal_angle_deg > 0.0 && params.max_mean_normal_angle_deg <= 180.0))
    throw UsageError(fmt::format("reconstruct_ball_pivoting: max_mean_normal_angle_deg must be in (0, 180], got {}",
                                 params.max_mean_normal_angle_deg));
  if (!(params.max_hole_perimeter_in_spacings >= 0.0) || !std::isfinite(params.max_hole_perimeter_in_spacings))
    throw UsageError(fmt::format("reconstruct_ball_pivoting: max_hole_perimeter_in_spacings must be finite and >= 0 (0: off), got {}",
                                 params.max_hole_perimeter_in_spacings));
  fields().validate(*this, "reconstruct_ball_pivoting");
}

ReconstructionResult reconstruct_ball_pivoting(const PointCloud& cloud, const BallPivotParams& params, const KdTree* tree,
                                               const ProgressCallback& progress) {
  const auto t_start = std::chrono::steady_clock::now();
  const std::size_t n = cloud.size();
  if (n < 3) throw UsageError(fmt::format("reconstruct_ball_pivoting: needs at least 3 points, got {}", n));
  if (n > std::size_t(std::numeric_limits<int>::max() / 4))
    throw UsageError(fmt::format("reconstruct_ball_pivoting: at most {} points, got {}", std::numeric_limits<int>::max() / 4, n));
  if (!cloud.has_normals())
    throw UsageError("reconstruct_ball_pivoting: the cloud has no normals; ball pivoting needs oriented normals "
                     "(estimate and orient them first)");
  if (cloud.normals.size() != n)
    throw UsageError(fmt::format("reconstruct_ball_pivoting: the cloud has {} normals for {} points", cloud.normals.size(), n));
  params.validate();
  if (tree != nullptr && tree->size() != n)
    throw UsageError(fmt::format("reconstruct_ball_pivoting: the kd-tree holds {} points but the cloud has {}", tree->size(), n));
  for (std::size_t i = 0; i < n; ++i)
    if (!cloud.positions[i].allFinite())
      throw InputError(fmt::format("reconstruct_ball_pivoting: point {} has a non-finite coordinate", i));

  std::optional<KdTree> own_tree;
  if (tree == nullptr) tree = &own_tree.emplace(cloud.positions);
  detail::ProgressReporter reporter(progress, 0.0, 1.0, n);

  ReconstructionResult result;
  result.mean_spacing = mean_spacing(*tree);
  if (!(result.mean_spacing > 0.0))
    throw ComputeError(fmt::format("reconstruct_ball_pivoting: all {} points coincide; there is no surface", n));
  std::vector<double> radii = params.radii;
  if (radii.empty())
    for (const double s : params.radii_in_spacings) radii.push_back(s * result.mean_spacing);
  std::sort(radii.begin(), radii.end());
  radii.erase(std::unique(radii.begin(), radii.end()), radii.end());

  // Local coordinates keep georeferenced clouds precise in the circumcentre computations.
  const Eigen::Vector3d origin = bounding_box(cloud.positions).center();
  std::vector<Eigen::Vector3d> local(n), normals(n);
  // Skipped: exact copies (by sorting, so a stack of copies stays cheap), points without a
  // usable normal, and near-duplicates of an earlier point that has one.
  std::vector<std::uint8_t> skip = detail::later_exact_copies(cloud.positions);
  result.stats.duplicate_points = std::size_t(std::count(skip.begin(), skip.end(), std::uint8_t{1}));
  const auto usable_normal = [&](std::size_t i) {
    const double len = cloud.normals[i].norm();
    return len > 0.0 && std::isfinite(len);
  };
  const double duplicate_distance = kDuplicateInSpacings * result.mean_spacing;
  tbb::enumerable_thread_specific<std::vector<Neighbor>> buffers;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 1024), [&](const tbb::blocked_range<std::size_t>& r) {
    std::vector<Neighbor>& nbs = buffers.local();
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      local[i] = cloud.positions[i] - origin;
      normals[i] = usable_normal(i) ? Eigen::Vector3d(cloud.normals[i] / cloud.normals[i].norm()) : Eigen::Vector3d::Zero();
      if (skip[i]) continue;  // an exact copy: its first is decided below
      if (normals[i].isZero()) {
        skip[i] = 1;
        continue;
      }
      tree->radius(cloud.positions[i], duplicate_distance, nbs);
      for (const Neighbor& nb : nbs)
        if (nb.index < i && cloud.positions[nb.index] != cloud.positions[i] && usable_normal(nb.index)) skip[i] = 1;
    }
  });

  Rules rules;
  rules.cos_vertex = std::cos(params.max_normal_angle_deg * std::numbers::pi / 180.0);
  rules.cos_mean = std::cos(params.max_mean_normal_angle_deg * std::numbers::pi / 180.0);
  rules.cos_opposite = std::cos(kOppositeNormalsDeg * std::numbers::pi / 180.0);
  rules.sheet_offset = kSheetOffsetInSpacings * result.mean_spacing;
  BallPivoter pivoter(*tree, std::move(local), std::move(normals), std::move(skip), origin, rules, reporter);
  // Lists of about 30 points each at the default 1.5 spacings; a first radius beyond
  // kPrecomputeInSpacings would make them large (they grow with its square), so the tree
  // answers instead.
  if (radii.front() <= kPrecomputeInSpacings * result.mean_spacing) pivoter.precompute_neighbours(radii.front());
  for (std::size_t pass = 0; pass < radii.size(); ++pass) pivoter.run_pass(radii[pass], pass, radii.size());
  reporter.report(1.0);
  reporter.throw_if_cancelled();

  result.mesh = TriangleMesh{cloud, pivoter.take_triangles(), {}};
  // Small holes (where the ball could not rest on a hole's corners, typically at a sharp edge):
  // the hole filler every reconstruction shares.
  result.stats.candidate_triangles = result.mesh.triangles.size();
  // fill_holes() less its own topology passes: one before (which is the result when nothing
  // changes) and one after.
  const HoleFillParams fill_params{params.max_hole_perimeter_in_spacings};
  fill_params.validate();
  result.topology = analyze_topology(result.mesh);
  HoleFillStats filled;
  if (!result.topology.boundary_loops.empty() && fill_params.max_perimeter_in_spacings > 0.0) {
    filled = detail::fill_mesh_holes(result.mesh, fill_params);
    if (filled.triangles_added > 0 || filled.triangles_removed > 0) result.topology = analyze_topology(result.mesh);
  }
  result.unused_points = result.topology.isolated_vertices;
  ReconstructionStats& stats = result.stats;
  stats.input_points = n;
  stats.holes_filled = filled.holes_filled;
  stats.fill_triangles = filled.triangles_added;
  stats.counts = {{"fill_triangles_removed", filled.triangles_removed}};
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  return result;
}

}  // namespace pointsurf
