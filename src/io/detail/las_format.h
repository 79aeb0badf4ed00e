// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// What LAS and LAZ share: the public header block, the VLRs, and the conversion between point
// records and a PointCloud's positions and fields (ASPRS LAS 1.4 R15). The LAS reader feeds the
// records straight from the file; the LAZ reader feeds them as it decompresses each chunk.
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "io/detail/formats.h"

namespace pointsurf::io::detail {

/// The public header block's fields a reader needs, checked for consistency.
struct LasHeader {
  int major = 1, minor = 4;
  int format = 0;          // point data record format 0-10 (the compression bits removed)
  bool compressed = false; // bit 7 or 6 of the format byte: LAZ
  std::size_t header_size = 0, point_offset = 0, record_length = 0;
  std::uint32_t vlr_count = 0;
  std::uint64_t count = 0;
  std::uint64_t evlr_start = 0;  // LAS 1.4: byte of the first extended VLR
  std::uint32_t evlr_count = 0;
  std::array<double, 3> scale{}, offset{};
};

/// Parses and checks the header at the start of `bytes` (at least the header's size).
/// Throws InputError naming `name` and the byte.
LasHeader parse_las_header(std::string_view bytes, std::uint64_t file_size, const std::string& name);

struct LasVlr {
  std::string user_id;
  std::uint16_t record_id = 0;
  std::string_view body;
};
/// The VLRs between the header and the points; `bytes` holds the file up to the points.
std::vector<LasVlr> las_vlrs(std::string_view bytes, const LasHeader& header);
/// The extended VLRs (LAS 1.4) in `tail`, the file from header.evlr_start on; stops at the first
/// that overruns it.
std::vector<LasVlr> las_evlrs(std::string_view tail, const LasHeader& header);

/// The coordinate system VLRs (user "LASF_Projection"): OGC WKT and the three GeoTIFF tags.
inline constexpr std::string_view kProjectionUserId = "LASF_Projection";
inline constexpr std::uint16_t kWktRecord = 2112, kGeoKeysRecord = 34735, kGeoDoubleRecord = 34736, kGeoAsciiRecord = 34737;
/// Fills `crs` from the coordinate system records among `vlrs` (VLRs or EVLRs); a later record
/// replaces an earlier one of the same kind.
void read_las_crs(const std::vector<LasVlr>& vlrs, CoordinateSystem& crs);
/// The VLRs holding `crs` (WKT first, then the GeoTIFF keys, doubles and ASCII), each payload as
/// stored; adds their number to `count`.
std::string las_crs_vlrs(const CoordinateSystem& crs, int& count);

/// Turns point records into a cloud: positions with scale and offset applied, the standard
/// fields that some point sets, extra bytes as named fields (nx, ny, nz as normals), colours.
class LasRecordReader {
public:
  LasRecordReader(const LasHeader& header, std::string_view head_bytes, const std::string& name, RawData& raw);
  ~LasRecordReader();
  /// Record `i` (header.record_length bytes).
  void read(std::size_t i, const char* record);
  /// Moves the fields into raw.cloud.
  void finish();

private:
  struct State;
  std::unique_ptr<State> s_;
};

/// Turns a cloud into point records: the header (LAS 1.4, point format 6, or 7 with colours),
/// the VLRs and one record per point; a field that does not fit its slot goes to extra bytes
/// under its name.
class LasRecordWriter {
public:
  /// Scale and offset: WriteOptions::las_scale/las_offset, else the cloud's grid (the source
  /// file's) while every point fits it in 32 bits, else the default; `notes` gets a line when
  /// the cloud's grid could not be kept.
  LasRecordWriter(const PointCloud& cloud, const WriteOptions& options, const std::string& name, std::vector<std::string>& notes);
  ~LasRecordWriter();
  int format() const;
  std::size_t record_length() const;
  std::size_t extra_bytes() const;  // after the format's own bytes
  /// The header with `more_vlrs` (whole VLRs) appended after the writer's own VLRs; `format_bits`
  /// is or-ed into the format byte (0x80 for LAZ).
  std::string head(const std::string& more_vlrs, int more_vlr_count, int format_bits) const;
  /// Record of point i into `out` (record_length() bytes).
  void record(std::size_t i, char* out) const;

private:
  struct State;
  std::unique_ptr<State> s_;
};

/// A VLR (54-byte header and body).
std::string las_vlr(std::string_view user_id, std::uint16_t record_id, std::string_view description, std::string_view body);

}  // namespace pointsurf::io::detail
