// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Reading and writing clouds and meshes in every common scan format.
//
// Formats: PLY (ascii, binary little/big endian), XYZ/PTS/TXT/CSV, PCD v0.7 (ascii, binary,
// binary_compressed), OFF, OBJ, STL (ascii, binary), LAS 1.0-1.4 (point formats 0-10; written as 1.4),
// LAZ (LASzip-compressed LAS: formats 0-10 read, written as format 6/7).
// The format of a file being read is detected from its content (magic bytes, header); the
// extension is only a hint for headerless text. The format written follows the extension of
// the output path unless WriteOptions::format says otherwise.
// E57 (ASTM E2807): several scans with their poses (CloudReadResult::scans), colour, intensity.
//
// Errors: malformed input throws InputError naming the file, the place (line, element index or
// byte offset) and what was expected; a bad option throws UsageError. Points with NaN/Inf
// coordinates are dropped and counted in the result (an InputError with `strict`).
// Writes go to a temporary file in the target directory that is renamed when complete, so an
// output is whole or absent.
// Thread-safety: all functions are reentrant; concurrent calls on different files are safe.
#include <array>
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/triangle_mesh.h"

namespace pointsurf {

/// Canonical format names: "ply", "xyz", "pcd", "off", "obj", "stl", "las", "laz".
/// Returns the format of `path` from its first bytes, falling back on the extension for text
/// without a header; throws InputError for an empty or unrecognised file.
std::string detect_format(const std::filesystem::path& path);

/// Format implied by the extension of `path` (".ply" -> "ply", ".txt"/".pts"/".csv" -> "xyz",
/// ".las" -> "las"); throws UsageError for an unknown extension.
std::string format_from_extension(const std::filesystem::path& path);

/// Checks, before any work, that `path` can be written: a known extension (unless
/// `format` is given), an existing writable directory, not a directory itself, and, with
/// `no_clobber`, no file there yet. Throws UsageError naming the path. Creates nothing.
void check_output_path(const std::filesystem::path& path, bool no_clobber = false, const std::string& format = {});

/// Checks that `path` names a readable regular file; throws InputError naming it otherwise.
void check_input_path(const std::filesystem::path& path);

/// Removes an output written by a run that then failed, so that none is left behind.
/// Ignores a file that is already gone. Never throws.
void remove_output(const std::filesystem::path& path) noexcept;

/// Whether two paths name the same file once made absolute and normalised (the file need not
/// exist).
bool same_path(const std::filesystem::path& a, const std::filesystem::path& b);

/// One scan of a file that holds several (E57): its name, point count and pose, the rigid
/// transform from the scan's own frame to the file's frame: p_file = rotation * p + translation.
struct ScanPose {
  std::string name;
  std::size_t points = 0;
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();  // unit quaternion
  Vector3d translation = Vector3d::Zero();                       // cloud units
};

struct ReadOptions {
  bool strict = false;      // NaN/Inf coordinates are an InputError instead of being dropped
  bool apply_poses = true;  // E57: move each scan by its pose; false keeps scan coordinates (poses in the result's scans)
  std::string format;       // force a format ("ply", "xyz", ...); empty: detect from content
  // Column meaning for XYZ-family text, comma separated: x,y,z,nx,ny,nz,r,g,b,i (intensity)
  // or any other name (kept as a field), "_" to skip a column. Empty: taken from a header line
  // of names, else recognised by the values (colours 0..255 integers, unit normals) among the
  // layouts tools write, with a warning naming it; two layouts that fit equally: InputError.
  std::string columns;
  // COPC (LAZ with an octree hierarchy): read the octree levels 0..copc_level only; -1: all.
  int copc_level = -1;
  // Keep only the points with min <= p <= max (xmin, ymin, zmin, xmax, ymax, zmax); COPC files
  // skip the octree nodes outside without decoding them.
  std::optional<std::array<double, 6>> bounds;
};

struct CloudReadResult {
  PointCloud cloud;
  std::string format;                  // detected format, e.g. "ply"
  std::string encoding;                // "ascii", "binary_little_endian", "binary_compressed", ...
  std::size_t dropped_nonfinite = 0;   // points dropped for NaN/Inf coordinates (smaller is better)
  std::size_t face_count = 0;          // faces present in the file (meshes read as clouds)
  std::vector<std::string> warnings;   // things the user should know, e.g. organized PCD flattened
  std::vector<ScanPose> scans;         // E57: one per scan, in file order (field "scan" numbers them when more than one)
};

struct MeshReadResult {
  TriangleMesh mesh;
  std::string format;
  std::string encoding;
  std::size_t dropped_nonfinite = 0;     // vertices dropped for NaN/Inf (faces using them too)
  std::size_t dropped_faces = 0;         // faces dropped: degenerate or touching dropped vertices
  std::size_t polygons_triangulated = 0; // faces with more than 3 corners split into a fan
  std::vector<std::string> warnings;
};

/// Reads any supported file as a point cloud (a mesh file gives its vertices).
CloudReadResult read_point_cloud(const std::filesystem::path& path, const ReadOptions& options = {});
/// Reads a mesh (PLY, OFF, OBJ, STL); a file without faces gives an empty triangle list. PLY
/// face properties other than the corner list become face fields (a polygon's value goes to
/// every triangle of its fan).
MeshReadResult read_mesh(const std::filesystem::path& path, const ReadOptions& options = {});

enum class PlyEncoding { BinaryLittleEndian, BinaryBigEndian, Ascii };

struct WriteOptions {
  std::string format;                     // force a format; empty: from the extension
  PlyEncoding ply_encoding = PlyEncoding::BinaryLittleEndian;  // PLY only
  bool ascii = false;                     // ascii PLY / PCD / STL (overrides ply_encoding)
  bool single_precision = false;          // float32 positions (PLY, PCD); refused with a
                                          // UsageError when the float32 step at the largest
                                          // coordinate exceeds 1e-5 of the bounding-box diagonal
                                          // (georeferenced data: keep double). PCD without either
                                          // flag: float32 when it moves no coordinate by more than
                                          // 1e-4 of the spacing (diagonal / sqrt(N)), else double
                                          // with a note in WriteResult (PCL and Open3D 0.16 read
                                          // double PCD positions as zeros)
  bool double_precision = false;          // PCD: double positions even where float32 would do
  bool pcd_compressed = false;            // PCD binary_compressed (LZF) instead of binary
  std::optional<Vector3d> las_offset;     // LAS offset; default: the cloud's grid, else near the data's minimum
  std::optional<double> las_scale;        // LAS scale (cloud units per count); default: the cloud's
                                          // grid (read from LAS/LAZ), else <= 1e-4
  std::vector<ScanPose> scan_poses;       // E57: pose of the scan whose "scan" field is i (identity when absent)
  std::optional<double> e57_scale;        // E57: scaled-integer coordinates with this step; default float64
  int precision = 17;                     // significant digits of text coordinates (XYZ, OBJ, ...)
};

struct WriteResult {
  std::vector<std::string> notes;  // choices the writer made that the user should know (PCD written as double)
};

/// Writes a cloud; formats that hold faces get none. Throws UsageError for a format that
/// cannot hold the data as asked and Error on an I/O failure.
WriteResult write_point_cloud(const std::filesystem::path& path, const PointCloud& cloud, const WriteOptions& options = {});
/// Writes a mesh (PLY, OFF, OBJ, STL; XYZ/PCD/LAS get its vertices only). Face fields go to
/// PLY only, as extra `element face` properties of their own type; other formats drop them.
WriteResult write_mesh(const std::filesystem::path& path, const TriangleMesh& mesh, const WriteOptions& options = {});

}  // namespace pointsurf
