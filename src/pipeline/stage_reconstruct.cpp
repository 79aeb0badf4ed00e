// SPDX-License-Identifier: GPL-3.0-or-later
// The reconstruct stage: a triangle mesh through the points (region-growing triangulation,
// cocone, Crust, ball pivoting or screened Poisson), with its topology reported.
#include <algorithm>
#include <limits>
#include <set>

#include "pipeline/detail/declare.h"
#include "pipeline/detail/stage_util.h"
#include "pointsurf/core/error.h"
#include "pointsurf/features/boundary_points.h"
#include "pointsurf/normals/noise.h"
#include "pointsurf/normals/normals.h"
#include "pointsurf/pipeline/context.h"
#include "pointsurf/reconstruct/ball_pivot.h"
#include "pointsurf/reconstruct/cocone.h"
#include "pointsurf/reconstruct/crust.h"
#include "pointsurf/reconstruct/flat_regions.h"
#include "pointsurf/reconstruct/handles.h"
#include "pointsurf/reconstruct/mesh_cleanup.h"
#include "pointsurf/reconstruct/poisson.h"
#include "pointsurf/reconstruct/triangulate.h"

namespace pointsurf::detail {
namespace {

// The mesh's boundary loops split into holes and border loops: a loop is the border of the
// scan (the rim of a terrain tile, the edge of an open part) when at least kBorderShare of its
// vertices are boundary points of the cloud by the angular-gap test (features/boundary_points.h,
// defaults); else it is a hole the reconstruction left. Not every vertex: the border of
// data/b9_training.ply zigzags, and 23 % of its 582 rim vertices have a gap under 90 degrees
// (its other border loops 11-40 %), where only 1-5 % of the rim vertices of the holes left on
// closed armadillo samples have more (measured). A sampling gap wider than the neighbourhood
// (radar.xyz's sparse bands) looks like a border to the test. Longest first, as in MeshTopology.
constexpr double kBorderShare = 0.5;
struct LoopKinds {
  std::vector<const BoundaryLoop*> holes, borders;
  static double perimeter(const std::vector<const BoundaryLoop*>& loops) {
    double total = 0.0;
    for (const BoundaryLoop* loop : loops) total += loop->length;
    return total;
  }
};

LoopKinds classify_loops(const MeshTopology& t, const PointCloud& cloud, const KdTree& tree) {
  LoopKinds kinds;
  if (t.boundary_loops.empty()) return kinds;
  const BoundaryResult rim = detect_boundary_points(cloud, {}, &tree);
  for (const BoundaryLoop& loop : t.boundary_loops) {
    const auto on_rim = std::count_if(loop.vertices.begin(), loop.vertices.end(), [&](auto v) { return rim.boundary[std::size_t(v)] != 0; });
    const bool border = double(on_rim) >= kBorderShare * double(loop.vertices.size());
    (border ? kinds.borders : kinds.holes).push_back(&loop);
  }
  return kinds;
}

// The Poisson figures beyond the common ones: the octree per level, the solver.
struct PoissonLevels {
  std::vector<double> nodes_per_level, relative_residual_per_level;
};
const ResultTable<PoissonLevels>& poisson_metrics() {
  static const ResultTable<PoissonLevels> table = [] {
    ResultTable<PoissonLevels> t;
    t.numbers("nodes_per_level", &PoissonLevels::nodes_per_level, "Octree nodes per level, from level 1");
    t.numbers("relative_residual_per_level", &PoissonLevels::relative_residual_per_level, "Relative residual of the solver per level, from level 1");
    return t;
  }();
  return table;
}

// The Poisson figures beyond the common ones: the depth used, the octree per level, the solver.
void record_poisson(const PoissonResult& r, StageRecord& rec) {
  rec.set_used("depth", std::int64_t{r.depth});
  PoissonLevels levels;
  for (std::size_t l = 1; l < r.nodes_per_level.size(); ++l) {
    levels.nodes_per_level.push_back(double(r.nodes_per_level[l]));
    levels.relative_residual_per_level.push_back(r.residual_per_level[l]);
  }
  rec.add(poisson_metrics(), levels);
}

// The mesh as built: its counts and metrics.
struct MeshSummary {
  std::size_t points = 0, triangles = 0, unused_points = 0, boundary_edges = 0, holes = 0, border_loops = 0;
  std::size_t non_manifold_edges = 0, non_manifold_vertices = 0, inconsistent_edges = 0, components = 0;
  double holes_total_perimeter = 0.0, largest_hole_perimeter = 0.0, border_perimeter = 0.0;
  std::int64_t euler_characteristic = 0;
  long genus = -1, handles = -1;
  bool watertight = false;
  double noise_in_spacings = 0.0, mean_spacing = 0.0;
  bool normals_estimated = false;
  std::string built_from;
};
const ResultTable<MeshSummary>& mesh_counts() {
  static const ResultTable<MeshSummary> table = [] {
    using M = MeshSummary;
    ResultTable<M> t;
    t.count("points", &M::points, "Points of the input");
    t.count("triangles", &M::triangles, "Triangles of the mesh");
    t.count("unused_points", &M::unused_points, "Points no triangle uses (0 for poisson)").lower_is_better();
    t.count("boundary_edges", &M::boundary_edges, "Edges with one triangle").lower_is_better();
    t.count("holes", &M::holes, "Boundary loops that are holes the reconstruction left").lower_is_better();
    t.count("border_loops", &M::border_loops, "Boundary loops along the border of the scan");
    t.count("non_manifold_edges", &M::non_manifold_edges, "Edges with more than two triangles").lower_is_better();
    t.count("non_manifold_vertices", &M::non_manifold_vertices, "Vertices whose triangles do not form one fan").lower_is_better();
    t.count("inconsistent_edges", &M::inconsistent_edges, "Edges whose two triangles disagree on orientation").lower_is_better();
    t.count("components", &M::components, "Connected components");
    return t;
  }();
  return table;
}
const ResultTable<MeshSummary>& noise_metrics() {
  static const ResultTable<MeshSummary> table = [] {
    ResultTable<MeshSummary> t;
    t.number("noise_in_spacings", &MeshSummary::noise_in_spacings, "Median RMS distance to the local plane, in local spacings")
        .with_unit("spacings");
    return t;
  }();
  return table;
}
const ResultTable<MeshSummary>& mesh_metrics() {
  static const ResultTable<MeshSummary> table = [] {
    using M = MeshSummary;
    ResultTable<M> t;
    t.number("holes_total_perimeter", &M::holes_total_perimeter, "Total perimeter of the holes").with_unit("cloud units").lower_is_better();
    t.number("largest_hole_perimeter", &M::largest_hole_perimeter, "Perimeter of the largest hole").with_unit("cloud units").lower_is_better();
    t.number("border_perimeter", &M::border_perimeter, "Total perimeter of the border loops").with_unit("cloud units");
    t.count("euler_characteristic", &M::euler_characteristic, "V - E + F");
    // MeshTopology::genus() is -1 where no genus is defined (several components, non-manifold):
    // the report says null rather than a number that reads like a value.
    t.computed("genus", ResultType::Integer,
               [](const M& m) { return m.genus >= 0 ? ResultValue(std::int64_t{m.genus}) : ResultValue(std::numeric_limits<double>::quiet_NaN()); },
               "Genus of a closed manifold mesh (null where undefined)");
    t.computed("handles", ResultType::Integer,
               [](const M& m) { return m.handles >= 0 ? ResultValue(std::int64_t{m.handles}) : ResultValue(std::numeric_limits<double>::quiet_NaN()); },
               "Genus summed over the components (null where undefined)");
    t.flag("watertight", &M::watertight, "Closed, manifold and consistently oriented");
    t.number("mean_spacing", &M::mean_spacing, "Mean distance to the nearest neighbour").with_unit("cloud units");
    t.flag("normals_estimated", &M::normals_estimated, "The input had no normals: they were estimated");
    t.text("built_from", &M::built_from, "Tag of the cloud the mesh comes from");
    return t;
  }();
  return table;
}

// Every method's ReconstructionStats, each key once (the first method's doc).
std::vector<ResultSpec> reconstruct_specs(const std::vector<std::string>& methods) {
  std::vector<ResultSpec> out = noise_metrics().specs();
  append(out, poisson_metrics().specs());
  std::set<std::string> seen;
  for (const std::string& method : methods)
    for (const ResultSpec& spec : ReconstructionStats::results(method).specs())
      if (seen.insert(spec.key).second) out.push_back(spec);
  append(out, SmallComponentsResult::results().specs());
  append(out, HandleResult::results().specs());
  append(out, FlatRegionResult::results().specs());
  append(out, counted(mesh_counts().specs()));
  append(out, mesh_metrics().specs());
  return out;
}

// Where the stage's tail (after the method) starts in the stage's progress, and where its short
// handles and flat regions start: fixed for the interpolating methods; for Poisson, whose tail
// follows its output's triangles, from a cost model (below).
struct TailShares {
  double begin = 0.9, handles = 0.91, flats = 0.95;
};

// Poisson's tail in seconds on 2 cores (quiet runs of 10 meshes sampled at 150k-500k points,
// bench/notes/progress.md): small components, the topology and the flat regions follow the
// triangles; the short-handle search runs only on a surface with handles, and its balls (of a
// fixed size in cloud spacings) hold more triangles as the mesh gets finer than the cloud: its
// cost per triangle grows with the triangles per point (1.2 us at 5.7 and 6.2). Until the
// surface is known, the search is assumed at most kAssumedSearch of the method's time.
struct PoissonTailCost {
  static constexpr double kComponents = 0.14e-6, kTopology = 0.15e-6, kFlats = 0.33e-6;  // per triangle
  static constexpr double kSearch = 0.21e-6;  // per triangle and triangle per point
  static constexpr double kAssumedSearch = 0.12;
  double components = 0.0, handles = 0.0, flats = 0.0;
  // `cap`: at most this long for the search (a surface whose handles are not known yet may have
  // none: an assumed search that does not run leaves the progress behind)
  PoissonTailCost(double triangles, double points, bool has_handles, double cap = std::numeric_limits<double>::infinity())
      : components(kComponents * triangles), handles(kTopology * triangles), flats(kFlats * triangles) {
    if (has_handles) handles += std::min(cap, kSearch * triangles * triangles / std::max(points, 1.0));
  }
  double total() const { return components + handles + flats; }
  TailShares shares(double begin) const {
    const double t = std::max(total(), 1e-12), rest = 1.0 - begin;
    return {begin, begin + rest * components / t, begin + rest * (components + handles) / t};
  }
};

// After any method: specks removed (min_component_share), short handles cut (max_handle_loop
// cloud spacings, issue 28), then the flat regions labelled as the face field "region" (issue
// 12). The topology is analysed again when faces changed.
HandleResult clean_and_label_faces(ReconstructionResult& result, const StageArgs& a, double spacing, StageRecord& rec,
                                   const ProgressCallback& progress, const TailShares& tail) {
  report_progress(progress, tail.begin, "small components");
  const SmallComponentsResult removed = remove_small_components(result.mesh, read_params<SmallComponentParams>(a));
  rec.add(SmallComponentsResult::results(), removed);
  report_progress(progress, tail.handles, "short handles");
  HandleParams hp = read_params<HandleParams>(a);
  hp.spacing = spacing;
  const HandleResult handles = remove_short_handles(result.mesh, hp, sub_progress(progress, tail.handles, tail.flats));
  rec.add(HandleResult::results(), handles);
  if (handles.short_handles > handles.handles_removed)
    rec.warnings.push_back(fmt::format("{} with a loop at most {} spacings ({:.3g}) long {} (topological noise; shortest loop {:.3g}){}",
                                       plural(handles.short_handles - handles.handles_removed, "short handle"), hp.max_loop_in_spacings,
                                       handles.max_loop_length, handles.short_handles - handles.handles_removed == 1 ? "remains" : "remain",
                                       handles.shortest_loop, hp.remove ? ": they could not be cut cleanly" : "; --remove-handles true cuts them"));
  if (removed.faces_removed > 0 || handles.handles_removed > 0) {
    const std::size_t used_before = result.topology.vertices;
    result.topology = analyze_topology(result.mesh);
    result.unused_points += used_before - result.topology.vertices;
  }
  report_progress(progress, tail.flats, "flat regions");
  const FlatRegionResult regions = label_flat_regions(result.mesh, read_params<FlatRegionParams>(a), sub_progress(progress, tail.flats, 1.0));
  ScalarField& field = result.mesh.face_fields.add("region", regions.region.size(), ScalarType::Int32);
  std::copy(regions.region.begin(), regions.region.end(), field.values.begin());
  rec.add(FlatRegionResult::results(), regions);
  return handles;
}

void run_reconstruct(StageRun& run) {
  const StageArgs& a = run.args;
  const std::string& method = a.method();
  DataItem& item = run.context.item(run.output);
  if (item.cloud().size() < 3) throw InputError(fmt::format("{}; a surface needs at least 3", plural(item.cloud().size(), "point")));
  if (!item.mesh.triangles.empty()) drop_faces(item, run.record);
  const double spacing = run.context.mean_spacing(run.output);
  if (!(spacing > 0.0)) throw InputError(fmt::format("all {} coincide; no surface can be built", plural(item.cloud().size(), "point")));
  StageRecord& rec = run.record;
  const bool estimated = method != "cocone" && method != "crust" && !item.cloud().has_normals();
  // the normals' share: Poisson takes about 15 times as long as the normals (200k points: 0.7 s
  // against 11-12 s), the interpolating methods about 4 times
  const double normals_share = method == "poisson" ? 0.06 : 0.2;
  if (estimated) estimate_missing_normals(run, a.int32("normals_k"), sub_progress(run.progress, 0.0, normals_share));
  const PointCloud& cloud = item.cloud();
  const KdTree& tree = run.context.tree(run.output);
  // the rest: labels, loops. Poisson's forecast (after its octree) moves the split; its tail
  // assumes handles to search until the surface says.
  const double begin = estimated ? normals_share : 0.0;
  TailShares tail;
  double forecast_tail = 0.0;
  // Poisson's share starts after the noise estimate (1-7 % of the stage: more at low depths)
  const double method_begin = method == "poisson" ? begin + 0.03 : begin;
  MovableProgress method_part(run.progress, method_begin, tail.begin);
  const ProgressCallback progress = method_part.callback([&](const ProgressForecast& f) {
    if (method != "poisson" || !(f.seconds > 0.0)) return;
    forecast_tail = PoissonTailCost(f.output_size, double(cloud.size()), true, PoissonTailCost::kAssumedSearch * f.seconds).total();
    method_part.move_end(method_begin + (1.0 - method_begin) * f.seconds / (f.seconds + forecast_tail));
  });
  const NoiseEstimate noise = estimate_noise(cloud, tree);
  MeshSummary m;
  m.noise_in_spacings = noise.median_in_spacings;
  rec.add(noise_metrics(), m);
  if (noise.median_in_spacings > kNoisyInSpacings && method != "poisson")
    rec.warnings.push_back(fmt::format(
        "the points are noisy: their neighbourhoods are {:.2f} local spacings thick (median RMS distance to the local plane; "
        "above {} an interpolating surface comes out in shreds); smooth them first (pointsurf clean --method bilateral) or "
        "simplify to a coarser spacing",
        noise.median_in_spacings, kNoisyInSpacings));
  ReconstructionResult result;
  if (method == "triangulate") {
    result = reconstruct_region_growing(cloud, read_params<TriangulateParams>(a), &tree, progress);
  } else if (method == "cocone") {
    result = reconstruct_cocone(cloud, read_params<CoconeParams>(a), progress);
  } else if (method == "crust") {
    result = reconstruct_crust(cloud, read_params<CrustParams>(a), progress);
  } else if (method == "poisson") {
    PoissonResult poisson = reconstruct_poisson(cloud, read_params<PoissonParams>(a), &tree, progress);
    record_poisson(poisson, rec);
    if (poisson.skipped_normals > 0)
      rec.warnings.push_back(fmt::format("{} skipped: zero or non-finite normal", plural(poisson.skipped_normals, "point")));
    result = std::move(poisson);
    if (forecast_tail > 0.0) {
      // The surface is known: the tail as predicted now, against what its share assumed; less
      // work than assumed (no handles) moves the progress on to the share done by time.
      const PoissonTailCost cost(double(result.mesh.triangles.size()), double(cloud.size()), result.topology.handles() > 0);
      const double end = method_part.end();
      const double at = std::max(end, end / (end + (1.0 - end) * cost.total() / forecast_tail));
      tail = cost.shares(at);
    }
  } else {
    const BallPivotParams p = read_params<BallPivotParams>(a);
    result = reconstruct_ball_pivoting(cloud, p, &tree, progress);
    std::vector<double> radii = p.radii;
    if (radii.empty())
      for (const double f : p.radii_in_spacings) radii.push_back(f * result.mean_spacing);
    std::sort(radii.begin(), radii.end());
    radii.erase(std::unique(radii.begin(), radii.end()), radii.end());
    rec.set_used("radii", radii);
  }
  rec.add(ReconstructionStats::results(method), result.stats);
  const HandleResult handles = clean_and_label_faces(result, a, spacing, rec, run.progress, tail);
  if (method == "poisson") result.unused_points = 0;  // approximating: its vertices are not the points
  const MeshTopology& t = result.topology;
  // Poisson's surface is closed but where trimming opened it: its loops are borders, and its
  // vertices are not the cloud's points, which the rim test reads
  LoopKinds loops;
  if (method == "poisson")
    for (const BoundaryLoop& loop : t.boundary_loops) loops.borders.push_back(&loop);
  else loops = classify_loops(t, cloud, tree);
  const double hole_perimeter = LoopKinds::perimeter(loops.holes);
  m.points = cloud.size();
  m.triangles = t.triangles;
  m.unused_points = result.unused_points;
  m.boundary_edges = t.boundary_edges;
  m.holes = loops.holes.size();
  m.border_loops = loops.borders.size();
  m.non_manifold_edges = t.non_manifold_edges;
  m.non_manifold_vertices = t.non_manifold_vertices;
  m.inconsistent_edges = t.inconsistent_edges;
  m.components = t.components;
  m.holes_total_perimeter = hole_perimeter;
  m.largest_hole_perimeter = loops.holes.empty() ? 0.0 : loops.holes.front()->length;
  m.border_perimeter = LoopKinds::perimeter(loops.borders);
  m.euler_characteristic = static_cast<std::int64_t>(t.euler_characteristic);
  m.genus = t.genus();
  m.handles = t.handles();
  m.watertight = t.watertight();
  m.mean_spacing = spacing;
  m.normals_estimated = estimated;
  m.built_from = run.record.inputs.front();
  rec.add_counts(mesh_counts(), m);
  rec.add(mesh_metrics(), m);
  if (t.triangles == 0)
    throw ComputeError(fmt::format("no triangle could be formed from {} (collinear, too sparse, or no usable normals?)",
                                   plural(cloud.size(), "point")));
  if (!loops.holes.empty())
    rec.warnings.push_back(fmt::format("{} remain{} (total perimeter {:.4g}, largest {:.4g}){}", plural(loops.holes.size(), "hole"),
                                       loops.holes.size() == 1 ? "s" : "", hole_perimeter, loops.holes.front()->length,
                                       loops.borders.empty() ? "" : fmt::format("; besides, {} along the border of the scan",
                                                                                plural(loops.borders.size(), "boundary loop"))));
  if (t.non_manifold_edges > 0) rec.warnings.push_back(plural(t.non_manifold_edges, "non-manifold edge"));
  if (t.non_manifold_vertices > 0) rec.warnings.push_back(plural(t.non_manifold_vertices, "non-manifold vertex", "non-manifold vertices"));
  const long genus = t.genus();
  rec.summary = fmt::format("reconstruct: {} {} from {}{}; {} (perimeter {:.4g}), {}, non-manifold {} edges / {} vertices, {}, genus {}",
                            method, plural(t.triangles, "triangle"), plural(cloud.size(), "point"), estimated ? " (normals estimated)" : "",
                            plural(loops.holes.size(), "hole"), hole_perimeter, plural(loops.borders.size(), "border loop"),
                            t.non_manifold_edges, t.non_manifold_vertices, plural(t.components, "component"),
                            genus >= 0 ? std::to_string(genus) : std::string("-"));
  if (handles.handles_removed > 0)
    rec.summary += fmt::format(" ({} cut: {} handles before, loops {:.3g} to {:.3g}, at most {:.3g})", plural(handles.handles_removed, "short handle"),
                               handles.handles_before >= 0 ? std::to_string(handles.handles_before) : std::string("-"), handles.shortest_loop,
                               std::max_element(handles.loops.begin(), handles.loops.end(), [](const HandleLoop& x, const HandleLoop& y) {
                                 return x.length < y.length;
                               })->length,
                               handles.max_loop_length);
  // The mesh's vertices are the cloud's points in order (Poisson: new vertices): the item keeps
  // its positions (and so its cached tree) and gains the faces.
  TriangleMesh& mesh = result.mesh;
  if (mesh.vertices.normals.empty() && cloud.has_normals() && mesh.vertices.positions.size() == cloud.size()) mesh.vertices.normals = cloud.normals;
  item.assign_mesh(std::move(mesh), run.record.inputs.front());  // the mesh records the cloud it came from
}

}  // namespace

StageSpec reconstruct_stage() {
  StageSpec s;
  s.name = "reconstruct";
  s.summary = "Triangle mesh through the points: region-growing triangulation (default), cocone, Crust, ball pivoting or screened Poisson";
  s.description = "Normals are estimated (PCA, normals_k) and MST-oriented when the input has none (cocone and crust need none). Poisson builds new vertices (approximating); its trim loops are border loops. Holes, "
                  "manifoldness, components and genus are reported; handles with a loop at most max_handle_loop cloud spacings long "
                  "(topological noise) are cut and closed.";
  s.order = 120;
  s.consumes = {Slot{"cloud", DataKind::Cloud}};
  s.produces = Slot{"mesh", DataKind::Mesh};
  s.methods = {"triangulate", "cocone", "crust", "ball-pivot", "poisson"};
  s.default_method = "triangulate";
  s.params = {P::integer("normals_k", NormalParams{}.k, "Neighbours for normals when the input has none").at_least(3).only({"triangulate", "ball-pivot", "poisson"})};
  append(s.params, params_of(TriangulateParams::fields(), {"triangulate"}));
  append(s.params, params_of(CoconeParams::fields(), {"cocone"}));
  append(s.params, params_of(CrustParams::fields(), {"crust"}));
  append(s.params, params_of(BallPivotParams::fields(), {"ball-pivot"}));
  append(s.params, params_of(PoissonParams::fields(), {"poisson"}));
  append(s.params, params_of(SmallComponentParams::fields()));
  append(s.params, params_of(HandleParams::fields()));
  append(s.params, params_of(FlatRegionParams::fields()));
  s.examples = {"pointsurf reconstruct data/kitten.xyz mesh.ply", "pointsurf reconstruct data/kitten.xyz mesh_bp.ply --method ball-pivot --radii-in-spacings 2,4",
                "pointsurf reconstruct data/kitten.xyz mesh_poisson.ply --method poisson --trim-depth 5"};
  s.results = reconstruct_specs(s.methods);
  s.run = run_reconstruct;
  s.check = [](const StageArgs& a) {
    if (a.has("radii") && a.given("radii") && a.given("radii_in_spacings")) throw key_error("radii", " and radii_in_spacings: give only one");
    read_params<SmallComponentParams>(a).validate();
    read_params<HandleParams>(a).validate();
    read_params<FlatRegionParams>(a).validate();
    if (a.method() == "triangulate") read_params<TriangulateParams>(a).validate();
    else if (a.method() == "cocone") read_params<CoconeParams>(a).validate();
    else if (a.method() == "crust") read_params<CrustParams>(a).validate();
    else if (a.method() == "poisson") read_params<PoissonParams>(a).validate();
    else read_params<BallPivotParams>(a).validate();
  };
  return s;
}

}  // namespace pointsurf::detail
