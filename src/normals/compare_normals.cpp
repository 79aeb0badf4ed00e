// SPDX-License-Identifier: GPL-3.0-or-later
#include <algorithm>
#include <cmath>
#include <numbers>

#include <fmt/format.h>

#include "pointsurf/core/error.h"
#include "pointsurf/normals/normals.h"

namespace pointsurf {
namespace {

// Zero (degenerate) or NaN (from a file) normals carry no side to agree with.
bool usable(const Eigen::Vector3d& n) { return n.allFinite() && n.squaredNorm() > 0.0; }

}  // namespace

NormalAgreement compare_normals(std::span<const Eigen::Vector3d> reference, std::span<const Eigen::Vector3d> normals) {
  NormalAgreement out;
  double angle_sum = 0.0;
  const std::size_t n = std::min(reference.size(), normals.size());
  for (std::size_t i = 0; i < n; ++i) {
    if (!usable(reference[i]) || !usable(normals[i])) continue;
    const double c = reference[i].dot(normals[i]) / (reference[i].norm() * normals[i].norm());
    angle_sum += std::acos(std::min(1.0, std::abs(c))) * 180.0 / std::numbers::pi;
    out.agreeing += c > 0.0;
    ++out.compared;
  }
  out.share = out.compared == 0 ? 1.0 : double(out.agreeing) / double(out.compared);
  out.mean_angle_deg = out.compared == 0 ? 0.0 : angle_sum / double(out.compared);
  return out;
}

OrientResult orient_to_reference(PointCloud& cloud, std::span<const Eigen::Vector3d> reference) {
  if (!cloud.has_normals()) throw UsageError("orient_to_reference: the cloud has no normals (estimate them first)");
  if (cloud.normals.size() != cloud.size() || reference.size() != cloud.size())
    throw UsageError(fmt::format("orient_to_reference: {} normals and {} reference normals for {} points", cloud.normals.size(),
                                 reference.size(), cloud.size()));
  OrientResult result;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (!usable(reference[i]) || !usable(cloud.normals[i]) || cloud.normals[i].dot(reference[i]) >= 0.0) continue;
    cloud.normals[i] = -cloud.normals[i];
    ++result.flipped;
  }
  return result;
}

OrientResult orient_to_scanners(PointCloud& cloud, std::span<const Eigen::Vector3d> scanners, std::span<const double> scan_of_point) {
  if (!cloud.has_normals()) throw UsageError("orient_to_scanners: the cloud has no normals (estimate them first)");
  if (scanners.empty()) throw UsageError("orient_to_scanners: no scanner position");
  if (cloud.normals.size() != cloud.size() || (!scan_of_point.empty() && scan_of_point.size() != cloud.size()))
    throw UsageError(fmt::format("orient_to_scanners: {} normals and {} scan indices for {} points", cloud.normals.size(), scan_of_point.size(),
                                 cloud.size()));
  OrientResult result;
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    std::size_t scan = 0;
    if (!scan_of_point.empty()) {
      const double s = scan_of_point[i];
      if (!(s >= 0.0 && s < double(scanners.size()) && s == std::floor(s)))
        throw InputError(fmt::format("orient_to_scanners: point {} has scan index {}, but there are {} scanner positions", i, s, scanners.size()));
      scan = static_cast<std::size_t>(s);
    }
    // About the point: the difference of two absolute positions is exact to their rounding.
    const Eigen::Vector3d towards = scanners[scan] - cloud.positions[i];
    if (!usable(cloud.normals[i]) || cloud.normals[i].dot(towards) >= 0.0) continue;
    cloud.normals[i] = -cloud.normals[i];
    ++result.flipped;
  }
  return result;
}

const ResultTable<NormalAgreement>& NormalAgreement::results() {
  static const ResultTable<NormalAgreement> table = [] {
    ResultTable<NormalAgreement> t;
    t.count("input_normals_compared", &NormalAgreement::compared, "Points where the input's and the new normal both have a direction").as_count();
    t.number("mean_angle_to_input_deg", &NormalAgreement::mean_angle_deg, "Mean angle between the new and the input's normal lines")
        .with_unit("degrees")
        .lower_is_better();
    t.number("orientation_agreement_with_input", &NormalAgreement::share, "Share of compared points whose new normal is on the input's side")
        .higher_is_better();
    return t;
  }();
  return table;
}

}  // namespace pointsurf
