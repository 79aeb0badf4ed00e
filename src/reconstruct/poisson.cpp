// SPDX-License-Identifier: GPL-3.0-or-later
// Screened Poisson reconstruction: the samples into a unit cube, the system solved on the
// octree (detail/poisson_solver), its level set extracted (detail/iso_surface), then the
// per-vertex density, trimming, and the nearest sample's colour and fields.
#include "pointsurf/reconstruct/poisson.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "pointsurf/core/error.h"
#include "pointsurf/core/mesh_topology.h"
#include "reconstruct/detail/density_trim.h"
#include "reconstruct/detail/iso_surface.h"
#include "reconstruct/detail/poisson_solver.h"

namespace pointsurf {
namespace {

constexpr int kMaxDepth = 16;
constexpr int kMinAutoDepth = 6, kMaxAutoDepth = 10;

// The shares of reconstruct_poisson's time until the octree is known (bench/notes/progress.md):
// the octree and the solve, the extraction, then the density, the colours and fields, the trim
// and the topology. Then PoissonCost decides them.
constexpr double kSolveEnd = 0.45, kExtractionEnd = 0.85;

// reconstruct_poisson's time predicted from its octree, in seconds on 2 cores (fitted on quiet
// runs of 150k-500k samples of 10 meshes, within 0.8-1.3x per part: bench/notes/progress.md):
// the solver follows its nodes, samples and the finest levels' size, the rest the output's triangles,
// which the extraction makes at the finest level the samples reach, over the whole surface. A
// level that covers the surface holds about 1 / kTrianglesPerNode times the triangles a surface
// meshed at that level has, and each finer level 4 times as many: the larger of the finest
// level's nodes and 4 times the level above's estimates them within 0.9-1.08x on those 10 and a
// noisy scan with outliers (coarser levels' nodes fill a thicker shell where the samples are
// noisy: 4.6x there).
struct PoissonCost {
  static constexpr double kPerNode = 1.1e-6, kSolverPerTriangle = 0.7e-6, kPerSample = 2.0e-6;  // the solver
  // the extraction (below): its seeds, the rest per triangle and the following's part of it
  static constexpr double kPerCoarseLeaf = 2.0e-6, kRestPerTriangle = 1.0e-6, kFollowPerTriangle = 1.7e-6;
  static constexpr double kFollowedCover = 0.5, kCellsPerSeededTriangle = 0.5;
  static constexpr double kDensityPerTriangle = 0.5e-6;
  static constexpr double kTrianglesPerNode = 0.215;
  double solver = 0.0, seeds = 0.0, extraction = 0.0, density = 0.0, triangles = 0.0, cells = 0.0;

