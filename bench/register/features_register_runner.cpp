// SPDX-License-Identifier: GPL-3.0-or-later
// Stage runner for bench/register/features_bench.sh: times pointsurf's FPFH, PFH and RANSAC
// alignment on a prepared pair (voxel-downsampled clouds with normals, written by
// features_open3d.py prep, the same files Open3D reads) and scores the pose against the truth.
//   features_register_runner SOURCE.ply TARGET.ply TRUTH.json VOXEL SEED [pfh]
// With "pfh", PFH descriptors are timed too and aligned with the same RANSAC. Environment:
// MAX_NORMAL_DEG (default 45) and MUTUAL (1/0) change those two alignment settings.
// Parameters as Open3D's global-registration recipe, from the voxel size: descriptor radius
// 5 voxels with at most 100 neighbours, max correspondence distance 1.5 voxels, edge-length
// ratio 0.9, 100000 trials at most, confidence 0.999, mutual matches. Prints one JSON line.
// Time of a step: FPFH = both kd-trees + both clouds' descriptors (Open3D builds its trees
// inside compute_fpfh_feature); RANSAC = matching + RANSAC + fitness (the target tree reused).
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "../bench_util.h"
#include "pointsurf/io/io.h"
#include "pointsurf/register/align.h"
#include "pointsurf/register/features.h"
#include "pointsurf/spatial/kd_tree.h"

using namespace pointsurf;
using bench::Clock;
using bench::seconds_since;

int main(int argc, char** argv) {
  if (argc < 6) {
    std::fprintf(stderr, "usage: features_register_runner SOURCE.ply TARGET.ply TRUTH.json VOXEL SEED [pfh]\n");
    return 1;
  }
  const PointCloud source = read_point_cloud(argv[1]).cloud;
  const PointCloud target = read_point_cloud(argv[2]).cloud;
  nlohmann::json truth_json;
  std::ifstream(argv[3]) >> truth_json;
  Eigen::Matrix4d m;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) m(r, c) = truth_json["matrix"][r][c].get<double>();
  const RigidTransform truth = RigidTransform::from_matrix(m);
  const double voxel = std::stod(argv[4]);
  const std::uint64_t seed = std::stoull(argv[5]);
  const bool with_pfh = argc > 6 && std::string(argv[6]) == "pfh";

  DescriptorParams fp;
  fp.radius = Length::cloud(5.0 * voxel);
  fp.max_neighbors = 100;
  auto t0 = Clock::now();
  const KdTree source_tree(source.positions), target_tree(target.positions);
  const Descriptors fs = compute_descriptors(source, source_tree, fp);
  const Descriptors ft = compute_descriptors(target, target_tree, fp);
  const double fpfh_s = seconds_since(t0);

  AlignParams ap;
  ap.max_distance = Length::cloud(1.5 * voxel);
  ap.edge_length_ratio = 0.9;
  ap.max_iterations = 100000;
  ap.confidence = 0.999;
  ap.mutual = true;
  ap.seed = seed;
  if (const char* deg = std::getenv("MAX_NORMAL_DEG")) ap.max_normal_deg = std::stod(deg);
  if (const char* mu = std::getenv("MUTUAL")) ap.mutual = std::string(mu) == "1";
  t0 = Clock::now();
  const RegistrationResult r = align_global(source, fs, target, ft, target_tree, ap);
  const double ransac_s = seconds_since(t0);

  const Eigen::Vector3d at = bounding_box(source.positions).center();

  // PFH on the same pair, as the paper compares them: descriptor time and the pose it gives.
  nlohmann::json pfh = {{"pfh_s", nullptr}, {"pfh_ransac_s", nullptr}, {"pfh_rotation_error_deg", nullptr}};
  if (with_pfh) {
    DescriptorParams pp = fp;
    pp.type = DescriptorType::Pfh;
    t0 = Clock::now();
    const KdTree s2(source.positions), t2(target.positions);
    const Descriptors ps = compute_descriptors(source, s2, pp);
    const Descriptors pt = compute_descriptors(target, t2, pp);
    pfh["pfh_s"] = seconds_since(t0);
    t0 = Clock::now();
    const RegistrationResult rp = align_global(source, ps, target, pt, t2, ap);
    pfh["pfh_ransac_s"] = seconds_since(t0);
    pfh["pfh_rotation_error_deg"] = RigidTransform::rotation_error_degrees(rp.transform, truth);
  }

  const nlohmann::json out = {{"tool", "pointsurf"},
                              {"points_source", source.size()},
                              {"points_target", target.size()},
                              {"fpfh_s", fpfh_s},
                              {"ransac_s", ransac_s},
                              {"total_s", fpfh_s + ransac_s},
                              {"rotation_error_deg", RigidTransform::rotation_error_degrees(r.transform, truth)},
                              {"translation_error", RigidTransform::translation_error(r.transform, truth, at)},
                              {"fitness", r.fitness},
                              {"inlier_rmse", r.inlier_rmse},
                              {"correspondences", r.correspondences},
                              {"iterations", r.iterations},
                              {"converged", r.converged},
                              {"message", r.message}};
  nlohmann::json line = out;
  line.update(pfh);
  std::printf("%s\n", line.dump().c_str());
  return 0;
}
