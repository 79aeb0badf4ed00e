// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "pointsurf/core/scalar_field.h"

namespace pointsurf {

using Vector3d = Eigen::Vector3d;
using Vector3f = Eigen::Vector3f;

/// The coordinate reference system a file declared, kept as the file's own payloads so that a
/// round trip writes them back byte for byte: OGC WKT (LAS record 2112, E57 coordinateMetadata)
/// and the GeoTIFF keys of LAS records 34735 (key directory), 34736 (doubles), 34737 (ASCII).
struct CoordinateSystem {
  std::string wkt;
  std::vector<std::uint8_t> geokeys, geodouble, geoascii;

  bool empty() const noexcept { return wkt.empty() && geokeys.empty(); }
  /// One short line: the WKT's CRS name and its EPSG code, "NAME (no EPSG code)" when the WKT
  /// names none of its own; else the EPSG code of the GeoTIFF ProjectedCSTypeGeoKey (3072) or
  /// GeographicTypeGeoKey (2048); "" when empty.
  std::string describe() const;
  /// The CRS's own EPSG code: the AUTHORITY (WKT1) or ID (WKT2) that is a direct child of the
  /// WKT's outermost CRS node (of a BOUNDCRS's source CRS), never one of its unit, datum or base
  /// CRS; else the GeoTIFF keys' code; 0 if none.
  int epsg() const;
};

/// The grid a file stored coordinates on: p = offset + scale * (integer), per axis (LAS and LAZ
/// files). Kept with the cloud so that a LAS or LAZ written from it uses the same scale and
/// offset unless asked otherwise; empty when the source stored floating-point coordinates.
struct CoordinateGrid {
  Vector3d scale = Vector3d::Zero();   // cloud units per count; all zero: no grid
  Vector3d offset = Vector3d::Zero();  // cloud units

  bool empty() const noexcept { return scale == Vector3d::Zero(); }
  bool operator==(const CoordinateGrid&) const = default;
};

/// An unorganized point cloud. Positions are double precision so that georeferenced
/// coordinates (1e6..1e7 m) keep sub-millimetre precision. Every optional attribute is either
/// empty or holds exactly one entry per point; `validate()` checks that.
struct PointCloud {
  std::vector<Vector3d> positions;  // N, cloud units
  std::vector<Vector3d> normals;    // 0 or N, unit length (zero where undefined)
  std::vector<Vector3f> colors;     // 0 or N, RGB in [0, 1]
  FieldSet fields;                  // each field holds N values
  CoordinateSystem crs;             // empty when unknown
  CoordinateGrid grid;              // empty unless read from a file with integer coordinates

  std::size_t size() const noexcept { return positions.size(); }
  bool empty() const noexcept { return positions.empty(); }
  bool has_normals() const noexcept { return !normals.empty(); }
  bool has_colors() const noexcept { return !colors.empty(); }

  /// Throws InputError when an attribute's size differs from the point count.
  void validate() const;
  /// The points at `indices`, in that order, with every attribute and field.
  PointCloud select(std::span<const std::size_t> indices) const;
  /// Appends `other`; attributes present in only one cloud are filled with zeros. The grid stays
  /// when both share it (or this cloud is empty), else it is cleared.
  void append(const PointCloud& other);
};

/// Axis-aligned bounding box. `empty()` until a point is added.
struct BoundingBox {
  Vector3d min = Vector3d::Constant(std::numeric_limits<double>::infinity());
  Vector3d max = Vector3d::Constant(-std::numeric_limits<double>::infinity());

  bool empty() const noexcept { return !(min.x() <= max.x()); }
  void extend(const Vector3d& p) noexcept { min = min.cwiseMin(p); max = max.cwiseMax(p); }
  Vector3d extent() const noexcept { return empty() ? Vector3d::Zero() : Vector3d(max - min); }
  Vector3d center() const noexcept { return empty() ? Vector3d::Zero() : Vector3d(0.5 * (min + max)); }
  double diagonal() const noexcept { return extent().norm(); }
};

/// Bounding box of a set of points (empty box for no points). Parallel; thread-safe.
BoundingBox bounding_box(std::span<const Vector3d> points);

}  // namespace pointsurf
