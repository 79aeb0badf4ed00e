// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Internal interface between the format dispatch (src/io/io.cpp) and the per-format readers
// and writers (src/io/<format>.cpp).
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include "pointsurf/io/io.h"

namespace pointsurf::io::detail {

/// What a format reader returns: vertices with their attributes, and faces when the file has
/// them. Faces may be polygons (any corner count >= 3); the dispatch triangulates them, drops
/// non-finite points (remapping faces) and applies `strict`. Readers must NOT drop
/// non-finite points themselves (except PCD organized NaN points, which they drop and count in
/// `dropped_nonfinite`).
struct RawData {
  PointCloud cloud;
  std::vector<std::vector<int>> polygons;  // only for mesh formats; indices into cloud
  std::vector<Triangle> triangles;         // readers may fill this directly instead of polygons
  FieldSet face_fields;                    // one value per face as read (triangles or polygons)
  std::string encoding;                    // "ascii", "binary_little_endian", ...
  std::size_t dropped_nonfinite = 0;       // dropped by the reader itself (organized PCD)
  std::vector<std::string> warnings;
  std::vector<ScanPose> scans;             // E57
};

// Readers. `display` is the file name to use in messages. Each throws InputError on malformed
// input with the file, the place and what was expected.
RawData read_ply(const std::filesystem::path& path, const ReadOptions& options);
RawData read_xyz(const std::filesystem::path& path, const ReadOptions& options);
RawData read_pcd(const std::filesystem::path& path, const ReadOptions& options);
RawData read_las(const std::filesystem::path& path, const ReadOptions& options);
RawData read_laz(const std::filesystem::path& path, const ReadOptions& options);
RawData read_off(const std::filesystem::path& path, const ReadOptions& options);
RawData read_obj(const std::filesystem::path& path, const ReadOptions& options);
RawData read_stl(const std::filesystem::path& path, const ReadOptions& options);
RawData read_e57(const std::filesystem::path& path, const ReadOptions& options);

// Writers: write `cloud` (the vertices, with attributes) and `triangles` (may be empty) to the
// already-open temporary file path `tmp_path`; the dispatch renames it afterwards. Only PLY
// holds face fields (one value per triangle each).
void write_ply(const std::filesystem::path& tmp_path, const PointCloud& cloud, const std::vector<Triangle>& triangles,
               const FieldSet& face_fields, const WriteOptions& options);
void write_xyz(const std::filesystem::path& tmp_path, const PointCloud& cloud, const WriteOptions& options);
// `notes` gets what the user should know about a choice the writer made (PCD: double positions).
void write_pcd(const std::filesystem::path& tmp_path, const PointCloud& cloud, const WriteOptions& options, std::vector<std::string>& notes);
void write_las(const std::filesystem::path& tmp_path, const PointCloud& cloud, const WriteOptions& options, std::vector<std::string>& notes);
void write_laz(const std::filesystem::path& tmp_path, const PointCloud& cloud, const WriteOptions& options, std::vector<std::string>& notes);
void write_off(const std::filesystem::path& tmp_path, const PointCloud& cloud, const std::vector<Triangle>& triangles, const WriteOptions& options);
void write_obj(const std::filesystem::path& tmp_path, const PointCloud& cloud, const std::vector<Triangle>& triangles, const WriteOptions& options);
void write_stl(const std::filesystem::path& tmp_path, const PointCloud& cloud, const std::vector<Triangle>& triangles, const WriteOptions& options);
void write_e57(const std::filesystem::path& tmp_path, const PointCloud& cloud, const WriteOptions& options, std::vector<std::string>& notes);

/// File name for messages ("scan.ply" as given by the user).
std::string display_name(const std::filesystem::path& path);

}  // namespace pointsurf::io::detail
