// SPDX-License-Identifier: GPL-3.0-or-later
// E57 reader (the layout and the writer: io/detail/e57_format.h, e57_write.cpp), written from the
// standard and checked against files of libE57Format and the libE57 reference implementation
// (tests/data/README.md).
//
// Reading: cartesianX/Y/Z, or sphericalRange/Azimuth/Elevation converted to cartesian; poses
// applied (ReadOptions::apply_poses) and reported per scan; a `scan` field (0, 1, ...) when the
// file has more than one scan; points flagged by cartesianInvalidState / sphericalInvalidState
// (not 0) dropped and counted in a warning; colorRed/Green/Blue scaled to [0, 1] by colorLimits
// (else the field's minimum and maximum); intensity as stored, its value (intensityLimits only
// give its range; values in [0, 1] outside them were written normalised and are scaled back); surface normals of the libE57 extension (nor:normalX/Y/Z) as normals;
// every other field (rowIndex, timeStamp, ...) as a named field. Images (/images2D) are skipped
// with a warning. Index packets are skipped.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <pugixml.hpp>

#include "io/detail/e57_format.h"
#include "io/detail/e57_pages.h"
#include "io/detail/file_util.h"
#include "io/detail/formats.h"
#include "pointsurf/core/error.h"

namespace pointsurf::io::detail {
namespace {

// One terminal element of a prototype: one bytestream in every data packet.
struct Leaf {
  enum class Kind { Integer, ScaledInteger, Float };
  std::string name;
  Kind kind = Kind::Float;
  bool single = false;  // Float precision="single"
  std::int64_t minimum = std::numeric_limits<std::int64_t>::min();
  std::int64_t maximum = std::numeric_limits<std::int64_t>::max();
  double scale = 1.0, offset = 0.0;
  double float_minimum = -std::numeric_limits<double>::infinity(), float_maximum = std::numeric_limits<double>::infinity();
  unsigned bits = 0;  // bit-packed width (Integer, ScaledInteger)

  // Bytes the bytestream needs for `count` records.
  std::uint64_t bytes_for(std::uint64_t count) const {
    if (kind == Kind::Float) return count * (single ? 4 : 8);
    return (count * bits + 7) / 8;  // count * bits < 2^64: count is bounded by the file size first
  }
  // Limits of the decoded values, for normalising colour.
  double lower() const { return kind == Kind::Float ? float_minimum : kind == Kind::Integer ? double(minimum) : double(minimum) * scale + offset; }
  double upper() const { return kind == Kind::Float ? float_maximum : kind == Kind::Integer ? double(maximum) : double(maximum) * scale + offset; }
};

struct Scan {
  std::string name;
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Vector3d translation = Vector3d::Zero();
  std::vector<Leaf> leaves;
  std::uint64_t records = 0;
  std::uint64_t file_offset = 0;
  double intensity_min = NAN, intensity_max = NAN;
  double color_min[3] = {NAN, NAN, NAN}, color_max[3] = {NAN, NAN, NAN};
};

class XmlReader {
public:
  XmlReader(const std::string& name) : name_(name) {}

  [[noreturn]] void fail(const std::string& where, const std::string& what) const {
    throw InputError(fmt::format("{}: XML section: {}: {}", name_, where, what));
  }

