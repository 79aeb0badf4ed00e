// SPDX-License-Identifier: GPL-3.0-or-later
// The evaluate stage (signed deviation of a reference from a mesh, its statistics, Chamfer and
// Hausdorff, the mesh's quality) and the quality stage (the quality block alone).
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <span>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_sort.h>

#include "pipeline/detail/declare.h"
#include "pipeline/detail/stage_util.h"
#include "pointsurf/core/error.h"
#include "pointsurf/evaluate/align_to_mesh.h"
#include "pointsurf/evaluate/deviation_stats.h"
#include "pointsurf/evaluate/mesh_distance.h"
#include "pointsurf/evaluate/mesh_quality.h"
#include "pointsurf/evaluate/surface_distance.h"
#include "pointsurf/evaluate/triangle_bvh.h"
#include "pointsurf/pipeline/context.h"
#include "pointsurf/reconstruct/handles.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf::detail {
namespace {

// The deviation block, under `prefix` ("deviation/"): the same keys in every report.
void record_deviation(StageRecord& rec, const std::string& prefix, const DeviationStats& s) { rec.add(DeviationStats::results(), s, prefix); }

// The quality block: the same keys from the quality and the evaluate stage.
void record_quality(StageRecord& rec, const MeshQuality& q) { rec.add(MeshQuality::results(), q, "quality/"); }

// Chamfer and Hausdorff between the reference and the mesh, reported under distance/.
struct TwoWayDistance {
  double reference_to_mesh_mean = 0.0, reference_to_mesh_max = 0.0;
  double mesh_to_reference_mean = 0.0, mesh_to_reference_max = 0.0;
  double chamfer = 0.0, hausdorff = 0.0;
  std::size_t mesh_samples = 0;
};

const ResultTable<TwoWayDistance>& distance_results() {
  static const ResultTable<TwoWayDistance> table = [] {
    using D = TwoWayDistance;
    const std::string u = "cloud units";
    ResultTable<D> t;
    t.number("reference_to_mesh_mean", &D::reference_to_mesh_mean, "Mean unsigned distance, reference to mesh").with_unit(u).lower_is_better();
    t.number("reference_to_mesh_max", &D::reference_to_mesh_max, "Largest distance, reference to mesh").with_unit(u).lower_is_better();
    t.number("mesh_to_reference_mean", &D::mesh_to_reference_mean, "Mean distance, mesh samples to reference").with_unit(u).lower_is_better();
    t.number("mesh_to_reference_max", &D::mesh_to_reference_max, "Largest distance, mesh samples to reference").with_unit(u).lower_is_better();
    t.number("chamfer", &D::chamfer, "Chamfer distance: the mean of both means").with_unit(u).lower_is_better();
    t.number("hausdorff", &D::hausdorff, "Hausdorff distance: the larger of both maxima").with_unit(u).lower_is_better();
    t.count("mesh_samples", &D::mesh_samples, "Area-uniform samples of the mesh");
    return t;
  }();
  return table;
}

// What evaluate reports besides its blocks.
struct EvaluateTexts {
  std::string reference, sign, region_field;
};
const ResultTable<EvaluateTexts>& evaluate_text_results() {
  static const ResultTable<EvaluateTexts> table = [] {
    ResultTable<EvaluateTexts> t;
    t.text("reference", &EvaluateTexts::reference, "Tag of the reference measured");
    t.text("sign", &EvaluateTexts::sign, "How the deviation's sign was decided (normals, winding, unsigned)");
    return t;
  }();
  return table;
}

// The label field of the per-region deviations, when the reference has one.
const ResultTable<EvaluateTexts>& region_text_results() {
  static const ResultTable<EvaluateTexts> table = [] {
    ResultTable<EvaluateTexts> t;
    t.text("region_field", &EvaluateTexts::region_field, "The label field of the per-region deviations (segment or region when present)");
    return t;
  }();
  return table;
}

// What evaluate counts: the data measured, then each block's points as it is recorded.
struct EvaluateCounts {
  std::size_t reference_points = 0, mesh_triangles = 0, points_not_vertices = 0, regions = 0, mesh_samples = 0;
};
using CountTable = ResultTable<EvaluateCounts>;
const CountTable& size_counts() {
  static const CountTable table = [] {
    CountTable t;
    t.count("reference_points", &EvaluateCounts::reference_points, "Points of the reference measured");
    t.count("mesh_triangles", &EvaluateCounts::mesh_triangles, "Triangles of the mesh");
    return t;
  }();
  return table;
}
const CountTable& not_vertices_counts() {
  static const CountTable table = [] {
    CountTable t;
    t.count("points_not_vertices", &EvaluateCounts::points_not_vertices, "Reference points that are no vertex of the mesh");
    return t;
  }();
  return table;
}
const CountTable& region_counts() {
  static const CountTable table = [] {
    CountTable t;
    t.count("regions", &EvaluateCounts::regions, "Regions of the region field");
    return t;
  }();
  return table;
}
const CountTable& sample_counts() {
  static const CountTable table = [] {
    CountTable t;
    t.count("mesh_samples", &EvaluateCounts::mesh_samples, "Area-uniform samples of the mesh");
    return t;
  }();
  return table;
}

// Every metric evaluate and quality report, for their declarations.
std::vector<ResultSpec> quality_specs() { return prefixed(MeshQuality::results().specs(), "quality/"); }
std::vector<ResultSpec> evaluate_specs() {
  std::vector<ResultSpec> out = prefixed(mesh_alignment_results().specs(), "align/");
  for (const ResultSpec& s : evaluate_text_results().specs()) out.push_back(s);
  append(out, region_text_results().specs());
  for (const char* block : {"deviation/", "deviation_not_vertices/", "deviation_by_region/*/"})
    for (const ResultSpec& s : prefixed(DeviationStats::results().specs(), block)) out.push_back(s);
  for (const ResultSpec& s : prefixed(distance_results().specs(), "distance/")) out.push_back(s);
  for (const ResultSpec& s : quality_specs()) out.push_back(s);
  for (const CountTable* t : {&size_counts(), &not_vertices_counts(), &region_counts(), &sample_counts()}) append(out, counted(t->specs()));
  return out;
}

void quality_warnings(StageRecord& rec, const MeshQuality& q) {
  const MeshTopology& t = q.topology;
  if (t.non_manifold_edges > 0) rec.warnings.push_back(plural(t.non_manifold_edges, "non-manifold edge"));
  if (t.non_manifold_vertices > 0) rec.warnings.push_back(plural(t.non_manifold_vertices, "non-manifold vertex", "non-manifold vertices"));
  if (t.inconsistent_edges > 0) rec.warnings.push_back(plural(t.inconsistent_edges, "inconsistently oriented edge"));
  if (q.self_intersections > 0) rec.warnings.push_back(plural(q.self_intersections, "self-intersecting triangle pair"));
  if (q.degenerate_faces > 0) rec.warnings.push_back(plural(q.degenerate_faces, "degenerate face"));
  if (q.duplicate_faces > 0) rec.warnings.push_back(plural(q.duplicate_faces, "duplicate face"));
}

std::string quality_line(const MeshQuality& q) {
  const MeshTopology& t = q.topology;
  return fmt::format("{}, {}, {}, {} boundary loop{}, {} self-intersection{}, area {:.6g}{}", plural(t.triangles, "triangle"),
                     q.watertight ? "watertight" : q.closed ? "closed (not watertight)" : "open", plural(t.components, "component"),
                     t.boundary_loops.size(), t.boundary_loops.size() == 1 ? "" : "s", q.self_intersections, q.self_intersections == 1 ? "" : "s",
                     q.area, q.has_volume ? fmt::format(", volume {:.6g}", q.volume) : std::string());
}

TriangleMesh mesh_of(const DataItem& item, const std::string& tag) {
  if (item.mesh.triangles.empty())
    throw InputError(fmt::format("\"{}\" ({}) has no faces: a mesh is needed ({})", tag, plural(item.cloud().size(), "point"),
                                 item.cloud().empty() ? "it is empty" : "is it a point cloud?"));
  TriangleMesh mesh;
  mesh.vertices.positions = item.cloud().positions;
  mesh.triangles = item.mesh.triangles;
  check_measurable_mesh(mesh, fmt::format("mesh \"{}\"", tag));
  return mesh;
}

BoundingBox used_box(const TriangleMesh& mesh) {
  BoundingBox box;
  for (const Triangle& t : mesh.triangles)
    for (int c = 0; c < 3; ++c) box.extend(mesh.vertices.positions[static_cast<std::size_t>(t[c])]);
  return box;
}

double box_gap(const BoundingBox& a, const BoundingBox& b) {
  const Vector3d gap = (a.min - b.max).cwiseMax(b.min - a.max).cwiseMax(0.0);
  return gap.norm();
}

// Per point: whether it lies exactly at a vertex used by a triangle of `mesh` (sorted vertex
// positions searched in parallel; -0 equals +0, as a distance test would have it).
std::vector<char> at_used_vertex(const TriangleMesh& mesh, std::span<const Vector3d> points) {
  std::vector<char> is_used(mesh.vertices.positions.size(), 0);
  for (const Triangle& t : mesh.triangles)
    for (int c = 0; c < 3; ++c) is_used[static_cast<std::size_t>(t[c])] = 1;
  using Key = std::array<double, 3>;
  const auto key = [](const Vector3d& p) { return Key{p.x() + 0.0, p.y() + 0.0, p.z() + 0.0}; };
  std::vector<Key> used;
  for (std::size_t v = 0; v < is_used.size(); ++v)
    if (is_used[v]) used.push_back(key(mesh.vertices.positions[v]));
  tbb::parallel_sort(used.begin(), used.end());
  std::vector<char> out(points.size(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 4096), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) out[i] = std::binary_search(used.begin(), used.end(), key(points[i])) ? 1 : 0;
  });
  return out;
}

