// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The Darboux-frame features of a pair of oriented points (Rusu et al. 2008), as PCL's and
// Open3D's computePairFeatures define them, and their histogram bins. Float: the offsets are
// differences of nearby points (small numbers whatever the cloud's origin), and PFH evaluates
// about 5000 pairs per point.
#include <algorithm>
#include <cmath>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace pointsurf::detail {

struct PairFeatures {
  float alpha = 0.0f;  // atan2(w . n2, u . n2): the rotation about the frame's v, in [-pi, pi]
  float phi = 0.0f;    // v . n2, in [-1, 1]
  float theta = 0.0f;  // u . d / |d|: cosine between the source normal and the line, in [-1, 1]
};

/// Features of (p1, n1) -> (p2, n2) with `d` = p2 - p1 and unit normals. The source of the
/// frame is the point whose normal makes the smaller angle with the line (so the pair gives the
/// same features in either order). Returns false for coincident points or a normal along the
/// line (no frame): PCL skips such pairs.
inline bool pair_features(const Eigen::Vector3f& d, const Eigen::Vector3f& n1, const Eigen::Vector3f& n2, PairFeatures& out) {
  const float length = d.norm();
  if (!(length > 0.0f)) return false;
  const float angle1 = n1.dot(d) / length;
  const float angle2 = n2.dot(d) / length;
  // PCL compares acos(|angle1|) > acos(|angle2|); acos decreases, so this is the same test.
  const bool swap = std::abs(angle1) < std::abs(angle2);
  const Eigen::Vector3f& u = swap ? n2 : n1;
  const Eigen::Vector3f& target = swap ? n1 : n2;
  const Eigen::Vector3f line = swap ? Eigen::Vector3f(-d) : d;
  Eigen::Vector3f v = line.cross(u);
  const float v_norm = v.norm();
  if (!(v_norm > 0.0f)) return false;
  v /= v_norm;
  const Eigen::Vector3f w = u.cross(v);
  out.theta = swap ? -angle2 : angle1;
  out.phi = v.dot(target);
  out.alpha = std::atan2(w.dot(target), u.dot(target));
  return true;
}

/// The bin of `fraction` (in [0, 1]) among `bins` equal bins, clamped as PCL does.
inline int feature_bin(float fraction, int bins) {
  return std::clamp(static_cast<int>(std::floor(static_cast<float>(bins) * fraction)), 0, bins - 1);
}

constexpr float kTwoPi = 6.28318530717958647692f;
constexpr float kPi = 3.14159265358979323846f;

/// Bins of the three features among `bins` each: alpha over [-pi, pi], phi and theta over [-1, 1].
inline void feature_bins(const PairFeatures& f, int bins, int out[3]) {
  out[0] = feature_bin((f.alpha + kPi) / kTwoPi, bins);
  out[1] = feature_bin((f.phi + 1.0f) * 0.5f, bins);
  out[2] = feature_bin((f.theta + 1.0f) * 0.5f, bins);
}

}  // namespace pointsurf::detail