  PoissonCost(const std::vector<std::size_t>& nodes_per_level, std::size_t samples, int full_depth) {
    std::size_t nodes = 0;
    int finest = 0;
    for (std::size_t l = 0; l < nodes_per_level.size(); ++l) {
      nodes += nodes_per_level[l];
      if (nodes_per_level[l] > 0) finest = int(l) + 1;
    }
    double shell = 0.0;
    for (int l = std::max(finest - 1, 1); l <= finest; ++l)
      shell = std::max(shell, double(nodes_per_level[std::size_t(l - 1)]) * std::pow(4.0, finest - l));
    triangles = kTrianglesPerNode * shell;
    // The extraction's seeds come from the leaves coarser than the finest level (a level's
    // nodes less its children's parents). Where the finest level covers little of the surface
    // (its nodes against 4 times the level above's), they find most cells and the rest costs
    // 1 us a triangle; where it covers it, the following finds them: 2.1-3.5 us. The following
    // processes about the finest level's nodes in the second case, half a cell a triangle in
    // the first (0.84-1.0x on 4 scans, 2 of them noisy).
    double coarse = 0.0;
    for (int l = std::max(full_depth, 1); l < finest; ++l)
      coarse += std::max(0.0, double(nodes_per_level[std::size_t(l - 1)]) - double(nodes_per_level[std::size_t(l)]) / 8.0);
    const double cover = finest > 1 ? double(nodes_per_level[std::size_t(finest - 1)]) / std::max(1.0, 4.0 * double(nodes_per_level[std::size_t(finest - 2)])) : 1.0;
    solver = kPerNode * double(nodes) + kSolverPerTriangle * triangles + kPerSample * double(samples);
    seeds = kPerCoarseLeaf * coarse;
    const double followed = std::min(1.0, cover / kFollowedCover);
    extraction = seeds + triangles * (kRestPerTriangle + kFollowPerTriangle * followed);
    cells = followed * double(finest > 0 ? nodes_per_level[std::size_t(finest - 1)] : 0) +
            (1.0 - followed) * kCellsPerSeededTriangle * triangles;
    density = kDensityPerTriangle * triangles;
  }
  double total() const { return solver + extraction + density; }
};

// Removes the pieces (vertex-connected components) whose sample support per area lies more than
// `gap` depth units (factors of 4) below the largest piece's, and the vertices they leave unused.
// A piece's support: the samples whose nearest vertex is one of its own (`support[v]`: the
// samples within reach that vertex is the nearest to); an outlier bubble holds only the few
// outliers that raised it. Returns the pieces and triangles removed.
std::pair<std::size_t, std::size_t> remove_unsupported_pieces(TriangleMesh& mesh, const std::vector<std::uint32_t>& support, double gap) {
  const std::size_t nv = mesh.vertex_count(), nf = mesh.triangle_count();
  if (gap <= 0.0 || nf == 0) return {0, 0};
  std::vector<std::uint32_t> parent(nv);
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](std::uint32_t a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
  };
  for (const Triangle& t : mesh.triangles)
    for (int k = 1; k < 3; ++k) {
      const std::uint32_t a = find(std::uint32_t(t[0])), b = find(std::uint32_t(t[k]));
      if (a != b) parent[std::max(a, b)] = std::min(a, b);  // the smaller index: same roots for any thread count
    }
  std::vector<std::size_t> faces(nv, 0);
  std::vector<double> area(nv, 0.0);
  for (const Triangle& t : mesh.triangles) {
    const std::uint32_t r = find(std::uint32_t(t[0]));
    ++faces[r];
    area[r] += 0.5 * (mesh.vertices.positions[t[1]] - mesh.vertices.positions[t[0]]).cross(mesh.vertices.positions[t[2]] - mesh.vertices.positions[t[0]]).norm();
  }
  const std::uint32_t largest = std::uint32_t(std::max_element(faces.begin(), faces.end()) - faces.begin());
  std::vector<double> samples(nv, 0.0);
  for (std::uint32_t v = 0; v < nv; ++v) samples[find(v)] += support[v];
  // per area, relative to the largest piece's: below 4^-gap the piece goes
  const double floor = std::pow(4.0, -gap) * samples[largest] / std::max(area[largest], std::numeric_limits<double>::min());
  std::vector<char> gone(nv, 0);
  for (std::uint32_t v = 0; v < nv; ++v)
    gone[v] = parent[v] == v && faces[v] > 0 && v != largest && samples[v] < floor * area[v];
  const std::size_t pieces = std::size_t(std::count(gone.begin(), gone.end(), 1));
  if (pieces == 0) return {0, 0};
  std::vector<Triangle> kept;
  std::vector<std::size_t> kept_faces;
  std::vector<std::int64_t> remap(nv, -1);
  std::vector<std::size_t> vertices;
  for (std::size_t f = 0; f < nf; ++f) {
    Triangle t = mesh.triangles[f];
    if (gone[find(std::uint32_t(t[0]))]) continue;
    for (int k = 0; k < 3; ++k) {
      std::int64_t& m = remap[std::size_t(t[k])];
      if (m < 0) m = std::int64_t(vertices.size()), vertices.push_back(std::size_t(t[k]));
      t[k] = int(m);
    }
    kept.push_back(t);
    kept_faces.push_back(f);
  }
  FieldSet face_fields;
  for (const ScalarField& f : mesh.face_fields) {
    ScalarField& out = face_fields.add(f.name, kept_faces.size(), f.type);
    for (std::size_t i = 0; i < kept_faces.size(); ++i) out.values[i] = f.values[kept_faces[i]];
  }
  const std::size_t removed = nf - kept.size();
  mesh = TriangleMesh{mesh.vertices.select(vertices), std::move(kept), std::move(face_fields)};
  return {pieces, removed};
}

}  // namespace

const EnumNames<PoissonBoundary>& poisson_boundary_names() {
  static const EnumNames<PoissonBoundary> names{{{PoissonBoundary::Neumann, "neumann"}, {PoissonBoundary::Dirichlet, "dirichlet"}}};
  return names;
}

