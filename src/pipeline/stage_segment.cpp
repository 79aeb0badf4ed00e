// SPDX-License-Identifier: GPL-3.0-or-later
// The segment stage: one integer label per point in the field "segment" (-1 unassigned), by
// region growing, Euclidean clusters, RANSAC primitives or HK surface type.
#include <algorithm>
#include <cctype>
#include <filesystem>

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

// What segment reports besides PrimitiveResult and each Primitive (ransac, the primitive i under
// "primitive_<i>/"): the labels of any method.
struct Labels {
  std::size_t points = 0, segments = 0, unassigned = 0;
  bool normals_estimated = false;
};
const ResultTable<Labels>& label_counts() {
  static const ResultTable<Labels> table = [] {
    ResultTable<Labels> t;
    t.count("points", &Labels::points, "Points");
    t.count("segments", &Labels::segments, "Segments (ransac: primitives) found");
    t.count("unassigned", &Labels::unassigned, "Points in no segment (label -1)");
    return t;
  }();
  return table;
}
const ResultTable<Labels>& label_metrics() {
  static const ResultTable<Labels> table = [] {
    ResultTable<Labels> t;
    t.flag("normals_estimated", &Labels::normals_estimated, "The input had no normals: they were estimated");
    return t;
  }();
  return table;
}
std::vector<ResultSpec> segment_specs() {
  std::vector<ResultSpec> out = zero_normals_specs();
  append(out, PrimitiveResult::results().specs());
  append(out, prefixed(Primitive::results().specs(), "primitive_*/"));
  append(out, counted(label_counts().specs()));
  append(out, label_metrics().specs());
  return out;
}

// What boundary reports besides BoundaryResult.
// One outline, under "outline_<i>".
struct OutlineRow {
  const SegmentOutline* outline = nullptr;
  std::size_t holes = 0;
};
const ResultTable<OutlineRow>& outline_metrics() {
  static const ResultTable<OutlineRow> table = [] {
    ResultTable<OutlineRow> t;
    t.computed("", ResultType::Numbers,
               [](const OutlineRow& r) {
                 const SegmentOutline& s = *r.outline;
                 return ResultValue(std::vector<double>{double(s.segment), s.area, s.perimeter, double(s.loops.size()), double(r.holes)});
               },
               "Outline i: segment, area, perimeter, loops, holes");
    return t;
  }();
  return table;
}
struct Outlines {
  std::size_t points = 0, outlines = 0, loops = 0, holes = 0, nonplanar_segments = 0, small_segments = 0;
  double outline_area = 0.0, outline_length = 0.0;
  std::string outline_source;
};
const ResultTable<Outlines>& boundary_points_counts() {
  static const ResultTable<Outlines> table = [] {
    ResultTable<Outlines> t;
    t.count("points", &Outlines::points, "Points");
    return t;
  }();
  return table;
}
const ResultTable<Outlines>& outline_counts() {
  static const ResultTable<Outlines> table = [] {
    ResultTable<Outlines> t;
    t.count("outlines", &Outlines::outlines, "Outlines of planar segments");
    t.count("loops", &Outlines::loops, "Their loops");
    t.count("holes", &Outlines::holes, "Loops that are holes");
    t.count("nonplanar_segments", &Outlines::nonplanar_segments, "Segments skipped as not planar");
    t.count("small_segments", &Outlines::small_segments, "Segments skipped for fewer than min_points points");
    return t;
  }();
  return table;
}
const ResultTable<Outlines>& outline_totals() {
  static const ResultTable<Outlines> table = [] {
    ResultTable<Outlines> t;
    t.number("outline_area", &Outlines::outline_area, "Total area of the outlines").with_unit("square cloud units");
    t.number("outline_length", &Outlines::outline_length, "Total perimeter of the outlines").with_unit("cloud units");
    t.text("outline_source", &Outlines::outline_source, "Where the segments came from (segment field, region growing)");
    return t;
  }();
  return table;
}
std::vector<ResultSpec> boundary_specs() {
  std::vector<ResultSpec> out = counted(boundary_points_counts().specs());
  append(out, BoundaryResult::results().specs());
  append(out, prefixed(outline_metrics().specs(), "outline_*"));
  append(out, counted(outline_counts().specs()));
  append(out, outline_totals().specs());
  return out;
}

void record_primitives(StageRecord& rec, const PrimitiveResult& r) {
  rec.set_used("epsilon_used", r.epsilon_used);
  rec.set_used("cluster_epsilon_used", r.cluster_epsilon_used);
  rec.set_used("min_points", static_cast<std::int64_t>(r.min_points_used));
  rec.add(PrimitiveResult::results(), r);
  for (std::size_t i = 0; i < r.primitives.size(); ++i) rec.add(Primitive::results(), r.primitives[i], fmt::format("primitive_{}/", i));
}

