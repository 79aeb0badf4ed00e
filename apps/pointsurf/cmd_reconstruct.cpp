// SPDX-License-Identifier: GPL-3.0-or-later
// pointsurf reconstruct IN OUT: a triangle mesh through the points (region-growing
// triangulation by default; Crust or ball pivoting on request), with its holes reported.
#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "cli_common.h"
#include "pointsurf/core/error.h"
#include "pointsurf/normals/normals.h"
#include "pointsurf/reconstruct/ball_pivot.h"
#include "pointsurf/reconstruct/crust.h"
#include "pointsurf/reconstruct/triangulate.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf::cli {
namespace {

struct ReconstructState {
  CommonOptions common;
  OutputOptions output;
  std::string input, output_path;
  std::string method = "triangulate";
  // Normals, when the input has none (PCA over k neighbours, MST orientation).
  int normals_k = 30;
  // Region-growing triangulation.
  TriangulateParams triangulate;
  // Crust.
  CrustParams crust;
  std::string crust_boundary = "auto";
  // Ball pivoting.
  std::string radii, radii_in_spacings;
  double bp_max_normal_angle_deg = BallPivotParams{}.max_normal_angle_deg;
  double bp_max_mean_normal_angle_deg = BallPivotParams{}.max_mean_normal_angle_deg;
  bool bp_keep_small_holes = false;
};

std::vector<double> parse_list(const std::string& text, const std::string& option) {
  std::vector<double> values;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    try {
      std::size_t used = 0;
      const double v = std::stod(item, &used);
      if (used != item.size() || !(v > 0.0) || !std::isfinite(v)) throw std::invalid_argument(item);
      values.push_back(v);
    } catch (const std::exception&) {
      throw UsageError(fmt::format("{}: '{}': expected positive numbers separated by commas", option, text));
    }
  }
  if (values.empty()) throw UsageError(fmt::format("{}: '{}': expected positive numbers separated by commas", option, text));
  return values;
}

CrustBoundary parse_boundary(const std::string& name) {
  if (name == "auto") return CrustBoundary::Auto;
  if (name == "closed") return CrustBoundary::Closed;
  if (name == "open") return CrustBoundary::Open;
  throw UsageError(fmt::format("--boundary: '{}': expected auto, closed or open", name));
}

void check_range(const std::string& option, double value, double low, double high, bool low_open, bool high_open) {
  const bool ok = std::isfinite(value) && (low_open ? value > low : value >= low) && (high_open ? value < high : value <= high);
  if (!ok)
    throw UsageError(fmt::format("--{}: {} must be in {}{}, {}{}", option, value, low_open ? "(" : "[", low, high, high_open ? ")" : "]"));
}

// Genus of the result when it is one connected, edge-manifold, oriented surface whose boundary
// edges all lie on the reported loops: (2 - chi - holes) / 2 (a closed surface has no holes);
// -1 otherwise.
long surface_genus(const MeshTopology& t) {
  std::size_t loop_edges = 0;
  for (const BoundaryLoop& loop : t.boundary_loops) loop_edges += loop.vertices.size();
  if (t.components != 1 || !t.edge_manifold() || !t.oriented() || loop_edges != t.boundary_edges) return -1;
  const long twice = 2 - t.euler_characteristic - long(t.boundary_loops.size());
  return twice >= 0 && twice % 2 == 0 ? twice / 2 : -1;
}

double total_hole_perimeter(const MeshTopology& t) {
  double total = 0.0;
  for (const BoundaryLoop& loop : t.boundary_loops) total += loop.length;
  return total;
}

