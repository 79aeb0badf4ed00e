// SPDX-License-Identifier: GPL-3.0-or-later
// The segment stage: one integer label per point in the field "segment" (-1 unassigned), by
// region growing, Euclidean clusters, RANSAC primitives or HK surface type.
#include <sstream>

#include "pipeline/detail/declare.h"
#include "pipeline/detail/stage_util.h"
#include "pointsurf/core/error.h"
#include "pointsurf/features/boundary_points.h"
#include "pointsurf/io/polylines.h"
#include "pointsurf/normals/normals.h"
#include "pointsurf/pipeline/context.h"
#include "pointsurf/segment/outlines.h"
#include "pointsurf/segment/segment.h"
#include "pointsurf/shape/primitives.h"

namespace pointsurf::detail {
namespace {

RegionGrowingParams region_params(const StageArgs& a) {
  RegionGrowingParams p;
  p.k = a.int32("k");
  p.max_angle_deg = a.number("max_angle_deg");
  p.max_variation = a.number("max_variation");
  p.use_features = a.boolean("use_features");
  p.min_points = static_cast<std::size_t>(a.integer("min_points"));
  return p;
}

EuclideanParams euclidean_params(const StageArgs& a) {
  EuclideanParams p;
  p.radius = a.number("radius");
  p.radius_in_spacings = a.number("radius_in_spacings");
  p.min_points = static_cast<std::size_t>(a.integer("min_points"));
  return p;
}

SurfaceTypeParams hk_params(const StageArgs& a) {
  SurfaceTypeParams p;
  p.k = a.int32("k");
  p.min_points = static_cast<std::size_t>(a.integer("min_points"));
  return p;
}

unsigned primitive_types(const std::string& list) {
  unsigned types = 0;
  std::stringstream in(list);
  std::string word;
  while (std::getline(in, word, ',')) {
    if (word == "plane") types |= kPlanes;
    else if (word == "sphere") types |= kSpheres;
    else if (word == "cylinder") types |= kCylinders;
    else if (word == "cone") types |= kCones;
    else if (word == "torus") types |= kTori;
    else throw UsageError(fmt::format("types: unknown primitive \"{}\" (expected a comma-separated list of plane, sphere, cylinder, cone, torus)", word));
  }
  return types;
}

std::string primitive_type_list(unsigned types) {
  std::string list;
  for (unsigned bit = 0; bit < 5; ++bit)
    if (types & (1u << bit)) list += (list.empty() ? "" : ",") + std::string(primitive_type_name(PrimitiveType(bit)));
  return list;
}

PrimitiveParams primitive_params(const StageArgs& a) {
  PrimitiveParams p;
  p.types = primitive_types(a.text("types"));
  p.epsilon = a.number("epsilon");
  p.epsilon_in_spacings = a.number("epsilon_in_spacings");
  p.cluster_epsilon = a.number("cluster_epsilon");
  p.cluster_in_spacings = a.number("cluster_in_spacings");
  p.max_normal_deg = a.number("max_normal_deg");
  p.min_points = static_cast<std::size_t>(a.integer("min_points"));
  p.probability = a.number("probability");
  p.band_in_epsilons = a.number("band_in_epsilons");
  p.seed = static_cast<std::uint64_t>(a.integer("seed"));
  return p;
}

void record_primitives(StageRecord& rec, const PrimitiveResult& r) {
  rec.set_used("epsilon", r.epsilon_used);
  rec.set_used("cluster_epsilon", r.cluster_epsilon_used);
  rec.set_used("min_points", static_cast<std::int64_t>(r.min_points_used));
  rec.count("candidates", as_count(r.candidates));
  for (std::size_t i = 0; i < r.primitives.size(); ++i) {
    const Primitive& s = r.primitives[i];
    // Per primitive: its type, then point (3), axis (3), radius, half angle (degrees), inliers, RMS,
    // minor radius (torus).
    rec.metric(fmt::format("primitive_{}_type", i), std::string(primitive_type_name(s.type)));
    rec.metric(fmt::format("primitive_{}", i), std::vector<double>{s.point.x(), s.point.y(), s.point.z(), s.axis.x(), s.axis.y(), s.axis.z(),
                                                                   s.radius, s.angle_deg, double(s.inliers), s.rms, s.minor_radius});
  }
}

void run_segment(StageRun& run) {
  const StageArgs& a = run.args;
  PointCloud& cloud = run.context.item(run.output).cloud;
  const std::string& method = a.method();
  StageRecord& rec = run.record;
  if (cloud.size() < 3) throw InputError(fmt::format("{}; segmentation needs at least 3", plural(cloud.size(), "point")));
  const bool needs_normals = method == "region" || method == "ransac";
  bool estimated = false;
  if (needs_normals && !cloud.has_normals()) {
    estimate_missing_normals(run, a.int32("normals_k"), sub_progress(run.progress, 0.0, 0.3));
    estimated = true;
  } else if (needs_normals) {
    check_input_normals(run, "left unassigned");
  }
  const ProgressCallback progress = sub_progress(run.progress, estimated ? 0.3 : 0.0, 1.0);
  std::vector<std::int32_t> labels;
  std::size_t segments = 0, unassigned = 0;
  if (method == "region") {
    const SegmentResult r = segment_region_growing(cloud, region_params(a), &run.context.tree(run.output), progress);
    labels = r.labels, segments = r.sizes.size(), unassigned = r.unassigned;
  } else if (method == "euclidean") {
    const SegmentResult r = segment_euclidean(cloud, euclidean_params(a), &run.context.tree(run.output));
    labels = r.labels, segments = r.sizes.size(), unassigned = r.unassigned;
  } else if (method == "hk") {
    if (!cloud.fields.contains("surface_type"))
      throw InputError("the input has no \"surface_type\" field; run the curvature stage first (pointsurf curvature)");
    const SegmentResult r = segment_surface_types(cloud, hk_params(a), &run.context.tree(run.output));
    labels = r.labels, segments = r.sizes.size(), unassigned = r.unassigned;
  } else {
    const PrimitiveResult r = detect_primitives(cloud, primitive_params(a), progress);
    labels = r.labels, segments = r.primitives.size(), unassigned = r.unassigned;
    record_primitives(rec, r);
  }
  std::vector<double>& field = cloud.fields.add("segment", cloud.size(), ScalarType::Int32).values;
  for (std::size_t i = 0; i < labels.size(); ++i) field[i] = labels[i];
  rec.count("points", as_count(cloud.size()));
  rec.count("segments", as_count(segments));
  rec.count("unassigned", as_count(unassigned));
  rec.metric("normals_estimated", estimated);
  if (segments == 0) rec.warnings.push_back("no segment was found: every point is unassigned (-1)");
  rec.summary = fmt::format("segment ({}): {} {}, {} of {} unassigned{}", method, segments, method == "ransac" ? "primitives" : "segments",
                            unassigned, plural(cloud.size(), "point"), estimated ? ", normals estimated" : "");
}

BoundaryParams boundary_params(const StageArgs& a) {
  BoundaryParams p;
  p.k = a.int32("k");
  p.min_gap_deg = a.number("min_gap_deg");
  return p;
}

OutlineParams outline_params(const StageArgs& a) {
  OutlineParams p;
  p.alpha = a.number("alpha");
  p.alpha_in_spacings = a.number("alpha_in_spacings");
  p.simplify_in_spacings = a.number("simplify_in_spacings");
  p.offset_in_spacings = a.number("offset_in_spacings");
  p.max_rms_in_spacings = a.number("max_rms_in_spacings");
  p.min_points = static_cast<std::size_t>(a.integer("min_points"));
  return p;
}

void run_boundary(StageRun& run) {
  const StageArgs& a = run.args;
  PointCloud& cloud = run.context.item(run.output).cloud;
  StageRecord& rec = run.record;
  if (cloud.size() < 5) throw InputError(fmt::format("{}; the boundary test needs at least 5", plural(cloud.size(), "point")));
  const KdTree& tree = run.context.tree(run.output);
  const BoundaryResult b = detect_boundary_points(cloud, boundary_params(a), &tree);
  std::vector<double>& field = cloud.fields.add("boundary", cloud.size(), ScalarType::UInt8).values;
  for (std::size_t i = 0; i < field.size(); ++i) field[i] = b.boundary[i];
  rec.count("points", as_count(cloud.size()));
  rec.count("boundary", as_count(b.count));
  // Outlines of the planar segments: the input's "segment" field, else region growing.
  std::vector<std::int32_t> labels(cloud.size(), -1);
  const ScalarField* segments = cloud.fields.find("segment");
  std::string source = "segment field";
  if (segments != nullptr) {
    for (std::size_t i = 0; i < labels.size(); ++i) labels[i] = static_cast<std::int32_t>(segments->values[i]);
  } else {
    if (!cloud.has_normals()) estimate_missing_normals(run, NormalParams{}.k, {});
    labels = segment_region_growing(cloud, {}, &run.context.tree(run.output)).labels;
    source = "region growing";
  }
  const OutlineResult o = outline_planar_segments(cloud, labels, outline_params(a));
  rec.set_used("alpha", o.alpha_used);
  std::vector<Polyline> lines;
  PolylineWriteOptions write;
  write.crs = a.text("crs");
  if (write.crs.empty() && cloud.crs.epsg() > 0) write.crs = fmt::format("EPSG:{}", cloud.crs.epsg());  // the input's own
  std::size_t holes = 0;
  double area = 0.0, length = 0.0;
  for (std::size_t i = 0; i < o.outlines.size(); ++i) {
    const SegmentOutline& s = o.outlines[i];
    std::size_t h = 0;
    for (std::size_t k = 0; k < s.loops.size(); ++k) {
      lines.push_back(s.loops[k]);
      write.group.push_back(s.segment);
      write.hole.push_back(s.hole[k]);
      h += s.hole[k];
    }
    holes += h;
    area += s.area;
    length += s.perimeter;
    // Per outline: segment, area, perimeter, loops, holes.
    rec.metric(fmt::format("outline_{}", i), std::vector<double>{double(s.segment), s.area, s.perimeter, double(s.loops.size()), double(h)});
  }
  rec.count("outlines", as_count(o.outlines.size()));
  rec.count("loops", as_count(lines.size()));
  rec.count("holes", as_count(holes));
  rec.count("nonplanar_segments", as_count(o.nonplanar));
  rec.metric("outline_area", area);
  rec.metric("outline_length", length);
  rec.metric("outline_source", source);
  const std::string& path = a.text("outlines");
  if (!path.empty()) write_polylines(path, lines, write);
  rec.summary = fmt::format("boundary: {} of {} on the boundary; {} outlines ({} loops, {} holes) of planar segments from the {}, area {:.4g}, length {:.4g}{}",
                            b.count, plural(cloud.size(), "point"), o.outlines.size(), lines.size(), holes, source, area, length,
                            path.empty() ? "" : ", written to " + path);
}

}  // namespace

StageSpec boundary_stage() {
  const BoundaryParams b;
  const OutlineParams o;
  StageSpec s;
  s.name = "boundary";
  s.summary = "Boundary points (field \"boundary\", angular gap) and alpha-shape outlines of planar segments, holes included";
  s.description = "Outlines come from the input's \"segment\" field (segment stage), or from region growing when it has none; "
                  "--outlines writes them as .ply edges, .obj lines or .geojson (coordinates in the cloud's own CRS, named by --crs).";
  s.order = 81;
  s.consumes = {Slot{"cloud", DataKind::Any}};
  s.produces = Slot{"cloud", DataKind::Any};
  s.params = {
      P::integer("k", b.k, "Neighbours per point of the angular-gap test").at_least(4),
      P::number("min_gap_deg", b.min_gap_deg, "A point is on the boundary when its neighbours leave a wider gap").unit("degrees").range(0.0, 360.0, true, true),
      P::number("alpha", o.alpha, "Alpha radius of the outlines; 0: alpha_in_spacings x mean spacing").unit("cloud units").non_negative().meta("A"),
      P::number("alpha_in_spacings", o.alpha_in_spacings, "Alpha radius when alpha is 0").unit("mean spacings").positive(),
      P::number("simplify_in_spacings", o.simplify_in_spacings, "Douglas-Peucker tolerance of the loops (0: none)").unit("mean spacings").non_negative(),
      P::number("offset_in_spacings", o.offset_in_spacings, "Loops are moved this far away from the points (outer out, holes in)").unit("mean spacings").non_negative(),
      P::number("max_rms_in_spacings", o.max_rms_in_spacings, "A segment is planar when its RMS distance to its plane is at most this").unit("mean spacings").non_negative(),
      P::integer("min_points", static_cast<std::int64_t>(o.min_points), "Fewest points of an outlined segment").at_least(3),
      P::text("outlines", "", "Write the outlines to this file (.ply, .obj, .geojson)").meta("FILE"),
      P::text("crs", "", "GeoJSON: name of the coordinates' CRS (e.g. EPSG:25832)").meta("CRS"),
  };
  s.examples = {"pointsurf boundary roofs.ply roofs_boundary.ply --outlines roofs.geojson --crs EPSG:25832"};
  s.run = run_boundary;
  s.check = [](const StageArgs& a) {
    boundary_params(a).validate();
    outline_params(a).validate();
  };
  return s;
}

StageSpec segment_stage() {
  const RegionGrowingParams rg;
  const EuclideanParams eu;
  const SurfaceTypeParams hk;
  const PrimitiveParams pr;
  StageSpec s;
  s.name = "segment";
  s.summary = "Split the points into segments: field \"segment\" (-1 unassigned), by region growing, Euclidean clusters, RANSAC primitives or HK surface type";
  s.description = "region: grows over the kNN graph while normals turn less than max_angle_deg, stopping at curved points and "
                  "feature points; euclidean: points closer than the radius; ransac: planes, spheres, cylinders, cones and tori by "
                  "efficient RANSAC (Schnabel et al. 2007), listed in the report; hk: connected regions of one surface_type (run "
                  "curvature first). Segments are numbered by size, largest first.";
  s.order = 80;
  s.consumes = {Slot{"cloud", DataKind::Any}};
  s.produces = Slot{"cloud", DataKind::Any};
  s.methods = {"region", "euclidean", "ransac", "hk"};
  s.default_method = "region";
  s.params = {
      P::integer("k", rg.k, "Neighbours per point (the graph's edges)").at_least(3).only({"region"}),
      P::number("max_angle_deg", rg.max_angle_deg, "Largest angle between neighbouring normals in one segment").unit("degrees").range(0.0, 90.0, true, false).only({"region"}),
      P::number("max_variation", rg.max_variation, "Points of higher surface variation join a segment but do not extend it").range(0.0, 1.0 / 3.0).only({"region"}),
      P::boolean("use_features", rg.use_features, "Feature points (field \"feature\" non-zero) do not extend a segment").only({"region"}),
      P::integer("min_points", static_cast<std::int64_t>(rg.min_points), "Fewest points of a segment; smaller ones are unassigned").at_least(1).only({"region", "euclidean", "hk"}),
      P::number("radius", eu.radius, "Cluster distance; 0: radius_in_spacings x mean spacing").unit("cloud units").non_negative().meta("R").only({"euclidean"}),
      P::number("radius_in_spacings", eu.radius_in_spacings, "Cluster distance when radius is 0").unit("mean spacings").positive().only({"euclidean"}),
      P::integer("k", hk.k, "Neighbours per point (the graph's edges)").at_least(2).only({"hk"}),
      P::text("types", primitive_type_list(pr.types), "Primitive types to detect, comma-separated: plane, sphere, cylinder, cone, torus").meta("LIST").only({"ransac"}),
      P::number("epsilon", pr.epsilon, "A candidate's score counts the points this close; 0: epsilon_in_spacings x mean spacing").unit("cloud units").non_negative().meta("E").only({"ransac"}),
      P::number("epsilon_in_spacings", pr.epsilon_in_spacings, "Scoring distance when epsilon is 0").unit("mean spacings").positive().only({"ransac"}),
      P::number("cluster_epsilon", pr.cluster_epsilon, "Connectivity grid cell; 0: cluster_in_spacings x mean spacing").unit("cloud units").non_negative().meta("C").only({"ransac"}),
      P::number("cluster_in_spacings", pr.cluster_in_spacings, "Connectivity cell when cluster_epsilon is 0").unit("mean spacings").positive().only({"ransac"}),
      P::number("max_normal_deg", pr.max_normal_deg, "Largest angle between a point's normal and the primitive's").unit("degrees").range(0.0, 90.0, true, true).only({"ransac"}),
      P::integer("min_points", static_cast<std::int64_t>(pr.min_points), "Fewest inliers of a primitive; 0: max(30, N / 200)").at_least(0).only({"ransac"}),
      P::number("probability", pr.probability, "Accepted chance of missing a primitive of min_points").range(0.0, 1.0, true, true).only({"ransac"}),
      P::number("band_in_epsilons", pr.band_in_epsilons, "A found primitive takes the points within this many epsilons of its refit").unit("epsilons").at_least(1.0).only({"ransac"}),
      P::integer("seed", static_cast<std::int64_t>(pr.seed), "Random seed").at_least(0).only({"ransac"}),
      P::integer("normals_k", NormalParams{}.k, "Neighbours for normals when the input has none").at_least(3).only({"region", "ransac"}),
  };
  s.examples = {"pointsurf segment part.ply part_segments.ply --method region --max_angle_deg 5",
                "pointsurf segment scene.ply primitives.ply --method ransac --report primitives.json"};
  s.run = run_segment;
  s.check = [](const StageArgs& a) {
    if (a.method() == "region") region_params(a).validate();
    else if (a.method() == "euclidean") euclidean_params(a).validate();
    else if (a.method() == "hk") hk_params(a).validate();
    else primitive_params(a).validate();
  };
  return s;
}

}  // namespace pointsurf::detail
