// SPDX-License-Identifier: GPL-3.0-or-later
#include "support/scan_views.h"

#include <cmath>
#include <filesystem>
#include <random>

#include <Eigen/Geometry>

#include "pointsurf/io/io.h"

namespace pointsurf::test {

Eigen::Vector3d centroid(const PointCloud& cloud) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : cloud.positions) sum += p;
  return sum / double(cloud.size());
}

const PointCloud& kitten() {
  static const PointCloud cloud = read_point_cloud(std::filesystem::path(POINTSURF_DATA_DIR) / "kitten.xyz").cloud;
  return cloud;
}

ScanViews scan_views(std::size_t n, double sigma_in_spacings, std::uint64_t seed, double step_deg) {
  const PointCloud& k = kitten();
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  ScanViews s;
  for (std::size_t v = 0; v < n; ++v) {
    const double a = step_deg > 0.0 ? step_deg * M_PI / 180.0 * double(v) : 2.0 * M_PI * double(v) / double(n);
    const Eigen::Vector3d view(3.0 * std::cos(a), 0.2, 3.0 * std::sin(a));
    PointCloud scan;
    for (std::size_t i = 0; i < k.size(); ++i) {
      if (k.normals[i].dot(view - k.positions[i]) <= 0.0 || u(rng) > 0.8) continue;
      scan.positions.push_back(k.positions[i] + sigma_in_spacings * kKittenSpacing * Eigen::Vector3d(g(rng), g(rng), g(rng)));
      scan.normals.push_back(k.normals[i]);
    }
    RigidTransform pose;
    if (v > 0) {
      const Eigen::Vector3d axis = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
      pose = RigidTransform(Eigen::AngleAxisd(0.6 * u(rng) + 0.2, axis).toRotationMatrix(), 0.3 * Eigen::Vector3d(g(rng), g(rng), g(rng)));
    }
    pose.inverse().apply(scan);  // into the scan's own frame
    s.clouds.push_back(std::move(scan));
    s.truth.push_back(pose);
  }
  return s;
}

}  // namespace pointsurf::test