// Holes and manifoldness of the result, for the report and the summary.
nlohmann::json topology_metrics(const ReconstructionResult& r) {
  const MeshTopology& t = r.topology;
  return {{"triangles", t.triangles},
          {"vertices_used", t.vertices},
          {"unused_points", r.unused_points},
          {"boundary_edges", t.boundary_edges},
          {"holes", t.boundary_loops.size()},
          {"holes_total_perimeter", total_hole_perimeter(t)},
          {"largest_hole_perimeter", t.boundary_loops.empty() ? 0.0 : t.boundary_loops.front().length},
          {"non_manifold_edges", t.non_manifold_edges},
          {"non_manifold_vertices", t.non_manifold_vertices},
          {"inconsistent_edges", t.inconsistent_edges},
          {"components", t.components},
          {"euler_characteristic", t.euler_characteristic},
          {"genus", surface_genus(t)},
          {"watertight", t.watertight()},
          {"mean_spacing", r.mean_spacing}};
}

void run_reconstruct(const ReconstructState& s) {
  if (s.method != "triangulate" && s.method != "crust" && s.method != "ball-pivot")
    throw UsageError(fmt::format("--method: '{}': expected triangulate, crust or ball-pivot", s.method));
  if (s.normals_k < 3) throw UsageError(fmt::format("--normals-k: {} must be at least 3", s.normals_k));
  const TriangulateParams& tp = s.triangulate;
  if (tp.k < 3) throw UsageError(fmt::format("--k: {} must be at least 3", tp.k));
  if (!(tp.radius >= 0.0) || !std::isfinite(tp.radius)) throw UsageError(fmt::format("--radius: {} must be >= 0", tp.radius));
  check_range("radius-in-spacings", tp.radius_in_spacings, 0.0, INFINITY, true, true);
  check_range("max-offset", tp.max_offset_in_spacings, 0.0, INFINITY, true, true);
  check_range("max-normal-angle", tp.max_normal_angle_deg, 0.0, 180.0, true, false);
  check_range("min-angle", tp.min_angle_deg, 0.0, 60.0, false, true);
  check_range("max-angle", tp.max_angle_deg, 60.0, 180.0, true, false);
  check_range("max-dihedral", tp.max_dihedral_deg, 0.0, 180.0, true, false);
  check_range("fill-holes", tp.max_hole_perimeter_in_spacings, 0.0, INFINITY, false, true);
  check_range("max-front-angle", tp.max_front_angle_deg, 0.0, 180.0, false, true);
  check_range("cocone-angle", s.crust.cocone_angle_deg, 0.0, 90.0, true, true);
  check_range("crust-normal-angle", s.crust.normal_filter_angle_deg, 0.0, 90.0, true, false);
  check_range("sharp-edge-angle", s.crust.sharp_edge_angle_deg, 180.0, 360.0, false, false);
  check_range("crust-rim-edge", s.crust.max_boundary_edge_in_spacings, 0.0, INFINITY, false, true);
  if (s.crust.max_hole_edges < 0) throw UsageError(fmt::format("--crust-fill-holes: {} must be >= 0", s.crust.max_hole_edges));
  CrustParams crust = s.crust;
  crust.boundary = parse_boundary(s.crust_boundary);
  BallPivotParams ball;
  if (!s.radii.empty()) ball.radii = parse_list(s.radii, "--radii");
  if (!s.radii_in_spacings.empty()) ball.radii_in_spacings = parse_list(s.radii_in_spacings, "--radii-in-spacings");
  check_range("ball-normal-angle", s.bp_max_normal_angle_deg, 0.0, 180.0, true, false);
  check_range("ball-mean-normal-angle", s.bp_max_mean_normal_angle_deg, 0.0, 180.0, true, false);
  ball.max_normal_angle_deg = s.bp_max_normal_angle_deg;
  ball.max_mean_normal_angle_deg = s.bp_max_mean_normal_angle_deg;
  ball.close_small_holes = !s.bp_keep_small_holes;
  const WriteOptions write_options = s.output.to_write_options();
  // An unknown output extension fails now, not after the work.
  const std::string out_format = write_options.format.empty() ? format_from_extension(s.output_path) : write_options.format;

  Report report("reconstruct");
  nlohmann::json& parameters = report.parameters();
  parameters = {{"input", s.input}, {"output", s.output_path}, {"method", s.method}, {"normals_k", s.normals_k}};
  if (s.method == "triangulate")
    parameters.update({{"k", tp.k},
                       {"radius", tp.radius},
                       {"radius_in_spacings", tp.radius_in_spacings},
                       {"max_offset_in_spacings", tp.max_offset_in_spacings},
                       {"max_normal_angle_deg", tp.max_normal_angle_deg},
                       {"min_angle_deg", tp.min_angle_deg},
                       {"max_angle_deg", tp.max_angle_deg},
                       {"max_dihedral_deg", tp.max_dihedral_deg},
                       {"max_hole_perimeter_in_spacings", tp.max_hole_perimeter_in_spacings},
                       {"max_front_angle_deg", tp.max_front_angle_deg}});
  if (s.method == "crust")
    parameters.update({{"cocone_angle_deg", crust.cocone_angle_deg},
                       {"normal_filter_angle_deg", crust.normal_filter_angle_deg},
                       {"sharp_edge_angle_deg", crust.sharp_edge_angle_deg},
                       {"max_boundary_edge_in_spacings", crust.max_boundary_edge_in_spacings},
                       {"max_hole_edges", crust.max_hole_edges},
                       {"boundary", s.crust_boundary}});
  if (s.method == "ball-pivot")
    parameters.update({{"radii", ball.radii},
                       {"radii_in_spacings", ball.radii_in_spacings},
                       {"max_normal_angle_deg", ball.max_normal_angle_deg},
                       {"max_mean_normal_angle_deg", ball.max_mean_normal_angle_deg},
                       {"close_small_holes", ball.close_small_holes}});

  PointCloud cloud = read_cloud_reported(s.input, s.common, report).cloud;
  if (cloud.size() < 3) throw InputError(fmt::format("{}: {} points; a surface needs at least 3", s.input, cloud.size()));

  std::size_t stage = report.begin_stage("kdtree");
  const KdTree tree(cloud.positions);
  const double spacing = mean_spacing(tree);
  report.end_stage(stage);
  report.stage(stage)["metrics"]["mean_spacing"] = spacing;
  if (!(spacing > 0.0)) throw InputError(fmt::format("{}: all {} points coincide; no surface can be built", s.input, cloud.size()));

  // Crust needs no normals; the others need oriented ones: estimated here when absent (and said
  // so in the report's "normals" stage and in the summary line).
  const bool estimated_normals = s.method != "crust" && !cloud.has_normals();
  if (estimated_normals) {
    estimate_missing_normals(cloud, tree, s.normals_k, s.common, report);
    report.warn(fmt::format("{}: no normals in the input; estimated (PCA, k = {}) and MST-oriented", s.input, s.normals_k), s.common.quiet);
  }

  stage = report.begin_stage(s.method);
  ReconstructionResult result;
  nlohmann::json method_counts = nlohmann::json::object();
  {
    ProgressBar bar(s.method, !s.common.quiet);
    if (s.method == "triangulate") {
      TriangulateResult r = reconstruct_region_growing(cloud, tp, &tree, bar.callback());
      method_counts = {{"candidate_triangles", r.candidate_triangles},
                       {"selected_triangles", r.selected_triangles},
                       {"holes_filled", r.holes_filled},
                       {"fill_triangles", r.fill_triangles},
                       {"duplicate_points", r.duplicate_points},
                       {"local_spacing_mean", r.local_spacing_mean}};
      result = std::move(r);
    } else if (s.method == "crust") {
      CrustStats stats;
      result = reconstruct_crust(cloud, crust, bar.callback(), &stats);
      method_counts = {{"duplicate_points", stats.duplicate_points}, {"delaunay_cells", stats.delaunay_cells},
                       {"cocone_triangles", stats.cocone_triangles}, {"normal_filtered", stats.normal_filtered},
                       {"pruned", stats.pruned},                     {"open_pieces", stats.open_pieces},
                       {"closed_pieces", stats.closed_pieces}};
    } else {
      result = reconstruct_ball_pivoting(cloud, ball, &tree, bar.callback());
      std::vector<double> radii = ball.radii;
      if (radii.empty())
        for (const double f : ball.radii_in_spacings) radii.push_back(f * result.mean_spacing);
      std::sort(radii.begin(), radii.end());
      method_counts = {{"radii_used", radii}};
    }
  }
  report.end_stage(stage);
  report.stage(stage)["counts"] = method_counts;
  report.stage(stage)["metrics"] = topology_metrics(result);
  const MeshTopology& topo = result.topology;
  if (topo.triangles == 0)
    throw ComputeError(fmt::format("{}: no triangle could be formed from {} points (collinear, too sparse, or no usable normals?)",
                                   s.input, cloud.size()));
  if (topo.boundary_loops.size() > 0)
    report.warn(fmt::format("{} holes remain (total perimeter {:.4g}, largest {:.4g})", topo.boundary_loops.size(),
                            total_hole_perimeter(topo),
                            topo.boundary_loops.front().length),
                s.common.quiet);
  if (topo.non_manifold_edges > 0) report.warn(fmt::format("{} non-manifold edges", topo.non_manifold_edges), s.common.quiet);

  TriangleMesh& mesh = result.mesh;
  if (mesh.vertex_normals.empty() && cloud.has_normals() && mesh.vertices.size() == cloud.size()) mesh.vertex_normals = cloud.normals;
  warn_lost_attributes(s.output_path, !mesh.vertex_normals.empty(), !mesh.vertex_colors.empty(), mesh.vertex_fields, mesh.triangle_count(),
                       write_options, s.common, report);
  stage = report.begin_stage("write");
  write_mesh(s.output_path, mesh, write_options);
  report.end_stage(stage);
  const bool holds_faces = out_format == "ply" || out_format == "off" || out_format == "obj" || out_format == "stl";
  const std::size_t faces_written = holds_faces ? mesh.triangle_count() : 0;
  report.stage(stage)["counts"] = {{"points", mesh.vertex_count()}, {"faces", faces_written}};
  report.add_output({{"path", s.output_path}, {"format", out_format}, {"points", mesh.vertex_count()}, {"faces", faces_written}});
  report.finish();
  if (!s.common.report_path.empty()) report.write(s.common.report_path);
  if (!s.common.quiet)
    fmt::print(stderr,
               "{} -> {}: {} {} triangles from {} points{}; {} holes (perimeter {:.4g}), {} non-manifold edges, {} components, "
               "genus {}, {:.2f} s\n",
               s.input, s.output_path, s.method, topo.triangles, cloud.size(), estimated_normals ? " (normals estimated)" : "",
               topo.boundary_loops.size(), total_hole_perimeter(topo), topo.non_manifold_edges, topo.components,
               surface_genus(topo) >= 0 ? std::to_string(surface_genus(topo)) : std::string("-"),
               report.json()["total_seconds"].get<double>());
}

}  // namespace

