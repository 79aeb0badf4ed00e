// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/core/point_cloud.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include "pointsurf/core/error.h"

namespace pointsurf {

void PointCloud::validate() const {
  const std::size_t n = size();
  if (!normals.empty() && normals.size() != n)
    throw InputError(fmt::format("point cloud: {} normals for {} points", normals.size(), n));
  if (!colors.empty() && colors.size() != n)
    throw InputError(fmt::format("point cloud: {} colours for {} points", colors.size(), n));
  for (const ScalarField& f : fields)
    if (f.values.size() != n)
      throw InputError(fmt::format("point cloud: field '{}' has {} values for {} points", f.name, f.values.size(), n));
}

PointCloud PointCloud::select(std::span<const std::size_t> indices) const {
  PointCloud out;
  out.positions.reserve(indices.size());
  for (std::size_t i : indices) out.positions.push_back(positions[i]);
  if (has_normals()) {
    out.normals.reserve(indices.size());
    for (std::size_t i : indices) out.normals.push_back(normals[i]);
  }
  if (has_colors()) {
    out.colors.reserve(indices.size());
    for (std::size_t i : indices) out.colors.push_back(colors[i]);
  }
  for (const ScalarField& f : fields) {
    ScalarField& g = out.fields.add(f.name, 0, f.type);
    g.values.reserve(indices.size());
    for (std::size_t i : indices) g.values.push_back(f.values[i]);
  }
  return out;
}

void PointCloud::append(const PointCloud& other) {
  if (&other == this) {  // inserting a vector's own range into itself is undefined
    const PointCloud copy = other;
    append(copy);
    return;
  }
  const std::size_t n0 = size(), n1 = other.size();
  const bool normals_out = has_normals() || other.has_normals();
  const bool colors_out = has_colors() || other.has_colors();
  positions.insert(positions.end(), other.positions.begin(), other.positions.end());
  if (normals_out) {
    normals.resize(n0, Vector3d::Zero());
    if (other.has_normals()) normals.insert(normals.end(), other.normals.begin(), other.normals.end());
    else normals.resize(n0 + n1, Vector3d::Zero());
  }
  if (colors_out) {
    colors.resize(n0, Vector3f::Zero());
    if (other.has_colors()) colors.insert(colors.end(), other.colors.begin(), other.colors.end());
    else colors.resize(n0 + n1, Vector3f::Zero());
  }
  for (ScalarField& f : fields) {
    const ScalarField* g = other.fields.find(f.name);
    if (g) f.values.insert(f.values.end(), g->values.begin(), g->values.end());
    else f.values.resize(n0 + n1, 0.0);
  }
  for (const ScalarField& g : other.fields) {
    if (fields.contains(g.name)) continue;
    ScalarField& f = fields.add(g.name, n0, g.type);
    f.values.insert(f.values.end(), g.values.begin(), g.values.end());
  }
}

BoundingBox bounding_box(std::span<const Vector3d> points) {
  return tbb::parallel_reduce(
      tbb::blocked_range<std::size_t>(0, points.size(), 1 << 14), BoundingBox{},
      [&](const tbb::blocked_range<std::size_t>& r, BoundingBox box) {
        for (std::size_t i = r.begin(); i != r.end(); ++i) box.extend(points[i]);
        return box;
      },
      [](BoundingBox a, const BoundingBox& b) {
        if (!b.empty()) { a.extend(b.min); a.extend(b.max); }
        return a;
      });
}

}  // namespace pointsurf
