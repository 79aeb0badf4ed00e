// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Writing polylines (outlines, sections): PLY edge lists, OBJ lines, GeoJSON.
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

#include "pointsurf/core/polyline.h"

namespace pointsurf {

struct PolylineWriteOptions {
  std::string crs;                  // GeoJSON: the coordinates' CRS (e.g. "EPSG:25832"), named in
                                    // the file's "crs" member; empty: none written
  std::vector<std::int64_t> group;  // 0 or one per polyline: a group id (a segment label),
                                    // written as a PLY edge property, OBJ group, GeoJSON property
  std::vector<std::uint8_t> hole;   // 0 or one per polyline: 1 for a hole (GeoJSON property)
};

/// Writes the polylines to `path` by its extension: .ply (ASCII; vertex x y z, edge vertex1
/// vertex2 group), .obj (v and l lines, one o per polyline, a closed one ends at its first
/// vertex), .geojson / .json (a FeatureCollection of LineStrings with x, y, z in the cloud's own
/// coordinates; properties id, group, hole, closed, length). Throws UsageError for an unknown
/// extension or option sizes other than the polyline count, InputError when the file cannot be
/// written.
void write_polylines(const std::filesystem::path& path, std::span<const Polyline> lines, const PolylineWriteOptions& options = {});

}  // namespace pointsurf