  long long integer(std::string_view text, const std::string& where) const {
    const std::string_view t = trim(text);
    if (t.empty()) return 0;
    long long v = 0;
    if (!parse_number(t, v)) fail(where, fmt::format("'{}' is not an integer", shown(t)));
    return v;
  }
  double number(std::string_view text, const std::string& where) const {
    const std::string_view t = trim(text);
    if (t.empty()) return 0.0;
    double v = 0;
    if (!parse_number(t, v)) fail(where, fmt::format("'{}' is not a number", shown(t)));
    return v;
  }
  // The value of an Integer, ScaledInteger or Float element; `fallback` when it is absent.
  double value(const pugi::xml_node& node, const std::string& where, double fallback) const {
    if (!node) return fallback;
    const std::string_view type = node.attribute("type").value();
    if (type == "Integer") return static_cast<double>(integer(node.child_value(), where));
    if (type == "Float") return number(node.child_value(), where);
    if (type == "ScaledInteger") {
      const double scale = node.attribute("scale") ? number(node.attribute("scale").value(), where + " scale") : 1.0;
      const double offset = node.attribute("offset") ? number(node.attribute("offset").value(), where + " offset") : 0.0;
      return static_cast<double>(integer(node.child_value(), where)) * scale + offset;
    }
    fail(where, fmt::format("type '{}', expected Integer, ScaledInteger or Float", shown(type)));
  }

  void leaves(const pugi::xml_node& node, const std::string& where, std::vector<Leaf>& out, int depth) const {
    if (depth > 8) fail(where, "prototype nested more than 8 levels");
    for (const pugi::xml_node& child : node.children()) {
      if (child.type() != pugi::node_element) continue;
      const std::string at = where + "/" + child.name();
      const std::string_view type = child.attribute("type").value();
      if (type == "Structure") {
        leaves(child, at, out, depth + 1);
        continue;
      }
      Leaf leaf;
      leaf.name = child.name();
      if (type == "Integer" || type == "ScaledInteger") {
        leaf.kind = type == "Integer" ? Leaf::Kind::Integer : Leaf::Kind::ScaledInteger;
        if (child.attribute("minimum")) leaf.minimum = integer(child.attribute("minimum").value(), at + " minimum");
        if (child.attribute("maximum")) leaf.maximum = integer(child.attribute("maximum").value(), at + " maximum");
        if (leaf.maximum < leaf.minimum) fail(at, fmt::format("maximum {} below minimum {}", leaf.maximum, leaf.minimum));
        if (leaf.kind == Leaf::Kind::ScaledInteger) {
          if (child.attribute("scale")) leaf.scale = number(child.attribute("scale").value(), at + " scale");
          if (child.attribute("offset")) leaf.offset = number(child.attribute("offset").value(), at + " offset");
          if (!(leaf.scale != 0.0) || !std::isfinite(leaf.scale) || !std::isfinite(leaf.offset))
            fail(at, "scale must be finite and non-zero, offset finite");
        }
        leaf.bits = bits_for_range(leaf.minimum, leaf.maximum);
      } else if (type == "Float") {
        leaf.kind = Leaf::Kind::Float;
        const std::string_view precision = child.attribute("precision").value();
        if (precision == "single") leaf.single = true;
        else if (!precision.empty() && precision != "double")
          fail(at, fmt::format("precision '{}', expected single or double", shown(precision)));
        if (child.attribute("minimum")) leaf.float_minimum = number(child.attribute("minimum").value(), at + " minimum");
        if (child.attribute("maximum")) leaf.float_maximum = number(child.attribute("maximum").value(), at + " maximum");
      } else {
        fail(at, fmt::format("prototype field of type '{}': only Integer, ScaledInteger, Float and Structure are supported", shown(type)));
      }
      out.push_back(std::move(leaf));
    }
  }

