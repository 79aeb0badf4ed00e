// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// write_e57 as a phase object: the state its phases share (scans, intensity limits, the logical
// byte stream, the XML) held as named members, so each phase can be run and checked alone.
#include <cstdint>
#include <filesystem>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "io/detail/e57_pages.h"
#include "pointsurf/core/point_cloud.h"
#include "pointsurf/io/io.h"

namespace pointsurf::io::detail {

// One field to write: its prototype element and its bytestream.
struct OutField {
  std::string element;  // the prototype element, e.g. <cartesianX type="Float"/>
  std::vector<unsigned char> bytes;
};

// Writes a cloud as E57: one scan, or one per value of the `scan` field. The phases run in the
// order they are declared, write_scan once per group; each reads the members named in its
// comment. The *_fields functions are the parts of write_scan.
class E57Writer {
public:
  /// Checks WriteOptions::e57_scale (positive and finite); throws UsageError naming the path.
  E57Writer(const std::filesystem::path& path, const PointCloud& cloud, const WriteOptions& options, std::vector<std::string>& notes);

  /// Reads the `scan` field; produces groups (point indices by scan number, one scan 0 without
  /// it); throws UsageError for a value that is not a scan number.
  void group_scans();
  /// Reads the `intensity` field; produces intensity_integer and intensity_lo/hi: the range of
  /// its type (uint8, uint16), [0, 1] for floats there, else the field's own range.
  void set_intensity_limits();
  /// Reads the colours; produces color_maximum: 255 when every channel is a multiple of 1/255, else 65535.
  void set_color_limits();
  /// Produces rng (GUIDs) and the logical writer with room for the file header.
  void start_file();
  /// Reads one group; appends its compressed vector section to writer and its structure to scans_xml.
  void write_scan(long long scan, const std::vector<std::size_t>& indices);
  /// cartesianX/Y/Z: float64, or ScaledInteger with e57_scale (UsageError past 64 bits).
  std::vector<OutField> coordinate_fields(const std::vector<std::size_t>& indices) const;
  /// colorRed/Green/Blue as integers 0..color_maximum (none without colours).
  std::vector<OutField> color_fields(const std::vector<std::size_t>& indices) const;
  /// nor:normalX/Y/Z as float32 (none without normals); sets any_normals.
  std::vector<OutField> normal_fields(const std::vector<std::size_t>& indices);
  /// The other fields: intensity as its value (Integer within its limits, or Float), E57 point fields by name, the rest as
  /// pointsurf: extensions (sets any_extension); names that are not XML names are left out (skipped).
  std::vector<OutField> extra_fields(long long scan, const std::vector<std::size_t>& indices);
  /// Reads skipped; adds a note naming the fields left out.
  void note_skipped_fields();
  /// Reads scans_xml and the namespaces used; produces xml, the file's XML section.
  void compose_xml();
  /// Reads xml; appends it to writer and fills in the file header.
  void append_xml_and_header();
  /// Writes writer's pages to the path.
  void save() const;

  const std::filesystem::path& path;
  const PointCloud& cloud;
  const WriteOptions& options;
  std::vector<std::string>& notes;

  std::map<long long, std::vector<std::size_t>> groups;  // group_scans
  const ScalarField* scan_field = nullptr;
  const ScalarField* intensity = nullptr;                // set_intensity_limits
  double intensity_lo = 0.0, intensity_hi = 1.0;
  bool intensity_integer = false;
  int color_maximum = 255;                               // set_color_limits
  std::mt19937_64 rng;                                   // start_file
  E57LogicalWriter writer;
  std::string scans_xml;                                 // write_scan
  bool any_normals = false, any_extension = false;
  std::vector<std::string> skipped;
  std::string xml;                                       // compose_xml
  std::uint64_t xml_logical = 0;                         // append_xml_and_header: the XML's logical offset

private:
  std::string scan_structure(long long scan, std::size_t n, std::uint64_t offset, const std::vector<OutField>& fields);
};

}  // namespace pointsurf::io::detail
