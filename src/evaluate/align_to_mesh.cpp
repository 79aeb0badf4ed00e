// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/evaluate/align_to_mesh.h"

#include <cmath>
#include <vector>

#include <Eigen/Geometry>
#include <fmt/format.h>

#include "pointsurf/core/error.h"
#include "pointsurf/evaluate/mesh_distance.h"
#include "pointsurf/evaluate/surface_distance.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf {
namespace {

Vector3d face_normal(const TriangleMesh& mesh, const Triangle& t) {
  const Vector3d& a = mesh.vertices.positions[static_cast<std::size_t>(t[0])];
  return (mesh.vertices.positions[static_cast<std::size_t>(t[1])] - a).cross(mesh.vertices.positions[static_cast<std::size_t>(t[2])] - a);
}

// ICP's target: samples with their triangle's normal, or the vertices with area-weighted normals.
PointCloud mesh_target(const TriangleMesh& mesh, std::size_t samples, std::uint64_t seed) {
  PointCloud target;
  if (samples > 0) {
    std::vector<std::uint32_t> triangle_of;
    target.positions = sample_mesh_surface(mesh.vertices.positions, mesh.triangles, samples, seed, &triangle_of);
    target.normals.resize(target.positions.size());
    for (std::size_t i = 0; i < triangle_of.size(); ++i) target.normals[i] = face_normal(mesh, mesh.triangles[triangle_of[i]]).normalized();
    return target;
  }
  std::vector<Vector3d> normals(mesh.vertices.positions.size(), Vector3d::Zero());
  std::vector<char> used(mesh.vertices.positions.size(), 0);
  for (const Triangle& t : mesh.triangles) {
    const Vector3d n = face_normal(mesh, t);  // |n| = twice the area: area weighting for free
    for (int c = 0; c < 3; ++c) {
      normals[static_cast<std::size_t>(t[c])] += n;
      used[static_cast<std::size_t>(t[c])] = 1;
    }
  }
  for (std::size_t v = 0; v < mesh.vertices.positions.size(); ++v)
    if (used[v]) {
      target.positions.push_back(mesh.vertices.positions[v]);
      target.normals.push_back(normals[v].norm() > 0.0 ? Vector3d(normals[v].normalized()) : Vector3d::Zero());
    }
  return target;
}

}  // namespace

const FieldTable<MeshAlignParams>& MeshAlignParams::fields() {
  static const FieldTable<MeshAlignParams> table = [] {
    using P = MeshAlignParams;
    FieldTable<P> t;
    // Keyed as the evaluate stage offers them; samples and seed there are the stage's own.
    t.integer("align_samples", &P::samples, "Points sampled on the mesh as ICP's target; 0: the mesh's vertices").unit("points").internal();
    t.integer("align_seed", &P::seed, "Seed of the sampling").internal();
    t.length("align_max_distance", &P::max_distance, "Pairs farther apart are ignored while aligning").positive();
    t.integer("align_iterations", &P::max_iterations, "ICP iterations at most while aligning").range(1, 100000);
    t.number("align_relative_rmse", &P::relative_rmse, "Converged when the RMSE changes by less than this relative amount").non_negative().internal();
    return t;
  }();
  return table;
}

void MeshAlignParams::validate() const { fields().validate(*this, "align_to_mesh"); }

RegistrationResult align_to_mesh(std::span<const Vector3d> points, const TriangleMesh& mesh, const MeshAlignParams& params,
                                 const ProgressCallback& progress) {
  params.validate();
  check_measurable_mesh(mesh, "align_to_mesh: the mesh");
  PointCloud scan;
  scan.positions.assign(points.begin(), points.end());
  const PointCloud target = mesh_target(mesh, params.samples, params.seed);
  if (target.size() < 3) {
    RegistrationResult r;
    r.message = "the mesh has no area to sample";
    return r;
  }
  IcpParams icp_params;
  icp_params.metric = IcpMetric::PointToPlane;
  icp_params.max_normal_deg = 180.0;
  icp_params.max_iterations = params.max_iterations;
  icp_params.relative_rmse = params.relative_rmse;
  icp_params.max_distance = params.max_distance;  // a length in spacings is resolved by ICP against the scan
  const KdTree tree(target.positions);
  return icp(scan, target, tree, RigidTransform(), icp_params, progress);
}

const ResultTable<RegistrationResult>& mesh_alignment_results() {
  static const ResultTable<RegistrationResult> table = [] {
    using R = RegistrationResult;
    ResultTable<R> t;
    t.computed("matrix", ResultType::Numbers,
               [](const R& r) {
                 const Eigen::Matrix4d m = r.transform.matrix();
                 std::vector<double> matrix;
                 for (int i = 0; i < 4; ++i)
                   for (int j = 0; j < 4; ++j) matrix.push_back(m(i, j));
                 return ResultValue(std::move(matrix));
               },
               "4x4 row by row: maps the reference as read onto the mesh");
    t.computed("rotation_deg", ResultType::Number, [](const R& r) { return ResultValue(r.transform.angle_degrees()); }, "Rotation angle of the fit")
        .with_unit("degrees");
    t.computed("translation", ResultType::Numbers,
               [](const R& r) {
                 const Eigen::Matrix4d m = r.transform.matrix();
                 return ResultValue(std::vector<double>{m(0, 3), m(1, 3), m(2, 3)});
               },
               "Translation of the fit")
        .with_unit("cloud units");
    t.number("fitness", &R::fitness, "Share of reference points within the fit's distance").higher_is_better();
    t.number("inlier_rmse", &R::inlier_rmse, "RMS distance of those points").with_unit("cloud units").lower_is_better();
    t.computed("iterations", ResultType::Integer, [](const R& r) { return ResultValue(std::int64_t(r.iterations)); }, "ICP iterations");
    t.flag("converged", &R::converged, "The fit converged").higher_is_better();
    t.text("message", &R::message, "How the fit ended");
    return t;
  }();
  return table;
}

}  // namespace pointsurf