  Scan scan(const pugi::xml_node& node, std::size_t index) const {
    Scan s;
    const std::string where = fmt::format("/data3D/{}", index);
    s.name = node.child("name").child_value();
    if (s.name.empty()) s.name = fmt::format("scan {}", index);
    if (const pugi::xml_node pose = node.child("pose")) {
      if (const pugi::xml_node r = pose.child("rotation")) {
        const double w = value(r.child("w"), where + "/pose/rotation/w", 1.0);
        const double x = value(r.child("x"), where + "/pose/rotation/x", 0.0);
        const double y = value(r.child("y"), where + "/pose/rotation/y", 0.0);
        const double z = value(r.child("z"), where + "/pose/rotation/z", 0.0);
        const double norm = std::sqrt(w * w + x * x + y * y + z * z);
        if (!(norm > 1e-12) || !std::isfinite(norm)) fail(where + "/pose/rotation", "the quaternion is zero or not finite");
        s.rotation = Eigen::Quaterniond(w / norm, x / norm, y / norm, z / norm);
      }
      if (const pugi::xml_node t = pose.child("translation"))
        s.translation = Vector3d(value(t.child("x"), where + "/pose/translation/x", 0.0), value(t.child("y"), where + "/pose/translation/y", 0.0),
                                 value(t.child("z"), where + "/pose/translation/z", 0.0));
      if (!s.translation.allFinite()) fail(where + "/pose/translation", "not finite");
    }
    if (const pugi::xml_node l = node.child("intensityLimits")) {
      s.intensity_min = value(l.child("intensityMinimum"), where + "/intensityLimits/intensityMinimum", NAN);
      s.intensity_max = value(l.child("intensityMaximum"), where + "/intensityLimits/intensityMaximum", NAN);
    }
    if (const pugi::xml_node l = node.child("colorLimits")) {
      const char* channel[3] = {"Red", "Green", "Blue"};
      for (int c = 0; c < 3; ++c) {
        const std::string lo = fmt::format("color{}Minimum", channel[c]), hi = fmt::format("color{}Maximum", channel[c]);
        s.color_min[c] = value(l.child(lo.c_str()), where + "/colorLimits/" + lo, NAN);
        s.color_max[c] = value(l.child(hi.c_str()), where + "/colorLimits/" + hi, NAN);
      }
    }
    const pugi::xml_node points = node.child("points");
    if (!points || std::string_view(points.attribute("type").value()) != "CompressedVector")
      fail(where, "no 'points' element of type CompressedVector");
    const long long offset = integer(points.attribute("fileOffset").value(), where + "/points fileOffset");
    const long long records = integer(points.attribute("recordCount").value(), where + "/points recordCount");
    if (offset <= 0 || records < 0) fail(where + "/points", fmt::format("fileOffset {} or recordCount {} out of range", offset, records));
    s.file_offset = static_cast<std::uint64_t>(offset);
    s.records = static_cast<std::uint64_t>(records);
    const pugi::xml_node prototype = points.child("prototype");
    if (!prototype) fail(where + "/points", "no prototype");
    leaves(prototype, where + "/points/prototype", s.leaves, 0);
    if (s.leaves.empty()) fail(where + "/points/prototype", "no fields");
    for (const pugi::xml_node& codec : points.child("codecs").children())
      if (codec.type() == pugi::node_element && !codec.child("bitPackCodec"))
        fail(where + "/points/codecs", "a codec other than bitPackCodec (none other is defined by E57 1.0)");
    return s;
  }

private:
  const std::string& name_;
};

// The bytestreams of one scan's compressed vector section, one per leaf, whole.
std::vector<std::vector<unsigned char>> read_bytestreams(const E57PagedReader& file, const Scan& scan, std::size_t index) {
  const std::string& name = file.name();
  const std::string where = fmt::format("scan {} ({}) section at byte {}", index, scan.name, scan.file_offset);
  if (!is_payload_offset(scan.file_offset) || e57_logical(scan.file_offset) >= file.logical_size())
    throw InputError(fmt::format("{}: {}: offset outside the file or on a checksum", name, where));
  const std::uint64_t start = e57_logical(scan.file_offset);
  unsigned char header[kSectionHeaderSize];
  file.read(start, kSectionHeaderSize, header, where);
  if (header[0] != kCompressedVectorSection)
    throw InputError(fmt::format("{}: {}: section id {}, expected {} (compressed vector)", name, where, header[0], kCompressedVectorSection));
  const auto length = load_value<std::uint64_t>(reinterpret_cast<const char*>(header) + 8);
  const auto data_physical = load_value<std::uint64_t>(reinterpret_cast<const char*>(header) + 16);
  if (length < kSectionHeaderSize || length > file.logical_size() - start)
    throw InputError(fmt::format("{}: {}: section length {} out of range [{}, {}]", name, where, length, kSectionHeaderSize, file.logical_size() - start));
  const std::uint64_t end = start + length;
  const std::uint64_t data = e57_logical(data_physical);
  if (scan.records > 0 && (!is_payload_offset(data_physical) || data < start + kSectionHeaderSize || data >= end))
    throw InputError(fmt::format("{}: {}: first data packet at byte {} lies outside the section", name, where, data_physical));

  // Each field needs a known number of bytes; their sum cannot exceed the section.
  std::vector<std::uint64_t> need(scan.leaves.size());
  std::uint64_t total = 0;
  const std::uint64_t max_records = 8 * file.logical_size() + 1024;  // beyond it even 1-bit fields overflow the file
  if (scan.records > max_records)
    throw InputError(fmt::format("{}: {}: recordCount {} exceeds what a file of this size can hold", name, where, scan.records));
  // Records whose every field is constant (0 bits) take no bytes: bound them apart, or a tiny
  // file could ask for any number of identical points.
  constexpr std::uint64_t kMaxConstantRecords = std::uint64_t{1} << 24;
  const bool constant = std::all_of(scan.leaves.begin(), scan.leaves.end(), [](const Leaf& l) { return l.kind != Leaf::Kind::Float && l.bits == 0; });
  if (constant && scan.records > kMaxConstantRecords)
    throw InputError(fmt::format("{}: {}: recordCount {} of points whose every field is constant (0 bits); at most {} are read", name, where,
                                 scan.records, kMaxConstantRecords));
  for (std::size_t k = 0; k < scan.leaves.size(); ++k) total += need[k] = scan.leaves[k].bytes_for(scan.records);
  if (total > length)
    throw InputError(fmt::format("{}: {}: {} records of {} fields need {} bytes, the section holds {}", name, where, scan.records,
                                 scan.leaves.size(), total, length));
  std::vector<std::vector<unsigned char>> streams(scan.leaves.size());
  for (std::size_t k = 0; k < streams.size(); ++k) streams[k].reserve(need[k] + 8);

  auto complete = [&] {
    for (std::size_t k = 0; k < streams.size(); ++k)
      if (streams[k].size() < need[k]) return false;
    return true;
  };
  std::vector<unsigned char> packet(kMaxPacketSize);
  std::uint64_t pos = data;
  std::size_t packet_index = 0;
  // Every packet advances pos by at least 4 bytes, so the walk ends within the section.
  while (scan.records > 0 && !complete()) {
    const std::string at = fmt::format("{}: {}: packet {} at logical offset {}", name, where, packet_index, pos);
    if (end - pos < 4) throw InputError(fmt::format("{}: the section ends before the fields are complete (truncated)", at));
    file.read(pos, 4, packet.data(), at);
    const std::size_t size = std::size_t{load_value<std::uint16_t>(reinterpret_cast<const char*>(packet.data()) + 2)} + 1;
    if (size < 4 || size % 4 != 0 || size > end - pos)
      throw InputError(fmt::format("{}: packet length {} is not a multiple of 4 or runs past the section end", at, size));
    const unsigned char type = packet[0];
    if (type == kDataPacket) {
      file.read(pos, size, packet.data(), at);
      if (size < 6) throw InputError(fmt::format("{}: data packet shorter than its 6-byte header", at));
      const std::size_t count = load_value<std::uint16_t>(reinterpret_cast<const char*>(packet.data()) + 4);
      if (count != streams.size())
        throw InputError(fmt::format("{}: {} bytestreams, the prototype has {} fields", at, count, streams.size()));
      std::size_t offset = 6 + 2 * count;
      if (offset > size) throw InputError(fmt::format("{}: bytestream lengths run past the packet end", at));
      for (std::size_t k = 0; k < count; ++k) {
        const std::size_t n = load_value<std::uint16_t>(reinterpret_cast<const char*>(packet.data()) + 6 + 2 * k);
        if (n > size - offset)
          throw InputError(fmt::format("{}: bytestream {} ({}) of {} bytes runs past the packet end", at, k, scan.leaves[k].name, n));
        // Bytes beyond what a field needs are padding (a writer flushes whole words).
        const std::size_t keep = static_cast<std::size_t>(std::min<std::uint64_t>(n, need[k] - std::min<std::uint64_t>(need[k], streams[k].size())));
        streams[k].insert(streams[k].end(), packet.begin() + offset, packet.begin() + offset + keep);
        offset += n;
      }
    } else if (type != kIndexPacket && type != kEmptyPacket) {
      throw InputError(fmt::format("{}: packet type {}, expected 0 (index), 1 (data) or 2 (empty)", at, type));
    }
    pos += size;
    ++packet_index;
  }
  return streams;
}

// Decodes one field of `count` records from its bytestream.
std::vector<double> decode(std::vector<unsigned char>& stream, const Leaf& leaf, std::uint64_t count, const std::string& where) {
  std::vector<double> out(count);
  if (leaf.kind == Leaf::Kind::Float) {
    const unsigned char* p = stream.data();
    if (leaf.single)
      for (std::uint64_t i = 0; i < count; ++i) out[i] = load_value<float>(reinterpret_cast<const char*>(p + 4 * i));
    else if (count > 0)
      std::memcpy(out.data(), p, count * sizeof(double));
    return out;
  }
  stream.resize(stream.size() + 16, 0);  // room for the unaligned 8-byte loads below
  const unsigned bits = leaf.bits;
  const std::uint64_t mask = bits >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << bits) - 1;
  const std::uint64_t range = static_cast<std::uint64_t>(leaf.maximum) - static_cast<std::uint64_t>(leaf.minimum);
  const char* p = reinterpret_cast<const char*>(stream.data());
  for (std::uint64_t i = 0; i < count; ++i) {
    std::uint64_t raw = 0;
    if (bits > 0) {
      const std::uint64_t bit = i * bits;
      const unsigned shift = static_cast<unsigned>(bit & 7);
      raw = load_value<std::uint64_t>(p + (bit >> 3)) >> shift;
      if (shift + bits > 64) raw |= std::uint64_t{static_cast<unsigned char>(p[(bit >> 3) + 8])} << (64 - shift);
      raw &= mask;
      if (raw > range)
        throw InputError(fmt::format("{}: record {}: value {} outside [{}, {}]", where, i,
                                     static_cast<std::int64_t>(static_cast<std::uint64_t>(leaf.minimum) + raw), leaf.minimum, leaf.maximum));
    }
    const auto v = static_cast<std::int64_t>(static_cast<std::uint64_t>(leaf.minimum) + raw);
    out[i] = leaf.kind == Leaf::Kind::Integer ? static_cast<double>(v) : static_cast<double>(v) * leaf.scale + leaf.offset;
  }
  return out;
}

ScalarType field_type(const Leaf& leaf) {
  if (leaf.kind == Leaf::Kind::Float) return leaf.single ? ScalarType::Float32 : ScalarType::Float64;
  if (leaf.kind == Leaf::Kind::ScaledInteger) return ScalarType::Float64;
  auto fits = [&](auto lo, auto hi) { return leaf.minimum >= static_cast<std::int64_t>(lo) && leaf.maximum <= static_cast<std::int64_t>(hi); };
  if (fits(0, 255)) return ScalarType::UInt8;
  if (fits(-128, 127)) return ScalarType::Int8;
  if (fits(0, 65535)) return ScalarType::UInt16;
  if (fits(-32768, 32767)) return ScalarType::Int16;
  if (fits(0, 4294967295LL)) return ScalarType::UInt32;
  if (fits(std::numeric_limits<std::int32_t>::min(), std::numeric_limits<std::int32_t>::max())) return ScalarType::Int32;
  return ScalarType::Int64;
}

// Scales `v` from [lo, hi] to [0, 1]; false when the limits are unusable.
bool normalise(std::vector<double>& v, double lo, double hi) {
  if (!std::isfinite(lo) || !std::isfinite(hi) || !(hi > lo)) return false;
  const double inv = 1.0 / (hi - lo);
  for (double& x : v) x = (x - lo) * inv;
  return true;
}

// Intensity is stored as its value, within intensityLimits [lo, hi] (ASTM E2807). Values all in
// [0, 1] with some outside the limits were stored normalised against them.
bool intensity_stored_normalised(const std::vector<double>& v, double lo, double hi) {
  if (!std::isfinite(lo) || !std::isfinite(hi) || !(hi > lo) || v.empty()) return false;
  const auto [a, b] = std::minmax_element(v.begin(), v.end());
  return *a >= 0.0 && *b <= 1.0 && (*a < lo || *b > hi);
}

// One scan's points as a cloud (before concatenation).
struct ScanCloud {
  PointCloud cloud;
  std::size_t invalid = 0;
};

ScanCloud scan_cloud(const E57PagedReader& file, const Scan& scan, std::size_t index, const ReadOptions& options, std::vector<std::string>& warnings) {
  std::vector<std::vector<unsigned char>> streams = read_bytestreams(file, scan, index);
  std::map<std::string, std::vector<double>, std::less<>> columns;
  std::vector<const Leaf*> order;
  for (std::size_t k = 0; k < scan.leaves.size(); ++k) {
    const std::string where = fmt::format("{}: scan {} ({}) field {}", file.name(), index, scan.name, scan.leaves[k].name);
    if (columns.count(scan.leaves[k].name)) throw InputError(fmt::format("{}: given twice in the prototype", where));
    columns[scan.leaves[k].name] = decode(streams[k], scan.leaves[k], scan.records, where);
    std::vector<unsigned char>().swap(streams[k]);
    order.push_back(&scan.leaves[k]);
  }
  auto take = [&](std::string_view key) -> std::vector<double>* {
    auto it = columns.find(key);
    return it == columns.end() ? nullptr : &it->second;
  };
  auto leaf_of = [&](std::string_view key) -> const Leaf* {
    for (const Leaf* l : order)
      if (l->name == key) return l;
    return nullptr;
  };
  const std::size_t n = static_cast<std::size_t>(scan.records);
  ScanCloud out;
  PointCloud& c = out.cloud;
  std::vector<double>*x = take("cartesianX"), *y = take("cartesianY"), *z = take("cartesianZ");
  std::vector<double>*r = take("sphericalRange"), *az = take("sphericalAzimuth"), *el = take("sphericalElevation");
  std::vector<double>* invalid = nullptr;
  c.positions.resize(n);
  if (x && y && z) {
    for (std::size_t i = 0; i < n; ++i) c.positions[i] = Vector3d((*x)[i], (*y)[i], (*z)[i]);
    invalid = take("cartesianInvalidState");
  } else if (r && az && el) {
    for (std::size_t i = 0; i < n; ++i) {
      const double ce = std::cos((*el)[i]);
      c.positions[i] = (*r)[i] * Vector3d(ce * std::cos((*az)[i]), ce * std::sin((*az)[i]), std::sin((*el)[i]));
    }
    invalid = take("sphericalInvalidState");
  } else {
    throw InputError(fmt::format("{}: scan {} ({}): neither cartesianX/Y/Z nor sphericalRange/Azimuth/Elevation among its fields",
                                 file.name(), index, scan.name));
  }
  const bool identity = scan.rotation.coeffs() == Eigen::Quaterniond::Identity().coeffs() && scan.translation == Vector3d::Zero();
  if (options.apply_poses && !identity) {
    const Eigen::Matrix3d rotation = scan.rotation.toRotationMatrix();
    for (Vector3d& p : c.positions) p = rotation * p + scan.translation;
  }
  const char* colour_names[3] = {"colorRed", "colorGreen", "colorBlue"};
  if (take(colour_names[0]) && take(colour_names[1]) && take(colour_names[2])) {
    c.colors.resize(n);
    for (int ch = 0; ch < 3; ++ch) {
      std::vector<double>& v = *take(colour_names[ch]);
      const Leaf* leaf = leaf_of(colour_names[ch]);
      if (!normalise(v, scan.color_min[ch], scan.color_max[ch]) && !normalise(v, leaf->lower(), leaf->upper()))
        throw InputError(fmt::format("{}: scan {} ({}): {} has no usable limits (colorLimits or the field's minimum and maximum)", file.name(),
                                     index, scan.name, colour_names[ch]));
      for (std::size_t i = 0; i < n; ++i) c.colors[i][ch] = static_cast<float>(std::clamp(v[i], 0.0, 1.0));
    }
  }
  const char* normal_names[3] = {"nor:normalX", "nor:normalY", "nor:normalZ"};
  if (take(normal_names[0]) && take(normal_names[1]) && take(normal_names[2])) {
    c.normals.resize(n);
    for (std::size_t i = 0; i < n; ++i) c.normals[i] = Vector3d((*take(normal_names[0]))[i], (*take(normal_names[1]))[i], (*take(normal_names[2]))[i]);
  }
  for (const Leaf* leaf : order) {
    const std::string_view key = leaf->name;
    if (key.rfind("cartesian", 0) == 0 && key != "cartesianInvalidState") continue;
    if (key.rfind("spherical", 0) == 0 && key != "sphericalInvalidState") continue;
    if ((c.has_colors() && key.rfind("color", 0) == 0) || (c.has_normals() && key.rfind("nor:normal", 0) == 0)) continue;
    if (key == "cartesianInvalidState" || key == "sphericalInvalidState") {
      if (take(key) == invalid) continue;
    }
    std::string field = std::string(key.rfind(kPointsurfPrefix, 0) == 0 ? key.substr(kPointsurfPrefix.size()) : key);
    ScalarType type = field_type(*leaf);
    std::vector<double>& v = *take(key);
    if (key == "intensity" && intensity_stored_normalised(v, scan.intensity_min, scan.intensity_max)) {
      // pointsurf before issue 28 stored (v - lo) / (hi - lo) under intensityLimits [lo, hi].
      warnings.push_back(fmt::format("scan {} ({}): intensity lies in [0, 1], outside its intensityLimits [{}, {}]: read as stored "
                                     "in [0, 1] against those limits (files of pointsurf before 2026-12)",
                                     index, scan.name, scan.intensity_min, scan.intensity_max));
      for (double& x : v) x = scan.intensity_min + x * (scan.intensity_max - scan.intensity_min);
      type = ScalarType::Float64;
    }
    if (c.fields.contains(field)) continue;
    c.fields.add(field, 0, type).values = std::move(v);
  }
  if (invalid) {
    std::vector<std::size_t> keep;
    keep.reserve(n);
    for (std::size_t i = 0; i < n; ++i)
      if ((*invalid)[i] == 0) keep.push_back(i);
    out.invalid = n - keep.size();
    if (out.invalid > 0) c = c.select(keep);
  }
  return out;
}

// Appends `part` to `all`; a field or attribute one of them lacks is filled with zeros.
void append_cloud(PointCloud& all, PointCloud&& part, std::vector<std::string>& warnings, std::size_t scan) {
  const std::size_t before = all.size(), added = part.size();
  if (before == 0 && all.fields.size() == 0 && all.colors.empty() && all.normals.empty()) {
    all = std::move(part);
    return;
  }
  auto merge = [&](auto& a, auto& b, auto zero, const char* what) {
    if (a.empty() && b.empty()) return;
    if (a.empty() != b.empty()) warnings.push_back(fmt::format("scan {}: {} missing in some scans, zero there", scan, what));
    if (a.empty()) a.assign(before, zero);
    if (b.empty()) b.assign(added, zero);
    a.insert(a.end(), b.begin(), b.end());
  };
  all.positions.insert(all.positions.end(), part.positions.begin(), part.positions.end());
  merge(all.normals, part.normals, Vector3d::Zero().eval(), "normals");
  merge(all.colors, part.colors, Vector3f::Zero().eval(), "colours");
  for (ScalarField& f : all.fields) {
    const ScalarField* g = part.fields.find(f.name);
    if (g) f.values.insert(f.values.end(), g->values.begin(), g->values.end());
    else {
      warnings.push_back(fmt::format("scan {}: field {} missing, zero there", scan, f.name));
      f.values.resize(before + added, 0.0);
    }
  }
  for (const ScalarField& g : part.fields) {
    if (all.fields.contains(g.name)) continue;
    warnings.push_back(fmt::format("scan {}: field {} missing in earlier scans, zero there", scan, g.name));
    ScalarField& f = all.fields.add(g.name, before, g.type);
    f.values.insert(f.values.end(), g.values.begin(), g.values.end());
  }
}

}  // namespace