// The best fit of the reference onto the mesh, recorded under align/.
RigidTransform align_reference(StageRun& run, const TriangleMesh& mesh, const std::string& ref_tag) {
  const StageArgs& a = run.args;
  StageRecord& rec = run.record;
  MeshAlignParams p = read_params<MeshAlignParams>(a);
  const SurfaceDistanceParams sd = read_params<SurfaceDistanceParams>(a);  // the stage's samples and seed serve both
  p.samples = sd.samples;
  p.seed = sd.seed;
  p.max_distance = Length::cloud(p.max_distance.resolve(p.max_distance.in_spacings() ? run.context.mean_spacing(ref_tag) : 0.0));
  rec.set_used("align_max_distance_used", p.max_distance.value);
  const RegistrationResult r = align_to_mesh(run.context.item(ref_tag).cloud().positions, mesh, p, sub_progress(run.progress, 0.0, 0.3, "align"));
  rec.add(mesh_alignment_results(), r, "align/");
  if (!r.converged) rec.warnings.push_back("align: " + r.message + "; measured as aligned so far");
  return r.transform;
}

// The quality stage's count of short handles (reconstruct/handles.h), spacings being the mesh's
// mean edge length: a mesh from elsewhere has no cloud to take its spacing from.
const ResultTable<HandleResult>& quality_handle_results() {
  static const ResultTable<HandleResult> table = [] {
    ResultTable<HandleResult> t;
    t.count("short_handles", &HandleResult::short_handles, "Handles with a loop at most max_handle_loop mean edge lengths long (topological noise)")
        .lower_is_better()
        .as_count();
    t.number("shortest_handle_loop", &HandleResult::shortest_loop, "Length of the shortest such loop; 0 when none").with_unit("mesh units");
    t.number("max_handle_loop_length", &HandleResult::max_loop_length, "The limit used, max_handle_loop x the mean edge length").with_unit("mesh units");
    return t;
  }();
  return table;
}
std::vector<ParamSpec> quality_params() {
  std::vector<ParamSpec> specs = params_of(HandleParams::fields());
  std::erase_if(specs, [](const ParamSpec& p) { return p.name != "max_handle_loop"; });  // it only counts
  return specs;
}