void run_segment(StageRun& run) {
  const StageArgs& a = run.args;
  PointCloud& cloud = run.context.item(run.output).cloud();
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
  std::vector<SegmentPlane>& planes = run.context.item(run.output).segment_planes;
  planes.clear();  // the field "segment" is about to change
  if (method == "region") {
    const SegmentResult r = segment_region_growing(cloud, read_params<RegionGrowingParams>(a), &run.context.tree(run.output), progress);
    labels = r.labels, segments = r.sizes.size(), unassigned = r.unassigned;
  } else if (method == "euclidean") {
    const SegmentResult r = segment_euclidean(cloud, read_params<EuclideanParams>(a), &run.context.tree(run.output));
    labels = r.labels, segments = r.sizes.size(), unassigned = r.unassigned;
  } else if (method == "hk") {
    if (!cloud.fields.contains("surface_type"))
      throw InputError("the input has no \"surface_type\" field; run the curvature stage first (pointsurf curvature)");
    const SegmentResult r = segment_surface_types(cloud, read_params<SurfaceTypeParams>(a), &run.context.tree(run.output));
    labels = r.labels, segments = r.sizes.size(), unassigned = r.unassigned;
  } else {
    const PrimitiveResult r = detect_primitives(cloud, read_params<PrimitiveParams>(a), progress);
    labels = r.labels, segments = r.primitives.size(), unassigned = r.unassigned;
    record_primitives(rec, r);
    // The planes, with their band, for boundary's outlines.
    for (std::size_t i = 0; i < r.primitives.size(); ++i)
      if (r.primitives[i].type == PrimitiveType::Plane)
        planes.push_back({static_cast<std::int32_t>(i), r.primitives[i].point, r.primitives[i].axis, r.epsilon_used});
  }
  std::vector<double>& field = cloud.fields.add("segment", cloud.size(), ScalarType::Int32).values;
  for (std::size_t i = 0; i < labels.size(); ++i) field[i] = labels[i];
  const Labels counts{cloud.size(), segments, unassigned, estimated};
  rec.add_counts(label_counts(), counts);
  rec.add(label_metrics(), counts);
  if (segments == 0) rec.warnings.push_back("no segment was found: every point is unassigned (-1)");
  rec.summary = fmt::format("segment ({}): {} {}, {} of {} unassigned{}", method, segments, method == "ransac" ? "primitives" : "segments",
                            unassigned, plural(cloud.size(), "point"), estimated ? ", normals estimated" : "");
}

void run_boundary(StageRun& run) {
  const StageArgs& a = run.args;
  PointCloud& cloud = run.context.item(run.output).cloud();
  StageRecord& rec = run.record;
  if (cloud.size() < 5) throw InputError(fmt::format("{}; the boundary test needs at least 5", plural(cloud.size(), "point")));
  const KdTree& tree = run.context.tree(run.output);
  const BoundaryResult b = detect_boundary_points(cloud, read_params<BoundaryParams>(a), &tree);
  std::vector<double>& field = cloud.fields.add("boundary", cloud.size(), ScalarType::UInt8).values;
  for (std::size_t i = 0; i < field.size(); ++i) field[i] = b.boundary[i];
  Outlines points;
  points.points = cloud.size();
  rec.add_counts(boundary_points_counts(), points);
  rec.add(BoundaryResult::results(), b);
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
  // A RANSAC segmentation in this pipeline gave its planes: each outlined on its own plane and
  // band, as segment found it (a file read back carries no planes: the least-squares test).
  const std::vector<SegmentPlane>& own = segments != nullptr ? run.context.item(run.output).segment_planes : std::vector<SegmentPlane>{};
  const OutlineParams op = read_params<OutlineParams>(a);
  const OutlineResult o = outline_planar_segments(cloud, labels, op, own);
  std::size_t labelled = 0;
  {
    std::vector<std::int32_t> distinct;
    for (std::int32_t l : labels)
      if (l >= 0) distinct.push_back(l);
    std::sort(distinct.begin(), distinct.end());
    labelled = static_cast<std::size_t>(std::unique(distinct.begin(), distinct.end()) - distinct.begin());
  }
  if (const std::string skipped = describe_skipped(o, labelled, op); !skipped.empty())
    rec.warnings.push_back(skipped + (own.empty() ? "" : "; RANSAC's planes and band were used"));
  rec.set_used("alpha_used", o.alpha_used);
  std::vector<Polyline> lines;
  PolylineWriteOptions write;
  write.crs = a.text("crs");
  if (write.crs.empty() && cloud.crs.epsg() > 0) write.crs = fmt::format("EPSG:{}", cloud.crs.epsg());  // the input's own
  std::size_t holes = 0;
  double area = 0.0, length = 0.0;
  for (std::size_t i = 0; i < o.outlines.size(); ++i) {
    const SegmentOutline& s = o.outlines[i];
    std::size_t h = 0;
    const std::size_t first = lines.size();
    for (std::size_t k = 0; k < s.loops.size(); ++k) {
      lines.push_back(s.loops[k]);
      write.group.push_back(s.segment);
      write.outer.push_back(s.outer[k] < 0 ? -1 : std::int64_t(first) + s.outer[k]);
      h += s.hole[k];
    }
    holes += h;
    area += s.area;
    length += s.perimeter;
    rec.add(outline_metrics(), OutlineRow{&s, h}, fmt::format("outline_{}", i));
  }
  const Outlines totals{cloud.size(), o.outlines.size(), lines.size(), holes, o.nonplanar, o.too_small, area, length, source};
  rec.add_counts(outline_counts(), totals);
  rec.add(outline_totals(), totals);
  const std::string& path = a.text("outlines");
  if (!path.empty()) write_polylines(path, lines, write);
  // GeoJSON names a CRS by its EPSG code: say so when the input's CRS has none (a WKT of its
  // own making) rather than leave the outlines' CRS unnamed silently.
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (write.crs.empty() && !cloud.crs.empty() && (ext == ".geojson" || ext == ".json"))
    rec.warnings.push_back(fmt::format("the GeoJSON outlines name no CRS: the input's CRS is {} (give one with --crs)", cloud.crs.describe()));
  rec.summary = fmt::format("boundary: {} of {} on the boundary; {} outlines ({} loops, {} holes) of planar segments from the {}, area {:.4g}, length {:.4g}{}",
                            b.count, plural(cloud.size(), "point"), o.outlines.size(), lines.size(), holes, source, area, length,
                            path.empty() ? "" : ", written to " + path);
}

}  // namespace