RawData read_e57_bytes(std::string_view bytes, const std::string& name, const ReadOptions& options) {
  const E57PagedReader file(bytes, name);
  const E57Header& h = file.header();
  std::string xml(static_cast<std::size_t>(h.xml_logical_length), '\0');
  file.read(e57_logical(h.xml_physical_offset), xml.size(), xml.data(), "XML section");
  pugi::xml_document doc;
  const pugi::xml_parse_result parsed = doc.load_buffer(xml.data(), xml.size(), pugi::parse_default, pugi::encoding_utf8);
  if (!parsed)
    throw InputError(fmt::format("{}: XML section: {} at byte {} of {}", name, parsed.description(), parsed.offset, xml.size()));
  const pugi::xml_node root = doc.child("e57Root");
  if (!root) throw InputError(fmt::format("{}: XML section: no e57Root element", name));
  const XmlReader reader(name);
  RawData raw;
  raw.encoding = fmt::format("E57 {}.{}", h.major, h.minor);
  std::vector<Scan> scans;
  for (const pugi::xml_node& child : root.child("data3D").children())
    if (child.type() == pugi::node_element) scans.push_back(reader.scan(child, scans.size()));
  if (scans.empty()) throw InputError(fmt::format("{}: no scans in /data3D", name));
  std::size_t images = 0;
  for (const pugi::xml_node& child : root.child("images2D").children())
    if (child.type() == pugi::node_element) ++images;
  if (images > 0) raw.warnings.push_back(fmt::format("{} image(s) in /images2D skipped: pointsurf reads the points only", images));
  std::size_t invalid = 0;
  for (std::size_t s = 0; s < scans.size(); ++s) {
    ScanCloud part = scan_cloud(file, scans[s], s, options, raw.warnings);
    invalid += part.invalid;
    if (scans.size() > 1) part.cloud.fields.add("scan", part.cloud.size(), scans.size() <= 65536 ? ScalarType::UInt16 : ScalarType::UInt32).values.assign(part.cloud.size(), double(s));
    ScanPose pose;
    pose.name = scans[s].name;
    pose.points = part.cloud.size();
    pose.rotation = scans[s].rotation;
    pose.translation = scans[s].translation;
    raw.scans.push_back(pose);
    append_cloud(raw.cloud, std::move(part.cloud), raw.warnings, s);
  }
  // The root's coordinateMetadata: the coordinate system as a string (WKT is what pointsurf writes).
  raw.cloud.crs.wkt = root.child("coordinateMetadata").child_value();
  if (invalid > 0)
    raw.warnings.push_back(fmt::format("{} point(s) flagged invalid (cartesianInvalidState / sphericalInvalidState) dropped", invalid));
  return raw;
}

RawData read_e57(const std::filesystem::path& path, const ReadOptions& options) {
  const FileBytes bytes(path);
  return read_e57_bytes(bytes.view(), display_name(path), options);
}

}  // namespace pointsurf::io::detail
