// SPDX-License-Identifier: GPL-3.0-or-later
// E57 writer (the layout and the reader: io/detail/e57_format.h, e57_read.cpp).
//
// Writing: one scan, or one per value of the `scan` field, each with its pose from
// WriteOptions::scan_poses (identity otherwise); coordinates float64, or scaled integers with
// WriteOptions::e57_scale; colours as 8- or 16-bit integers, intensity as its value (integer or
// float) with its limits,
// normals by the nor: extension (float32), other fields in a pointsurf: extension namespace
// (E57's own point fields such as timeStamp or rowIndex under their names).
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <optional>
#include <utility>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <pugixml.hpp>

#include "io/detail/e57_format.h"
#include "io/detail/e57_pages.h"
#include "io/detail/e57_writer.h"
#include "io/detail/file_util.h"
#include "io/detail/formats.h"
#include "pointsurf/core/error.h"

namespace pointsurf::io::detail {

namespace {

std::string xml_number(double v) { return fmt::format("{:.17g}", v); }

std::string cdata(std::string_view text) {
  std::string out = "<![CDATA[";
  std::size_t start = 0, at;
  while ((at = text.find("]]>", start)) != std::string_view::npos) {
    out.append(text.substr(start, at + 2 - start));
    out.append("]]><![CDATA[");
    start = at + 2;
  }
  out.append(text.substr(start));
  return out + "]]>";
}

std::vector<unsigned char> pack_bits(const std::vector<std::uint64_t>& raw, unsigned bits) {
  std::vector<unsigned char> out((raw.size() * bits + 7) / 8 + 16, 0);
  if (bits > 0) {
    for (std::size_t i = 0; i < raw.size(); ++i) {
      const std::uint64_t bit = static_cast<std::uint64_t>(i) * bits;
      const unsigned shift = static_cast<unsigned>(bit & 7);
      unsigned char* p = out.data() + (bit >> 3);
      std::uint64_t word;
      std::memcpy(&word, p, 8);
      word |= raw[i] << shift;
      std::memcpy(p, &word, 8);
      if (shift + bits > 64) p[8] |= static_cast<unsigned char>(raw[i] >> (64 - shift));
    }
  }
  out.resize((raw.size() * bits + 7) / 8);
  return out;
}

// An Integer field; its minimum and maximum are the values' own, widened to `limits` when given.
OutField integer_field(const std::string& name, const std::vector<std::int64_t>& values,
                       std::optional<std::pair<std::int64_t, std::int64_t>> limits = std::nullopt) {
  std::int64_t lo = limits ? limits->first : 0, hi = limits ? limits->second : 0;
  if (!values.empty()) {
    const auto [a, b] = std::minmax_element(values.begin(), values.end());
    lo = limits ? std::min(lo, *a) : *a;
    hi = limits ? std::max(hi, *b) : *b;
  }
  std::vector<std::uint64_t> raw(values.size());
  for (std::size_t i = 0; i < values.size(); ++i) raw[i] = static_cast<std::uint64_t>(values[i]) - static_cast<std::uint64_t>(lo);
  return {fmt::format("<{} type=\"Integer\" minimum=\"{}\" maximum=\"{}\"/>", name, lo, hi), pack_bits(raw, bits_for_range(lo, hi))};
}

template <typename T>
OutField float_field(const std::string& name, const std::vector<double>& values) {
  OutField f;
  f.element = fmt::format("<{} type=\"Float\" precision=\"{}\"/>", name, sizeof(T) == 4 ? "single" : "double");
  f.bytes.resize(values.size() * sizeof(T));
  for (std::size_t i = 0; i < values.size(); ++i) {
    const T v = static_cast<T>(values[i]);
    std::memcpy(f.bytes.data() + i * sizeof(T), &v, sizeof(T));
  }
  return f;
}

bool is_xml_name(std::string_view s) {
  if (s.empty() || !(std::isalpha(static_cast<unsigned char>(s[0])) || s[0] == '_')) return false;
  return std::all_of(s.begin(), s.end(), [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.'; });
}

bool is_e57_point_field(std::string_view s) {
  for (const char* known : {"rowIndex", "columnIndex", "returnIndex", "returnCount", "timeStamp", "isTimeStampInvalid", "isIntensityInvalid",
                            "isColorInvalid", "cartesianInvalidState", "sphericalInvalidState"})
    if (s == known) return true;
  return false;
}

// Writes one compressed vector section of the given bytestreams; returns its physical offset.
std::uint64_t write_section(E57LogicalWriter& w, const std::vector<OutField>& fields) {
  w.pad_to(4);
  const std::uint64_t start = w.size();
  const unsigned char zeros[kSectionHeaderSize] = {};
  w.append(zeros, kSectionHeaderSize);
  const std::size_t n = fields.size();
  std::uint64_t total = 0;
  for (const OutField& f : fields) total += f.bytes.size();
  // Slices rounded up to 8 bytes (whole words for any reader's bit-unpacking register).
  const std::size_t budget = kMaxPacketSize - 6 - 2 * n - 3 - 8 * n;
  const std::uint64_t packets = std::max<std::uint64_t>(1, (total + budget - 1) / budget);
  std::vector<std::size_t> slice(n);
  for (std::size_t k = 0; k < n; ++k) slice[k] = static_cast<std::size_t>(((fields[k].bytes.size() + packets - 1) / packets + 7) / 8 * 8);
  for (std::uint64_t p = 0; p < packets; ++p) {
    std::vector<std::size_t> from(n), len(n);
    std::size_t size = 6 + 2 * n;
    for (std::size_t k = 0; k < n; ++k) {
      from[k] = std::min<std::size_t>(fields[k].bytes.size(), p * slice[k]);
      len[k] = std::min<std::size_t>(fields[k].bytes.size() - from[k], slice[k]);
      size += len[k];
    }
    const std::size_t padded = (size + 3) / 4 * 4;
    w.append_value<std::uint8_t>(kDataPacket);
    w.append_value<std::uint8_t>(0);
    w.append_value<std::uint16_t>(static_cast<std::uint16_t>(padded - 1));
    w.append_value<std::uint16_t>(static_cast<std::uint16_t>(n));
    for (std::size_t k = 0; k < n; ++k) w.append_value<std::uint16_t>(static_cast<std::uint16_t>(len[k]));
    for (std::size_t k = 0; k < n; ++k) w.append(fields[k].bytes.data() + from[k], len[k]);
    w.pad_to(4);
  }
  const std::uint64_t length = w.size() - start;
  unsigned char header[kSectionHeaderSize] = {};
  header[0] = kCompressedVectorSection;
  const std::uint64_t data_physical = e57_physical(start + kSectionHeaderSize);
  std::memcpy(header + 8, &length, 8);
  std::memcpy(header + 16, &data_physical, 8);
  w.patch(start, header, kSectionHeaderSize);
  return e57_physical(start);
}

std::string guid(std::mt19937_64& rng) {
  const std::uint64_t a = rng(), b = rng();
  return fmt::format("{{{:08x}-{:04x}-4{:03x}-{:04x}-{:012x}}}", a >> 32, (a >> 16) & 0xFFFF, a & 0xFFF, (b >> 48 & 0x3FFF) | 0x8000,
                     b & 0xFFFFFFFFFFFFULL);
}

}  // namespace

E57Writer::E57Writer(const std::filesystem::path& path, const PointCloud& cloud, const WriteOptions& options,
                     std::vector<std::string>& notes)
    : path(path), cloud(cloud), options(options), notes(notes) {
  if (options.e57_scale && !(*options.e57_scale > 0.0 && std::isfinite(*options.e57_scale)))
    throw UsageError(fmt::format("{}: E57 scale {} must be positive", display_name(path), *options.e57_scale));
}

void E57Writer::group_scans() {
  groups.clear();
  scan_field = cloud.fields.find("scan");
  if (scan_field) {
    for (std::size_t i = 0; i < cloud.size(); ++i) {
      const double v = scan_field->values[i];
      if (!(v >= 0 && v < 1e9) || v != std::floor(v))
        throw UsageError(fmt::format("{}: point {}: field scan = {} is not a scan number (0, 1, ...)", display_name(path), i, v));
      groups[static_cast<long long>(v)].push_back(i);
    }
  } else {
    std::vector<std::size_t>& all = groups[0];
    all.resize(cloud.size());
    for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
  }
  if (groups.empty()) groups[0];
}

// E57 stores intensity as its value and declares the range it can take in intensityLimits
// (ASTM E2807), so a reader that takes the stored value and one that scales by the limits each
// see what the writer meant. Integer fields (LAS's uint16) are stored as integers with their type's range as
// the limits when they fit it; floats as floats, with [0, 1] as the limits when they lie there.
void E57Writer::set_intensity_limits() {
  intensity = cloud.fields.find("intensity");
  intensity_lo = 0.0;
  intensity_hi = 1.0;
  intensity_integer = false;
  if (!intensity || intensity->values.empty()) return;
  const auto [a, b] = std::minmax_element(intensity->values.begin(), intensity->values.end());
  intensity_integer = !scalar_type_is_float(intensity->type);
  if (intensity_integer && (intensity->type == ScalarType::UInt8 || intensity->type == ScalarType::UInt16)) {
    intensity_hi = intensity->type == ScalarType::UInt8 ? 255.0 : 65535.0;
    if (*a >= 0.0 && *b <= intensity_hi) return;
  } else if (!intensity_integer && *a >= 0.0 && *b <= 1.0) {
    return;
  }
  intensity_lo = *a;
  intensity_hi = *b > *a ? *b : *a + 1.0;
}

// 8-bit colour limits when every channel is a multiple of 1/255 (8-bit sources: PLY, PCD, text),
// else 16-bit (LAS's colours), so that no colour is rounded to a coarser step than it came with.
void E57Writer::set_color_limits() {
  color_maximum = 255;
  for (const Vector3f& c : cloud.colors)
    for (int ch = 0; ch < 3; ++ch) {
      const double v = std::clamp(double(c[ch]), 0.0, 1.0) * 255.0;
      if (std::abs(v - std::round(v)) > 1e-3) {
        color_maximum = 65535;
        return;
      }
    }
}

void E57Writer::start_file() {
  rng.seed(std::random_device{}());
  // Bytes per point: coordinates, colours, normals and fields at most 8 each, plus packet and XML overhead.
  writer.reserve(cloud.size() * (24 + 3 + 12 + 8 * cloud.fields.size()) * 65 / 64 + 65536);
  const unsigned char header_space[kE57HeaderSize] = {};
  writer.append(header_space, kE57HeaderSize);
}

std::vector<OutField> E57Writer::coordinate_fields(const std::vector<std::size_t>& indices) const {
  const std::size_t n = indices.size();
  std::vector<OutField> fields;
  std::vector<double> column(n);
  for (int axis = 0; axis < 3; ++axis) {
    const std::string name = std::string("cartesian") + "XYZ"[axis];
    for (std::size_t i = 0; i < n; ++i) column[i] = cloud.positions[indices[i]][axis];
    if (!options.e57_scale) {
      fields.push_back(float_field<double>(name, column));
      continue;
    }
    const double scale = *options.e57_scale;
    std::vector<std::int64_t> raw(n);
    for (std::size_t i = 0; i < n; ++i) {
      const double q = std::round(column[i] / scale);
      if (!(std::abs(q) < 9.0e18))
        throw UsageError(fmt::format("{}: point {}: coordinate {} does not fit a 64-bit scaled integer of step {}", display_name(path),
                                     indices[i], column[i], scale));
      raw[i] = static_cast<std::int64_t>(q);
    }
    OutField f = integer_field(name, raw);
    const std::string lo = f.element.substr(f.element.find("minimum="));
    f.element = fmt::format("<{} type=\"ScaledInteger\" {} scale=\"{}\" offset=\"0\"/>", name, lo.substr(0, lo.size() - 2), xml_number(scale));
    fields.push_back(std::move(f));
  }
  return fields;
}

std::vector<OutField> E57Writer::color_fields(const std::vector<std::size_t>& indices) const {
  const std::size_t n = indices.size();
  std::vector<OutField> fields;
  if (!cloud.has_colors()) return fields;
  for (int ch = 0; ch < 3; ++ch) {
    std::vector<std::int64_t> raw(n);
    for (std::size_t i = 0; i < n; ++i)
      raw[i] = static_cast<std::int64_t>(std::clamp(double(cloud.colors[indices[i]][ch]), 0.0, 1.0) * color_maximum + 0.5);
    fields.push_back({fmt::format("<color{} type=\"Integer\" minimum=\"0\" maximum=\"{}\"/>", ch == 0 ? "Red" : ch == 1 ? "Green" : "Blue",
                                  color_maximum),
                      pack_bits(std::vector<std::uint64_t>(raw.begin(), raw.end()), color_maximum == 255 ? 8 : 16)});
  }
  return fields;
}

std::vector<OutField> E57Writer::normal_fields(const std::vector<std::size_t>& indices) {
  const std::size_t n = indices.size();
  std::vector<OutField> fields;
  if (!cloud.has_normals()) return fields;
  any_normals = true;
  std::vector<double> column(n);
  for (int axis = 0; axis < 3; ++axis) {
    for (std::size_t i = 0; i < n; ++i) column[i] = cloud.normals[indices[i]][axis];
    fields.push_back(float_field<float>(std::string("nor:normal") + "XYZ"[axis], column));
  }
  return fields;
}

std::vector<OutField> E57Writer::extra_fields(long long scan, const std::vector<std::size_t>& indices) {
  const std::size_t n = indices.size();
  std::vector<OutField> fields;
  std::vector<double> column(n);
  for (const ScalarField& field : cloud.fields) {
    if (&field == scan_field) continue;
    for (std::size_t i = 0; i < n; ++i) column[i] = field.values[indices[i]];
    if (&field == intensity) {
      if (intensity_integer) {
        std::vector<std::int64_t> raw(n);
        for (std::size_t i = 0; i < n; ++i) raw[i] = to_stored<std::int64_t>(column[i]);
        fields.push_back(integer_field("intensity", raw, std::pair(static_cast<std::int64_t>(intensity_lo), static_cast<std::int64_t>(intensity_hi))));
      } else {
        fields.push_back(field.type == ScalarType::Float32 ? float_field<float>("intensity", column) : float_field<double>("intensity", column));
      }
      continue;
    }
    if (!is_xml_name(field.name)) {
      if (scan == groups.begin()->first) skipped.push_back(field.name);
      continue;
    }
    std::string element = field.name;
    if (!is_e57_point_field(field.name)) {
      element = std::string(kPointsurfPrefix) + field.name;
      any_extension = true;
    }
    if (field.type == ScalarType::Float32) fields.push_back(float_field<float>(element, column));
    else if (scalar_type_is_float(field.type)) fields.push_back(float_field<double>(element, column));
    else {
      std::vector<std::int64_t> raw(n);
      for (std::size_t i = 0; i < n; ++i) raw[i] = to_stored<std::int64_t>(column[i]);
      fields.push_back(integer_field(element, raw));
    }
  }
  return fields;
}

void E57Writer::write_scan(long long scan, const std::vector<std::size_t>& indices) {
  std::vector<OutField> fields = coordinate_fields(indices);
  const auto append = [&fields](std::vector<OutField> more) {
    for (OutField& f : more) fields.push_back(std::move(f));
  };
  append(color_fields(indices));
  append(normal_fields(indices));
  append(extra_fields(scan, indices));
  const std::uint64_t offset = write_section(writer, fields);
  scans_xml += scan_structure(scan, indices.size(), offset, fields);
}

// The scan's structure in /data3D: name, pose, limits and the points' prototype.
std::string E57Writer::scan_structure(long long scan, std::size_t n, std::uint64_t offset, const std::vector<OutField>& fields) {
  ScanPose pose;
  if (scan < static_cast<long long>(options.scan_poses.size())) pose = options.scan_poses[static_cast<std::size_t>(scan)];
  std::string prototype;
  for (const OutField& f : fields) prototype += "          " + f.element + "\n";
  const std::string name = pose.name.empty() ? fmt::format("scan {}", scan) : pose.name;
  const Eigen::Quaterniond q = pose.rotation.normalized();
  std::string out = fmt::format(
      "    <vectorChild type=\"Structure\">\n"
      "      <guid type=\"String\">{}</guid>\n"
      "      <name type=\"String\">{}</name>\n"
      "      <pose type=\"Structure\">\n"
      "        <rotation type=\"Structure\"><w type=\"Float\">{}</w><x type=\"Float\">{}</x><y type=\"Float\">{}</y><z type=\"Float\">{}</z></rotation>\n"
      "        <translation type=\"Structure\"><x type=\"Float\">{}</x><y type=\"Float\">{}</y><z type=\"Float\">{}</z></translation>\n"
      "      </pose>\n",
      cdata(guid(rng)), cdata(name), xml_number(q.w()), xml_number(q.x()), xml_number(q.y()), xml_number(q.z()),
      xml_number(pose.translation.x()), xml_number(pose.translation.y()), xml_number(pose.translation.z()));
  if (intensity)
    out += fmt::format(
        "      <intensityLimits type=\"Structure\"><intensityMinimum type=\"Float\">{}</intensityMinimum>"
        "<intensityMaximum type=\"Float\">{}</intensityMaximum></intensityLimits>\n",
        xml_number(intensity_lo), xml_number(intensity_hi));
  if (cloud.has_colors()) {
    out += "      <colorLimits type=\"Structure\">";
    for (const char* c : {"Red", "Green", "Blue"})
      out += fmt::format("<color{0}Minimum type=\"Integer\">0</color{0}Minimum><color{0}Maximum type=\"Integer\">{1}</color{0}Maximum>", c,
                         color_maximum);
    out += "</colorLimits>\n";
  }
  out += fmt::format(
      "      <points type=\"CompressedVector\" fileOffset=\"{}\" recordCount=\"{}\">\n"
      "        <prototype type=\"Structure\">\n{}        </prototype>\n"
      "        <codecs type=\"Vector\" allowHeterogeneousChildren=\"1\"/>\n"
      "      </points>\n"
      "    </vectorChild>\n",
      offset, n, prototype);
  return out;
}

void E57Writer::note_skipped_fields() {
  if (!skipped.empty())
    notes.push_back(fmt::format("field(s) {} not written: an E57 field name must be an XML name", fmt::join(skipped, ", ")));
}

void E57Writer::compose_xml() {
  std::string namespaces = fmt::format("xmlns=\"{}\"", kE57Namespace);
  if (any_normals) namespaces += fmt::format(" xmlns:nor=\"{}\"", kNormalsNamespace);
  if (any_extension) namespaces += fmt::format(" xmlns:pointsurf=\"{}\"", kPointsurfNamespace);
  xml = fmt::format(
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      "<e57Root type=\"Structure\" {}>\n"
      "  <formatName type=\"String\"><![CDATA[ASTM E57 3D Imaging Data File]]></formatName>\n"
      "  <guid type=\"String\">{}</guid>\n"
      "  <versionMajor type=\"Integer\">1</versionMajor>\n"
      "  <versionMinor type=\"Integer\">0</versionMinor>\n"
      "  <e57LibraryVersion type=\"String\"><![CDATA[pointsurf {}]]></e57LibraryVersion>\n"
      "  <coordinateMetadata type=\"String\">{}</coordinateMetadata>\n"
      "  <data3D type=\"Vector\" allowHeterogeneousChildren=\"1\">\n{}  </data3D>\n"
      "  <images2D type=\"Vector\" allowHeterogeneousChildren=\"1\"/>\n"
      "</e57Root>\n",
      namespaces, cdata(guid(rng)), POINTSURF_VERSION, cloud.crs.wkt.empty() ? std::string() : cdata(cloud.crs.wkt), scans_xml);
}

void E57Writer::append_xml_and_header() {
  writer.pad_to(4);
  xml_logical = writer.size();
  writer.append(xml.data(), xml.size());
  const std::uint64_t pages = std::max<std::uint64_t>(1, (writer.size() + kE57PagePayload - 1) / kE57PagePayload);
  unsigned char header[kE57HeaderSize] = {};
  std::memcpy(header, "ASTM-E57", 8);
  const std::uint32_t major = 1, minor = 0;
  const std::uint64_t file_length = pages * kE57PageSize, xml_physical = e57_physical(xml_logical), xml_length = xml.size(),
                      page_size = kE57PageSize;
  std::memcpy(header + 8, &major, 4);
  std::memcpy(header + 12, &minor, 4);
  std::memcpy(header + 16, &file_length, 8);
  std::memcpy(header + 24, &xml_physical, 8);
  std::memcpy(header + 32, &xml_length, 8);
  std::memcpy(header + 40, &page_size, 8);
  writer.patch(0, header, kE57HeaderSize);
}

void E57Writer::save() const {
  FileWriter out(path);
  writer.write_pages(out);
  out.close();
}

void write_e57(const std::filesystem::path& path, const PointCloud& cloud, const WriteOptions& options, std::vector<std::string>& notes) {
  E57Writer e57(path, cloud, options, notes);
  e57.group_scans();
  e57.set_intensity_limits();
  e57.set_color_limits();
  e57.start_file();
  for (const auto& [scan, indices] : e57.groups) e57.write_scan(scan, indices);
  e57.note_skipped_fields();
  e57.compose_xml();
  e57.append_xml_and_header();
  e57.save();
}

}  // namespace pointsurf::io::detail