void run_quality(StageRun& run) {
  const DataItem& item = run.context.item(run.output);
  const TriangleMesh mesh = mesh_of(item, run.inputs.front());
  const MeshQuality q = analyze_mesh_quality(mesh, nullptr, sub_progress(run.progress, 0.0, 0.7));
  report_progress(run.progress, 0.7, "short handles");
  record_quality(run.record, q);
  quality_warnings(run.record, q);
  const HandleResult handles = find_short_handles(mesh, read_params<HandleParams>(run.args), sub_progress(run.progress, 0.7, 1.0));
  run.record.add(quality_handle_results(), handles);
  if (handles.short_handles > 0)
    run.record.warnings.push_back(fmt::format("{} with a loop at most {} mean edge lengths ({:.4g}) long (topological noise?; shortest loop {:.4g}); "
                                              "reconstruct cuts them (max_handle_loop, remove_handles)",
                                              plural(handles.short_handles, "short handle"), run.args.number("max_handle_loop"),
                                              handles.max_loop_length, handles.shortest_loop));
  run.record.summary = "quality: " + quality_line(q) + (handles.short_handles > 0 ? ", " + plural(handles.short_handles, "short handle") : "");
}

void run_evaluate(StageRun& run) {
  const StageArgs& a = run.args;
  StageRecord& rec = run.record;
  const std::string& mesh_tag = run.inputs.at(0);
  const std::string& ref_tag = run.inputs.at(1);
  const TriangleMesh mesh = mesh_of(run.context.item(mesh_tag), mesh_tag);
  const DataItem& ref = run.context.item(ref_tag);
  if (ref.cloud().empty()) throw InputError(fmt::format("the reference \"{}\" has no points", ref_tag));
  for (std::size_t i = 0; i < ref.cloud().size(); ++i)
    if (!ref.cloud().positions[i].allFinite()) throw InputError(fmt::format("the reference \"{}\": point {} is not finite", ref_tag, i));

  const BoundingBox mesh_box = used_box(mesh), ref_box = bounding_box(ref.cloud().positions);
  const double diagonal = std::max(mesh_box.diagonal(), ref_box.diagonal());
  const double gap = box_gap(mesh_box, ref_box);
  if (gap > diagonal && !a.boolean("allow_far"))
    throw InputError(fmt::format("the reference \"{}\" lies {:.6g} away from the mesh \"{}\" (diagonals {:.6g} and {:.6g}): another unit or "
                                 "coordinate system? (allow_far measures it anyway)",
                                 ref_tag, gap, mesh_tag, ref_box.diagonal(), mesh_box.diagonal()));

  // The points measured: the reference cloud, or the surface of a reference mesh (`samples`
  // area-uniform samples of its triangles, seeded: a CAD mesh's vertices are only its corners);
  // moved onto the mesh first when asked to (a best fit).
  const SurfaceDistanceParams sd = read_params<SurfaceDistanceParams>(a);
  const bool surface = !ref.mesh.triangles.empty();
  const std::optional<RigidTransform> fit = a.boolean("align") ? std::optional(align_reference(run, mesh, ref_tag)) : std::nullopt;
  std::vector<Vector3d> ref_vertices;  // a reference mesh's vertices, moved
  if (fit && surface) {
    ref_vertices = ref.cloud().positions;
    fit->apply(std::span<Vector3d>(ref_vertices));
  }
  std::vector<Vector3d> moved;
  if (surface) {
    moved = sample_mesh_surface(fit ? std::span<const Vector3d>(ref_vertices) : std::span<const Vector3d>(ref.cloud().positions), ref.mesh.triangles,
                                sd.samples, sd.seed + 1);
    if (moved.empty()) throw InputError(fmt::format("the reference mesh \"{}\" has no area to sample", ref_tag));
  } else if (fit) {
    moved = ref.cloud().positions;
    fit->apply(std::span<Vector3d>(moved));
  }
  const std::vector<Vector3d>& measured = surface || fit ? moved : ref.cloud().positions;

  // Progress: each phase's share of the bar from a cost model in microseconds per triangle or
  // point (fitted to traces of 1M points against 75k and 1.2M triangles on 2 cores,
  // bench/notes/progress.md), so the bar follows the clock whatever the sizes.
  const double s0 = fit ? 0.3 : 0.0;  // the fit's share
  const double triangles = static_cast<double>(mesh.triangles.size()), points = static_cast<double>(measured.size());
  const bool needs_tree = !fit && !ref.is_mesh;
  MeshDistanceParams dp = read_params<MeshDistanceParams>(a);
  DeviationParams sp = read_params<DeviationParams>(a);
  const bool signed_run = dp.sign != DistanceSign::Unsigned;
  const double bvh_cost = 0.7 * triangles, quality_cost = 0.75 * triangles;
  const double tree_cost = needs_tree ? 0.45 * points : 0.0;  // beside the two above, on one core
  const double prepare_cost = std::max(bvh_cost + quality_cost, tree_cost);
  const double sign_cost = signed_run ? 0.5 * triangles : 0.0;
  const double distance_cost = points * (0.5 + 1.2 * triangles / (triangles + 3e5));
  const double statistics_cost = 0.2 * points + 0.1 * static_cast<double>(mesh.vertices.positions.size());
  const double samples_cost = 0.8 * static_cast<double>(sd.samples);
  const double total_cost = std::max(prepare_cost + sign_cost + distance_cost + statistics_cost + samples_cost, 1.0);
  double spent = 0.0;
  // The share of the bar at the start of the next phase, after `cost` more.
  const auto share = [&](double cost = 0.0) { return s0 + (1.0 - s0) * std::min(1.0, (spent += cost) / total_cost); };
  const double prepare_scale = prepare_cost / std::max(bvh_cost + quality_cost, 1.0);
  const double at_bvh = share(), at_quality = share(bvh_cost * prepare_scale), at_distances = share(quality_cost * prepare_scale);
  const double at_counted = share(sign_cost), at_statistics = share(distance_cost);
  const double at_vertices = share(0.1 * statistics_cost), at_samples = share(0.9 * statistics_cost);

  // The reference's kd-tree (the default tolerance, Chamfer) builds on one core (nanoflann):
  // beside the BVH and the quality pass, which keep the other cores busy.
  std::optional<TriangleBvh> bvh_holder;
  MeshQuality q;
  tbb::parallel_invoke(
      [&] {
        bvh_holder.emplace(mesh, sub_progress(run.progress, at_bvh, at_quality, "BVH build"));
        // its self-intersection count also serves the sign
        q = analyze_mesh_quality(mesh, &*bvh_holder, sub_progress(run.progress, at_quality, at_distances, "quality"));
      },
      [&] {
        if (!needs_tree) return;
        if (sp.tolerance == 0.0 && !surface) run.context.mean_spacing(ref_tag);  // the default tolerance
        else run.context.tree(ref_tag);
      });
  const TriangleBvh& bvh = *bvh_holder;
  dp.known_self_intersections = static_cast<long>(q.self_intersections);
  report_progress(run.progress, at_distances, "distances");  // its set-up (signs) reports nothing
  const MeshDistanceResult dist = mesh_distances(measured, mesh, dp, &bvh, sub_progress(run.progress, at_counted, at_statistics), &q.topology);
  report_progress(run.progress, at_statistics, "statistics");
  for (const std::string& w : dist.warnings) rec.warnings.push_back(w);

  if (sp.tolerance == 0.0) {
    sp.tolerance = surface ? mean_spacing(measured) : run.context.mean_spacing(ref_tag);
    rec.set_used("tolerance", sp.tolerance);
  }
  const DeviationStats stats = summarize_deviation(dist.distances, sp);
  EvaluateCounts counts;
  counts.reference_points = measured.size();
  counts.mesh_triangles = mesh.triangles.size();
  rec.add_counts(size_counts(), counts);
  rec.add(evaluate_text_results(), EvaluateTexts{ref_tag, distance_sign_names().name(dist.sign_used), ""});
  rec.set_used("reference", ref_tag);
  record_deviation(rec, "deviation/", stats);

  // The points that did not become vertices of the mesh (removed by cleaning or
  // simplification, or left out by the reconstruction): their deviation on its own.
  std::vector<double> unused;
  {
    report_progress(run.progress, at_vertices, "points at vertices");
    const std::vector<char> is_vertex = at_used_vertex(mesh, surface ? std::span<const Vector3d>(measured) : ref.cloud().positions);
    for (std::size_t i = 0; i < is_vertex.size(); ++i)
      if (!is_vertex[i]) unused.push_back(dist.distances[i]);
  }
  counts.points_not_vertices = unused.size();
  rec.add_counts(not_vertices_counts(), counts);
  record_deviation(rec, "deviation_not_vertices/", summarize_deviation(unused, sp));

  // Per region, when the reference carries labels.
  std::string region = a.text("region_field");
  if (surface && !region.empty())
    throw InputError(fmt::format("region_field: the reference \"{}\" is a mesh, measured by its surface samples, which carry no labels", ref_tag));
  if (region.empty()) {
    if (!surface) region = ref.cloud().fields.contains("segment") ? "segment" : ref.cloud().fields.contains("region") ? "region" : "";
  } else if (!ref.cloud().fields.contains(region))
    throw InputError(fmt::format("region_field: the reference \"{}\" has no field \"{}\"", ref_tag, region));
  if (!region.empty()) {
    rec.add(region_text_results(), EvaluateTexts{"", "", region});
    const std::vector<RegionDeviation> regions = summarize_deviation_by_region(dist.distances, ref.cloud().fields.find(region)->values, sp);
    counts.regions = regions.size();
    rec.add_counts(region_counts(), counts);
    for (const RegionDeviation& r : regions) record_deviation(rec, fmt::format("deviation_by_region/{}_{}/", region, r.label), r.stats);
  }

  // Chamfer and Hausdorff: reference to mesh exactly, mesh to reference from area-uniform samples.
  report_progress(run.progress, at_samples, "mesh samples");
  const std::vector<Vector3d> on_mesh = sample_mesh_surface(mesh, sd.samples, sd.seed);
  const SurfaceView ref_view = surface ? SurfaceView{fit ? std::span<const Vector3d>(ref_vertices) : std::span<const Vector3d>(ref.cloud().positions),
                                                    ref.mesh.triangles}
                                      : SurfaceView{measured, {}};
  // The context's kd-tree over the reference serves unless the points were moved.
  const KdTree* ref_tree = fit || ref.is_mesh ? nullptr : &run.context.tree(ref_tag);
  const std::vector<double> back =
      on_mesh.empty() ? std::vector<double>{} : nearest_surface_distances(on_mesh, ref_view, sd.exact, sd.samples, sd.seed, nullptr, ref_tree);
  double back_sum = 0.0, back_max = 0.0;
  for (double d : back) {
    back_sum += d;
    back_max = std::max(back_max, d);
  }
  const double forward_max = std::max(stats.max_positive, -stats.max_negative);
  const double back_mean = back.empty() ? 0.0 : back_sum / static_cast<double>(back.size());
  counts.mesh_samples = on_mesh.size();
  rec.add_counts(sample_counts(), counts);
  TwoWayDistance two_way;
  two_way.reference_to_mesh_mean = stats.mean_absolute;
  two_way.reference_to_mesh_max = forward_max;
  two_way.mesh_to_reference_mean = back_mean;
  two_way.mesh_to_reference_max = back_max;
  two_way.chamfer = 0.5 * (stats.mean_absolute + back_mean);
  two_way.hausdorff = std::max(forward_max, back_max);
  two_way.mesh_samples = on_mesh.size();
  rec.add(distance_results(), two_way, "distance/");

  record_quality(rec, q);

  rec.summary = fmt::format("evaluate: {:.1f}% out of tolerance +-{:.4g} ({:.1f}% above, {:.1f}% below) of {}{} against \"{}\" ({}); "
                            "|d| p95 {:.4g}, p99 {:.4g}; max +{:.4g} / {:.4g}, mean +{:.4g} / {:.4g}, rms {:.4g}; Hausdorff {:.4g}; mesh {}",
                            100.0 * stats.out_of_tolerance, stats.tolerance, 100.0 * stats.above_tolerance, 100.0 * stats.below_tolerance,
                            surface ? plural(measured.size(), "surface sample") : plural(ref.cloud().size(), "point"), fit ? " (aligned: " + fit->describe() + ")" : std::string(), mesh_tag,
                            distance_sign_names().name(dist.sign_used), stats.abs_p95, stats.abs_p99, stats.max_positive, stats.max_negative,
                            stats.mean_positive, stats.mean_negative, stats.rms, std::max(forward_max, back_max), quality_line(q));

  // The output: the measured points with their deviation (a reference mesh's surface samples,
  // where they lie).
  if (surface) {
    PointCloud samples;
    samples.positions = measured;
    samples.crs = ref.cloud().crs;
    run.context.set_cloud(run.output, std::move(samples), ref_tag);
  } else {
    run.context.copy(ref_tag, run.output);
  }
  DataItem& out = run.context.item(run.output);
  out.mesh.triangles.clear();
  out.is_mesh = false;
  out.cloud().fields.add("deviation", out.cloud().size()).values = dist.distances;
  out.measured = MeasuredField{"deviation", sp.tolerance};
  if (fit && !surface) fit->apply(out.cloud());
}