Command register_reconstruct(CLI::App& app) {
  auto state = std::make_shared<ReconstructState>();
  ReconstructState& s = *state;
  CLI::App* cmd = app.add_subcommand(
      "reconstruct", "Triangle mesh through the points: region-growing triangulation (default), Crust or ball pivoting");
  cmd->add_option("input", s.input, "Input cloud (normals are estimated and MST-oriented when absent)")->required();
  cmd->add_option("output", s.output_path, "Output mesh with vertex normals (.ply .off .obj .stl)")->required();
  cmd->add_option("--method", s.method, "triangulate (region growing, default), crust or ball-pivot")->type_name("METHOD");
  cmd->add_option("--normals-k", s.normals_k, "Neighbours for normals when the input has none (default 30)");
  // triangulate
  cmd->add_option("--k", s.triangulate.k, "triangulate: at most k neighbours per point (default 30)");
  cmd->add_option("--radius", s.triangulate.radius, "triangulate: search radius and longest edge, cloud units (default: from local spacing)")
      ->type_name("R");
  cmd->add_option("--radius-in-spacings", s.triangulate.radius_in_spacings, "triangulate: radius in local spacings when --radius is 0 (default 3)");
  cmd->add_option("--max-offset", s.triangulate.max_offset_in_spacings,
                  "triangulate: ignore neighbours farther from the tangent plane, local spacings (default 1.25)");
  cmd->add_option("--max-normal-angle", s.triangulate.max_normal_angle_deg,
                  "triangulate: ignore neighbours whose normal deviates more, degrees (default 120)");
  cmd->add_option("--min-angle", s.triangulate.min_angle_deg, "triangulate: smallest inner angle, degrees (default 5)");
  cmd->add_option("--max-angle", s.triangulate.max_angle_deg, "triangulate: largest inner angle, degrees (default 160)");
  cmd->add_option("--max-dihedral", s.triangulate.max_dihedral_deg,
                  "triangulate: largest angle between neighbouring triangle normals, degrees (default 135)");
  cmd->add_option("--fill-holes", s.triangulate.max_hole_perimeter_in_spacings,
                  fmt::format("triangulate: close holes up to this perimeter in local spacings, 0: none (default {})",
                              TriangulateParams{}.max_hole_perimeter_in_spacings));
  cmd->add_option("--max-front-angle", s.triangulate.max_front_angle_deg,
                  fmt::format("triangulate: after growing, close boundary corners opening less than this, degrees; 0: off (default {})",
                              TriangulateParams{}.max_front_angle_deg));
  // crust
  cmd->add_option("--cocone-angle", s.crust.cocone_angle_deg, "crust: cocone half-angle theta, degrees (default 22.5)");
  cmd->add_option("--crust-normal-angle", s.crust.normal_filter_angle_deg,
                  "crust: drop triangles deviating more from the pole vectors, degrees; 90 disables (default 60)");
  cmd->add_option("--sharp-edge-angle", s.crust.sharp_edge_angle_deg, "crust: sharp-edge pruning gap, degrees; 360 disables (default 270)");
  cmd->add_option("--boundary", s.crust_boundary, "crust: auto, closed or open (default auto)")->type_name("KIND");
  cmd->add_option("--crust-rim-edge", s.crust.max_boundary_edge_in_spacings,
                  fmt::format("crust: peel rim triangles with a boundary edge longer than this, mean spacings; 0: off (default {})",
                              CrustParams{}.max_boundary_edge_in_spacings));
  cmd->add_option("--crust-fill-holes", s.crust.max_hole_edges,
                  fmt::format("crust: close holes of at most this many edges; 0: off (default {})", CrustParams{}.max_hole_edges));
  // ball pivoting
  cmd->add_option("--radii", s.radii, "ball-pivot: ball radii, cloud units (default: from --radii-in-spacings)")->type_name("R1,R2,...");
  cmd->add_option("--radii-in-spacings", s.radii_in_spacings, "ball-pivot: radii in mean spacings (default 1.5,3,6)")->type_name("A,B,...");
  cmd->add_option("--ball-normal-angle", s.bp_max_normal_angle_deg,
                  "ball-pivot: largest angle between a triangle and each vertex normal, degrees (default 100)");
  cmd->add_option("--ball-mean-normal-angle", s.bp_max_mean_normal_angle_deg,
                  "ball-pivot: largest angle between a triangle and its mean vertex normal, degrees (default 65)");
  cmd->add_flag("--ball-keep-small-holes", s.bp_keep_small_holes,
                "ball-pivot: skip the final pass that closes holes of up to 6 edges within the largest ball");
  add_common_options(*cmd, s.common);
  add_output_options(*cmd, s.output);
  return {cmd, [state] { run_reconstruct(*state); }, &state->common};
}

const CommandRegistration reconstruct_registration{120, register_reconstruct};

}  // namespace pointsurf::cli