const FieldTable<PoissonParams>& PoissonParams::fields() {
  static const FieldTable<PoissonParams> table = [] {
    using P = PoissonParams;
    FieldTable<P> t;
    t.integer("depth", &P::depth,
              "Finest octree level (2^depth cells across 1.1x the largest extent); 0: the level whose cell is nearest the mean spacing, 6..10")
        .range(0, 16);
    t.integer("full_depth", &P::full_depth, "Octree levels 1..full_depth are complete grids").range(1, 16);
    t.number("samples_per_node", &P::samples_per_node, "Density output: the depth at which a node holds this many samples").unit("samples").positive();
    t.number("point_weight", &P::point_weight, "Screening weight alpha: pull of the surface to the samples; 0: plain Poisson").non_negative();
    t.choice("boundary_condition", &P::boundary, poisson_boundary_names(),
             "Function on the bounding cube: zero slope (neumann) or zero value (dirichlet)");
    t.boolean("weight_by_normal_length", &P::weight_by_normal_length, "Weight each point by its normal's length").was("confidence");
    t.number("trim_depth", &P::trim_depth, "Remove the surface where the density is below this depth (PoissonRecon --trim, e.g. 7 at depth 10); 0: off")
        .unit("depth")
        .range(0, 16);
    t.number("island_area_ratio", &P::island_area_ratio, "After trimming, remove pieces smaller than this share of the largest's area")
        .unit("share of area")
        .range(0, 1);
    t.number("unsupported_piece_gap", &P::unsupported_piece_gap,
             "Remove pieces whose samples per area are this far below the main surface's (outlier bubbles; each unit 4x fewer); 0: keep all")
        .unit("depth")
        .range(0, 16);
    t.integer("root_refinement_steps", &P::root_refinement_steps,
              "Vertex placement per edge crossing: 0 linear, 1 quadratic through the edge midpoint (exact here), more: further false-position steps")
        .range(0, 20);
    t.integer("max_iterations", &P::max_iterations, "Conjugate-gradient iterations per sparse level at most").at_least(1);
    t.number("tolerance", &P::tolerance, "Relative residual reduction at which a level's solver stops").range(0, 1, true, true).internal();
    return t;
  }();
  return table;
}

void PoissonParams::validate() const {
  if (depth != 0 && (depth < 2 || depth > kMaxDepth))
    throw UsageError(fmt::format("reconstruct_poisson: depth must be 0 (from the data) or in [2, {}], got {}", kMaxDepth, depth));
  if (full_depth < 1 || full_depth > kMaxDepth)
    throw UsageError(fmt::format("reconstruct_poisson: full_depth must be in [1, {}], got {}", kMaxDepth, full_depth));
  if (!(samples_per_node > 0.0 && std::isfinite(samples_per_node)))
    throw UsageError(fmt::format("reconstruct_poisson: samples_per_node must be > 0 and finite, got {}", samples_per_node));
  if (!(point_weight >= 0.0 && std::isfinite(point_weight)))
    throw UsageError(fmt::format("reconstruct_poisson: point_weight must be >= 0 and finite, got {}", point_weight));
  if (!(trim_depth >= 0.0 && trim_depth <= kMaxDepth))
    throw UsageError(fmt::format("reconstruct_poisson: trim_depth must be in [0, {}] (0: off), got {}", kMaxDepth, trim_depth));
  if (!(island_area_ratio >= 0.0 && island_area_ratio <= 1.0))
    throw UsageError(fmt::format("reconstruct_poisson: island_area_ratio must be in [0, 1], got {}", island_area_ratio));
  if (!(unsupported_piece_gap >= 0.0 && unsupported_piece_gap <= kMaxDepth))
    throw UsageError(fmt::format("reconstruct_poisson: unsupported_piece_gap must be in [0, {}] (0: keep all), got {}", kMaxDepth, unsupported_piece_gap));
  if (root_refinement_steps < 0 || root_refinement_steps > 20)
    throw UsageError(fmt::format("reconstruct_poisson: root_refinement_steps must be in [0, 20], got {}", root_refinement_steps));
  if (max_iterations < 1) throw UsageError(fmt::format("reconstruct_poisson: max_iterations must be >= 1, got {}", max_iterations));
  if (!(tolerance > 0.0 && tolerance < 1.0))
    throw UsageError(fmt::format("reconstruct_poisson: tolerance must be in (0, 1), got {}", tolerance));
  fields().validate(*this, "reconstruct_poisson");
}

