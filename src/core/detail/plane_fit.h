// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Plane hypotheses for RANSAC: seeding by coordinates, the MSAC score, the least-squares refit.
// Shared by clean's local-plane outlier test and shape's primitive detection.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <optional>
#include <span>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

namespace pointsurf::detail {

/// SplitMix64: a small, good mixer for per-point seeds and RNG streams.
inline std::uint64_t mix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

/// A point's random stream: from the seed and its coordinates only (not its index), so that
/// results do not depend on the order of the points.
inline std::uint64_t seed_for(std::uint64_t seed, const Eigen::Vector3d& p) {
  return mix(seed ^ mix(std::bit_cast<std::uint64_t>(p.x()) ^
                        mix(std::bit_cast<std::uint64_t>(p.y()) ^ mix(std::bit_cast<std::uint64_t>(p.z())))));
}

/// A uniform double in [0, 1) from the stream `state` (advanced).
inline double uniform01(std::uint64_t& state) { return double((state = mix(state)) >> 11) * 0x1.0p-53; }

/// A plane normal . x + offset = 0.
struct Plane {
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  double offset = 0.0;
  double rms = 0.0;       // refitted planes: RMS distance of the inliers they were fitted to
  bool surrounds = true;  // refitted planes: the origin's foot lies within the inliers' spread
  double score = 0.0;     // candidates: their MSAC score
};

/// How well a plane fits points: how many lie within `distance` (its support) and the MSAC
/// score sum(1 - r^2 / distance^2) over those, which prefers a surface (residuals at the noise
/// level) to a plane cutting across creases (residuals spread over the whole band).
struct PlaneFit {
  std::size_t support = 0;
  double score = 0.0;
};

inline PlaneFit msac_fit(std::span<const Eigen::Vector3d> q, const Plane& plane, double distance) {
  PlaneFit fit;
  const double inverse = 1.0 / (distance * distance);
  for (const Eigen::Vector3d& x : q) {
    const double r = plane.normal.dot(x) + plane.offset;
    if (std::abs(r) > distance) continue;
    ++fit.support;
    fit.score += 1.0 - r * r * inverse;
  }
  return fit;
}

/// Running sums of points for a least-squares plane.
struct PlaneMoments {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
  std::size_t count = 0;
  void add(const Eigen::Vector3d& x) {
    sum += x;
    outer.noalias() += x * x.transpose();
    ++count;
  }
};

/// The least-squares plane of the moments (PCA: normal along the smallest eigenvector); nullopt
/// when fewer than 3 points or when they are collinear (middle eigenvalue below
/// min_sine^2 times the largest). `spread`: the origin's foot must lie within this many in-plane
/// standard deviations of the centroid for `surrounds`.
inline std::optional<Plane> fit_plane(const PlaneMoments& m, double min_sine, double spread) {
  if (m.count < 3) return std::nullopt;
  const Eigen::Vector3d centroid = m.sum / double(m.count);
  const Eigen::Matrix3d covariance = m.outer / double(m.count) - centroid * centroid.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen;
  eigen.computeDirect(covariance);
  const Eigen::Vector3d values = eigen.eigenvalues();  // ascending
  if (!(values[1] > min_sine * min_sine * values[2])) return std::nullopt;  // a line, not a plane
  Plane fitted{eigen.eigenvectors().col(0).normalized(), 0.0, std::sqrt(std::max(values[0], 0.0))};
  fitted.offset = -fitted.normal.dot(centroid);
  const Eigen::Vector3d foot = -centroid + fitted.normal.dot(centroid) * fitted.normal;
  fitted.surrounds = foot.squaredNorm() <= spread * spread * (values[1] + values[2]);
  return fitted;
}

/// The least-squares plane of the points of `q` within `distance` of `plane` (its inliers).
inline std::optional<Plane> refit_plane(std::span<const Eigen::Vector3d> q, const Plane& plane, double distance, double min_sine,
                                        double spread) {
  PlaneMoments m;
  for (const Eigen::Vector3d& x : q)
    if (std::abs(plane.normal.dot(x) + plane.offset) <= distance) m.add(x);
  return fit_plane(m, min_sine, spread);
}

}  // namespace pointsurf::detail
