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
  std::vector<std::int64_t> outer;  // 0 or one per polyline: for a hole, the index of the closed
                                    // polyline around it (GeoJSON: an inner ring of that one's
                                    // Polygon); -1 for none
};

/// Writes the polylines to `path` by its extension: .ply (ASCII; vertex x y z, edge vertex1
/// vertex2 group), .obj (v and l lines, one o per polyline, a closed one ends at its first
/// vertex), .geojson / .json (a FeatureCollection with x, y, z in the cloud's own coordinates:
/// a closed polyline of at least 3 vertices, flagged closed or ending at its first vertex, is a
/// Polygon whose outer ring runs counter-clockwise in x, y and whose holes (`outer`) are inner
/// rings running clockwise, RFC 7946; any other polyline is a LineString; properties id, group,
/// closed, holes, length (of all rings)). PLY and OBJ write holes as polylines of their own.
/// Throws UsageError for an unknown extension, option sizes other than the polyline count or a
/// hole whose outer polyline is not a closed polyline that is no hole; InputError when the file
/// cannot be written.
void write_polylines(const std::filesystem::path& path, std::span<const Polyline> lines, const PolylineWriteOptions& options = {});

}  // namespace pointsurf