// The parameter `name` of `params` (declared there).
ParamSpec& param(std::vector<ParamSpec>& params, const std::string& name) {
  for (ParamSpec& p : params)
    if (p.name == name) return p;
  throw std::logic_error("evaluate: no parameter " + name);
}

}  // namespace

StageSpec evaluate_stage() {
  StageSpec s;
  s.name = "evaluate";
  s.results = evaluate_specs();
  s.shape = CommandShape::Compare;
  s.summary = "Signed deviation of a reference cloud from a mesh, with statistics, Chamfer, Hausdorff and mesh quality";
  s.description = "Every reference point gets its exact distance to the mesh's triangles, positive outside (where the normals point). "
                  "A reference mesh is measured by its surface: samples points drawn area-uniformly on its triangles (seeded), not its "
                  "vertices. In a pipeline the reference is the cloud as read, unless reference names another tag. The output is the "
                  "reference (a reference mesh's surface samples) with a field deviation. With align the reference is first moved onto the mesh by a best fit (point-to-plane ICP), "
                  "measured and written where it was moved to, and the transform is reported under align/.";
  s.order = 130;
  s.consumes = {Slot{"mesh", DataKind::Mesh}, Slot{"reference", DataKind::Any}};
  s.produces = Slot{"cloud", DataKind::Cloud};
  s.params = {P::text("reference", "", "Tag of the cloud to measure (pipeline); the command line takes a file. Default: the cloud as read").meta("TAG")};
  append(s.params, params_of(DeviationParams::fields()));
  append(s.params, params_of(MeshDistanceParams::fields()));
  append(s.params, params_of(SurfaceDistanceParams::fields()));
  // The stage's own meanings: tolerance 0 is the reference's mean spacing; the mesh-to-reference
  // distance needs at least one sample.
  param(s.params, "tolerance").doc = "Share within +-tolerance is reported; 0: the reference's mean spacing";
  ParamSpec& samples = param(s.params, "samples");
  samples.min = 1;
  samples.doc = "Points sampled area-uniformly on the mesh for the mesh-to-reference distance";
  s.params.push_back(
      P::text("region_field", "", "Field with region labels for a per-region breakdown; default segment or region when present").meta("NAME"));
  s.params.push_back(P::boolean("allow_far", false, "Measure even when the reference lies farther from the mesh than their size"));
  s.params.push_back(P::boolean(
      "align", false, "Best fit first: move the reference onto the mesh by point-to-plane ICP against the mesh samples; the transform is reported"));
  append(s.params, params_of(MeshAlignParams::fields()));
  s.examples = {"pointsurf reconstruct data/kitten.xyz mesh.ply",
                "pointsurf evaluate mesh.ply --reference data/kitten.xyz --tolerance 0.001 --out deviation.ply",
                "pointsurf evaluate mesh.ply --reference data/kitten.xyz --align --report fit.json"};
  s.run = run_evaluate;
  return s;
}

StageSpec quality_stage() {
  StageSpec s;
  s.name = "quality";
  s.results = quality_specs();
  append(s.results, quality_handle_results().specs());
  s.params = quality_params();
  s.shape = CommandShape::Measure;
  s.summary = "Mesh quality: manifoldness, orientation, holes, components, genus, self-intersections, angles, area, volume";
  s.description = "Short handles (topological noise) are counted with spacings taken as the mesh's mean edge length.";
  s.order = 125;
  s.consumes = {Slot{"mesh", DataKind::Mesh}};
  s.produces = Slot{"mesh", DataKind::Mesh};
  s.examples = {"pointsurf reconstruct data/kitten.xyz mesh.ply", "pointsurf quality mesh.ply --report quality.json"};
  s.run = run_quality;
  return s;
}

}  // namespace pointsurf::detail