StageSpec boundary_stage() {
  StageSpec s;
  s.name = "boundary";
  s.summary = "Boundary points (field \"boundary\", angular gap) and alpha-shape outlines of planar segments, holes included";
  s.description = "Outlines come from the input's \"segment\" field (segment stage), or from region growing when it has none; "
                  "--outlines writes them as .ply edges, .obj lines or .geojson (coordinates in the cloud's own CRS, named by --crs).";
  s.order = 81;
  s.consumes = {Slot{"cloud", DataKind::Any}};
  s.produces = Slot{"cloud", DataKind::Any};
  s.params = params_of(BoundaryParams::fields());
  append(s.params, params_of(OutlineParams::fields()));
  s.params.push_back(P::text("outlines", "", "Write the outlines to this file (.ply, .obj, .geojson)").meta("FILE"));
  s.params.push_back(P::text("crs", "", "GeoJSON: name of the coordinates' CRS (e.g. EPSG:25832)").meta("CRS"));
  s.examples = {"pointsurf segment data/b9_training.ply roofs.ply --method ransac --types plane",
                "pointsurf boundary roofs.ply roofs_boundary.ply --outlines roofs.geojson --crs EPSG:25832"};
  s.results = boundary_specs();
  s.run = run_boundary;
  s.check = [](const StageArgs& a) {
    read_params<BoundaryParams>(a).validate();
    read_params<OutlineParams>(a).validate();
  };
  return s;
}

StageSpec segment_stage() {
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
  s.params = params_of(RegionGrowingParams::fields(), {"region"});
  append(s.params, params_of(EuclideanParams::fields(), {"euclidean"}));
  append(s.params, params_of(SurfaceTypeParams::fields(), {"hk"}));
  append(s.params, params_of(PrimitiveParams::fields(), {"ransac"}));
  s.params.push_back(P::integer("normals_k", NormalParams{}.k, "Neighbours for normals when the input has none").at_least(3).only({"region", "ransac"}));
  s.examples = {"pointsurf segment data/kitten.xyz kitten_segments.ply --method region --max-angle-deg 5",
                "pointsurf segment data/b9_training.ply primitives.ply --method ransac --report primitives.json"};
  s.results = segment_specs();
  s.run = run_segment;
  s.check = [](const StageArgs& a) {
    if (a.method() == "region") read_params<RegionGrowingParams>(a).validate();
    else if (a.method() == "euclidean") read_params<EuclideanParams>(a).validate();
    else if (a.method() == "hk") read_params<SurfaceTypeParams>(a).validate();
    else read_params<PrimitiveParams>(a).validate();
  };
  return s;
}

}  // namespace pointsurf::detail