PoissonResult reconstruct_poisson(const PointCloud& cloud, const PoissonParams& params, const KdTree* tree, const ProgressCallback& progress) {
  const auto start = std::chrono::steady_clock::now();
  params.validate();
  const std::size_t n = cloud.size();
  if (!cloud.has_normals()) throw UsageError("reconstruct_poisson: the cloud has no normals (estimate and orient them first)");
  cloud.validate();
  if (tree != nullptr && tree->size() != n)
    throw UsageError(fmt::format("reconstruct_poisson: the kd-tree holds {} points but the cloud has {}", tree->size(), n));
  for (std::size_t i = 0; i < n; ++i)
    if (!cloud.positions[i].allFinite()) throw InputError(fmt::format("reconstruct_poisson: point {} has a non-finite coordinate", i));

  PoissonResult result;
  result.stats.input_points = n;
  std::vector<std::size_t> usable;
  usable.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vector3d& v = cloud.normals[i];
    if (v.allFinite() && v.squaredNorm() > 0.0) usable.push_back(i);
  }
  result.skipped_normals = n - usable.size();
  if (usable.size() < 4)
    throw InputError(fmt::format("reconstruct_poisson: {} of {} points have a usable normal (non-zero, finite); at least 4 are needed",
                                 usable.size(), n));
  BoundingBox box;
  for (const std::size_t i : usable) box.extend(cloud.positions[i]);
  const double extent = box.extent().maxCoeff();
  if (!(extent > 0.0)) throw InputError(fmt::format("reconstruct_poisson: all {} usable points coincide", usable.size()));

  std::optional<KdTree> own_tree;
  if (tree == nullptr) tree = &own_tree.emplace(cloud.positions);
  result.mean_spacing = mean_spacing(*tree);
  // The lattice lives in coordinates relative to the box's centre: the solver, the extractor's
  // secant steps and the density are evaluated there, so that a 1e6 m offset costs no precision;
  // the vertices move back to the cloud's frame at the end.
  const Vector3d centre = box.center();
  detail::IsoLattice lattice;
  lattice.size = 1.1 * extent;
  lattice.origin = Vector3d::Constant(-0.5 * lattice.size);
  int depth = params.depth;
  if (depth == 0) {
    const double ratio = result.mean_spacing > 0.0 ? lattice.size / result.mean_spacing : 1.0;
    depth = std::clamp(int(std::lround(std::log2(ratio))), kMinAutoDepth, kMaxAutoDepth);
  }
  lattice.depth = depth;
  result.depth = depth;

  std::vector<detail::PoissonSample> samples(usable.size());
  tbb::parallel_for(std::size_t(0), usable.size(), [&](std::size_t k) {
    const std::size_t i = usable[k];
    samples[k].position = ((cloud.positions[i] - centre) / lattice.size).array() + 0.5;
    const Vector3d& v = cloud.normals[i];
    samples[k].normal = params.weight_by_normal_length ? v : v.normalized();
  });
  detail::PoissonSystemParams sys;
  sys.depth = depth;
  sys.full_depth = std::min(params.full_depth, depth);
  sys.kernel_depth = std::max(1, depth - 2);
  sys.point_weight = params.point_weight;
  sys.samples_per_node = params.samples_per_node;
  sys.dirichlet = params.boundary == PoissonBoundary::Dirichlet;
  sys.max_iterations = params.max_iterations;
  sys.tolerance = params.tolerance;
  // the split of the progress follows the cost predicted once the octree is known
  MovableProgress solver_part(progress, 0.0, kSolveEnd);
  const std::size_t sample_count = samples.size();
  double extraction_end = kExtractionEnd, expected_cells = 0.0, seed_share = 0.0;
  const auto on_octree = [&](const std::vector<std::size_t>& nodes) {
    const PoissonCost cost(nodes, sample_count, sys.full_depth);
    if (!(cost.total() > 0.0)) return;
    solver_part.move_end(cost.solver / cost.total());
    extraction_end = std::max(solver_part.end(), (cost.solver + cost.extraction) / cost.total());
    report_forecast(progress, {cost.total(), cost.triangles});
    expected_cells = cost.cells;
    seed_share = cost.extraction > 0.0 ? cost.seeds / cost.extraction : 0.0;
  };
  const detail::PoissonFunction function(std::move(samples), sys, lattice, solver_part.callback(), on_octree);
  result.iso_value = function.iso_value();
  result.peak_bytes = function.peak_bytes();
  result.nodes_per_level.assign(std::size_t(depth + 1), 0);
  result.iterations_per_level.assign(std::size_t(depth + 1), 0);
  result.residual_per_level.assign(std::size_t(depth + 1), 0.0);
  for (const detail::PoissonLevelReport& r : function.levels()) {
    result.nodes_per_level[std::size_t(r.level)] = r.nodes;
    result.iterations_per_level[std::size_t(r.level)] = r.iterations;
    result.residual_per_level[std::size_t(r.level)] = r.initial_residual > 0.0 ? r.final_residual / r.initial_residual : 0.0;
  }

  detail::IsoSurfaceParams iso;
  iso.iso_value = function.iso_value();
  iso.inside_positive = false;  // the function grows along the (outward) normals
  iso.root_refinement_steps = params.root_refinement_steps;
  iso.expected_cells = expected_cells;
  iso.seed_share = seed_share;
  // Meshed at the finest level the samples reached, as PoissonRecon meshes its leaves: a depth
  // beyond what the sampling supports adds no detail, only triangles.
  lattice.depth = function.finest_level();
  detail::IsoSurface surface = detail::extract_iso_surface(function, lattice, iso, sub_progress(progress, solver_part.end(), extraction_end, "extraction"));

  TriangleMesh& mesh = result.mesh;
  mesh.vertices.positions = std::move(surface.vertices);
  mesh.vertices.normals = std::move(surface.normals);
  mesh.triangles.resize(surface.triangles.size());
  for (std::size_t t = 0; t < surface.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) mesh.triangles[t][k] = static_cast<int>(surface.triangles[t][std::size_t(k)]);
  const std::size_t nv = mesh.vertices.positions.size();
  report_phase(progress, "density");
  ScalarField& density = mesh.vertices.fields.add("density", nv, ScalarType::Float32);
  std::vector<std::uint32_t> nearest(nv);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv), [&](const tbb::blocked_range<std::size_t>& range) {
    std::vector<Neighbor> hit;
    for (std::size_t v = range.begin(); v != range.end(); ++v) {
      density.values[v] = function.density_depth(mesh.vertices.positions[v]);  // centred frame
      mesh.vertices.positions[v] += centre;
      tree->knn(mesh.vertices.positions[v], 1, hit);
      nearest[v] = hit.empty() ? 0 : hit.front().index;
    }
  });
  if (progress && !progress(extraction_end + 0.4 * (1.0 - extraction_end))) throw CancelledError("reconstruct_poisson: cancelled");
  if (cloud.has_colors()) {
    mesh.vertices.colors.resize(nv);
    for (std::size_t v = 0; v < nv; ++v) mesh.vertices.colors[v] = cloud.colors[nearest[v]];
  }
  for (const ScalarField& field : cloud.fields) {
    if (field.name == "density") continue;
    ScalarField& out = mesh.vertices.fields.add(field.name, nv, field.type);
    for (std::size_t v = 0; v < nv; ++v) out.values[v] = field.values[nearest[v]];
  }

  if (params.unsupported_piece_gap > 0.0 && nv > 0) {
    // each sample supports its nearest vertex within two finest cells
    const double reach = 2.0 * lattice.size / double(1 << lattice.depth);
    const KdTree vertices(mesh.vertices.positions);
    std::vector<std::uint32_t> to(usable.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, usable.size()), [&](const tbb::blocked_range<std::size_t>& range) {
      std::vector<Neighbor> hit;
      for (std::size_t k = range.begin(); k != range.end(); ++k) {
        vertices.knn(cloud.positions[usable[k]], 1, hit);
        to[k] = !hit.empty() && hit.front().squared_distance <= reach * reach ? hit.front().index : std::uint32_t(nv);
      }
    });
    std::vector<std::uint32_t> support(nv, 0);
    for (const std::uint32_t v : to)
      if (v < nv) ++support[v];
    std::tie(result.unsupported_pieces, result.unsupported_triangles) = remove_unsupported_pieces(mesh, support, params.unsupported_piece_gap);
  }

  detail::TrimResult trim;
  report_phase(progress, "trim and topology");
  if (progress && !progress(extraction_end + 0.8 * (1.0 - extraction_end))) throw CancelledError("reconstruct_poisson: cancelled");
  if (params.trim_depth > 0.0) {
    trim = detail::trim_by_vertex_field(mesh, "density", params.trim_depth, params.island_area_ratio);
    result.trimmed_triangles = trim.removed_triangles;
  }

  result.topology = analyze_topology(mesh);
  result.stats.counts = {{"skipped_normals", result.skipped_normals}, {"depth", std::size_t(depth)},
                         {"finest_level", std::size_t(lattice.depth)},
                         {"finest_nodes", result.nodes_per_level[std::size_t(lattice.depth)]}, {"trimmed_triangles", result.trimmed_triangles},
                         {"trim_cut_triangles", trim.cut_triangles}, {"trim_removed_islands", trim.removed_islands},
                         {"unsupported_pieces", result.unsupported_pieces}, {"unsupported_triangles", result.unsupported_triangles}};
  result.stats.figures = {{"iso_value", result.iso_value}, {"peak_megabytes", double(result.peak_bytes) / 1e6}};
  result.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (progress && !progress(1.0)) throw CancelledError("reconstruct_poisson: cancelled");
  return result;
}

}  // namespace pointsurf
