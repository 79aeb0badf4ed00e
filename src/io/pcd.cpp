// SPDX-License-Identifier: GPL-3.0-or-later
// PCD v0.7 (the Point Cloud Library format): a text header, then the points as ascii, binary
// (row-major, little endian) or binary_compressed (LZF over column-major data).
//
// Reading: x y z of any numeric type; normal_x.. (or nx ny nz) when all three are present; rgb
// and rgba packed in 4 bytes (float or uint32) as 0x00RRGGBB, the alpha of rgba kept as field
// "alpha"; every other field kept as a ScalarField with its type. A field with COUNT k > 1
// (histograms such as FPFH) becomes k fields "name_0" .. "name_<k-1>". "_" padding is skipped.
// Organized clouds (HEIGHT > 1) are flattened and their NaN points dropped here, counted in
// RawData::dropped_nonfinite with a warning.
//
// Writing: x y z as F4 when float32 moves no point by more than 1e-4 of the spacing (PCL's tools
// and Open3D 0.16 read F8 positions as zeros), else F8 with a note; single_precision forces F4
// (refused beyond 1e-5 of the diagonal), double_precision F8. normal_x..
// as F4, rgb packed into an F4 (U4 in ascii files, as PCL writes it), fields with their own
// type. PCL reads all three encodings back (checked with pcl_convert_pcd_ascii_binary 1.13).
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>
#include <lzf.h>

#include "io/detail/file_util.h"
#include "io/detail/formats.h"
#include "pointsurf/core/error.h"

namespace pointsurf::io::detail {
namespace {

struct PcdField {
  std::string name;
  char type = 'F';         // 'I', 'U' or 'F'
  int size = 4;            // bytes per value
  std::size_t count = 1;   // values per point
  std::size_t offset = 0;  // byte offset of the field within one row-major point
};

struct PcdHeader {
  std::vector<PcdField> fields;
  std::size_t width = 0, height = 1, points = 0;
  std::string data;              // "ascii", "binary" or "binary_compressed"
  std::size_t data_offset = 0;   // first byte after the DATA line
  std::size_t data_line = 0;     // line number of the DATA line
  std::size_t point_size = 0;    // bytes of one row-major point
  std::size_t values_per_point = 0;
};

std::string upper(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return out;
}

ScalarType scalar_type_of(char type, int size) {
  if (type == 'F') return size == 4 ? ScalarType::Float32 : ScalarType::Float64;
  const bool is_signed = type == 'I';
  switch (size) {
    case 1: return is_signed ? ScalarType::Int8 : ScalarType::UInt8;
    case 2: return is_signed ? ScalarType::Int16 : ScalarType::UInt16;
    case 4: return is_signed ? ScalarType::Int32 : ScalarType::UInt32;
    default: return is_signed ? ScalarType::Int64 : ScalarType::UInt64;
  }
}

double load_scalar(const char* p, char type, int size) noexcept {
  if (type == 'F') return size == 4 ? static_cast<double>(load_value<float>(p)) : load_value<double>(p);
  if (type == 'I') {
    switch (size) {
      case 1: return load_value<std::int8_t>(p);
      case 2: return load_value<std::int16_t>(p);
      case 4: return load_value<std::int32_t>(p);
      default: return static_cast<double>(load_value<std::int64_t>(p));
    }
  }
  switch (size) {
    case 1: return load_value<std::uint8_t>(p);
    case 2: return load_value<std::uint16_t>(p);
    case 4: return load_value<std::uint32_t>(p);
    default: return static_cast<double>(load_value<std::uint64_t>(p));
  }
}

// Parses the text header up to and including the DATA line, validating every entry.
PcdHeader parse_pcd_header(std::string_view bytes, const std::string& name) {
  TextCursor cursor(bytes);
  std::string_view line;
  std::vector<std::string_view> tokens;
  PcdHeader h;
  std::vector<std::string> field_names, sizes, types, counts;
  std::size_t fields_line = 0, size_line = 0, type_line = 0, count_line = 0, width_line = 0, height_line = 0, points_line = 0;
  bool have_points = false, have_height = false;

  auto fail = [&](std::size_t at, const std::string& what) -> void {
    throw InputError(fmt::format("{}: line {}: {}", name, at, what));
  };
  auto parse_count = [&](std::string_view keyword, std::size_t at) {
    if (tokens.size() != 2) fail(at, fmt::format("{} needs one value, got {}", keyword, tokens.size() - 1));
    long long v = 0;
    if (!parse_number(tokens[1], v) || v < 0)
      fail(at, fmt::format("{} '{}' is not a non-negative integer", keyword, shown(tokens[1])));
    return static_cast<std::size_t>(v);
  };

  for (;;) {
    if (!cursor.next_line(line))
      throw InputError(fmt::format("{}: header ends at line {} without a DATA line (expected DATA ascii, binary or binary_compressed)",
                                   name, cursor.line_number()));
    const std::string_view t = trim(line);
    if (t.empty() || t.front() == '#') continue;
    const std::size_t at = cursor.line_number();
    split_tokens(t, tokens);
    const std::string keyword = upper(tokens[0]);
    auto collect = [&](std::vector<std::string>& into, std::size_t& where) {
      if (where != 0) fail(at, fmt::format("{} given twice (first on line {})", keyword, where));
      where = at;
      for (std::size_t i = 1; i < tokens.size(); ++i) into.emplace_back(tokens[i]);
    };
    if (keyword == "VERSION") continue;
    if (keyword == "FIELDS" || keyword == "COLUMNS") collect(field_names, fields_line);
    else if (keyword == "SIZE") collect(sizes, size_line);
    else if (keyword == "TYPE") collect(types, type_line);
    else if (keyword == "COUNT") collect(counts, count_line);
    else if (keyword == "WIDTH") { h.width = parse_count("WIDTH", at); width_line = at; }
    else if (keyword == "HEIGHT") { h.height = parse_count("HEIGHT", at); height_line = at; have_height = true; }
    else if (keyword == "POINTS") { h.points = parse_count("POINTS", at); points_line = at; have_points = true; }
    else if (keyword == "VIEWPOINT") {
      double v;
      if (tokens.size() != 8 || !std::all_of(tokens.begin() + 1, tokens.end(), [&](std::string_view s) { return parse_number(s, v); }))
        fail(at, "VIEWPOINT needs 7 numbers (tx ty tz qw qx qy qz)");
    } else if (keyword == "DATA") {
      if (tokens.size() != 2) fail(at, "DATA needs one value: ascii, binary or binary_compressed");
      h.data = lower(tokens[1]);
      if (h.data != "ascii" && h.data != "binary" && h.data != "binary_compressed")
        fail(at, fmt::format("unknown DATA '{}': expected ascii, binary or binary_compressed", shown(tokens[1])));
      h.data_line = at;
      h.data_offset = cursor.offset();
      break;
    } else {
      fail(at, fmt::format("unknown header entry '{}': expected VERSION, FIELDS, SIZE, TYPE, COUNT, WIDTH, HEIGHT, VIEWPOINT, POINTS or DATA",
                           shown(tokens[0])));
    }
  }

  const std::size_t data_line = h.data_line;
  if (fields_line == 0 || field_names.empty()) fail(data_line, "the header has no FIELDS before DATA");
  if (size_line == 0) fail(data_line, "the header has no SIZE before DATA");
  if (type_line == 0) fail(data_line, "the header has no TYPE before DATA");
  if (width_line == 0) fail(data_line, "the header has no WIDTH before DATA");
  const std::size_t n = field_names.size();
  if (sizes.size() != n) fail(size_line, fmt::format("SIZE has {} entries, FIELDS has {}", sizes.size(), n));
  if (types.size() != n) fail(type_line, fmt::format("TYPE has {} entries, FIELDS has {}", types.size(), n));
  if (count_line != 0 && counts.size() != n) fail(count_line, fmt::format("COUNT has {} entries, FIELDS has {}", counts.size(), n));

  for (std::size_t f = 0; f < n; ++f)
    for (std::size_t g = f + 1; g < n; ++g)
      if (field_names[f] == field_names[g] && field_names[f] != "_")
        fail(fields_line, fmt::format("field '{}' appears twice in FIELDS", field_names[f]));
  std::size_t offset = 0;
  for (std::size_t f = 0; f < n; ++f) {
    PcdField field;
    field.name = field_names[f];
    long long size = 0;
    if (!parse_number(sizes[f], size) || (size != 1 && size != 2 && size != 4 && size != 8))
      fail(size_line, fmt::format("SIZE of '{}' is '{}': expected 1, 2, 4 or 8", field.name, shown(sizes[f])));
    field.size = static_cast<int>(size);
    const std::string type = upper(types[f]);
    if (type != "I" && type != "U" && type != "F")
      fail(type_line, fmt::format("TYPE of '{}' is '{}': expected I, U or F", field.name, shown(types[f])));
    field.type = type[0];
    if (field.type == 'F' && field.size != 4 && field.size != 8)
      fail(size_line, fmt::format("SIZE of float field '{}' is {}: expected 4 or 8", field.name, field.size));
    if (count_line != 0) {
      long long count = 0;
      // The bound keeps the point size arithmetic far from overflow; real files use <= a few hundred.
      if (!parse_number(counts[f], count) || count < 1 || count > (1 << 20))
        fail(count_line, fmt::format("COUNT of '{}' is '{}': expected an integer from 1 to {}", field.name, shown(counts[f]), 1 << 20));
      field.count = static_cast<std::size_t>(count);
    }
    field.offset = offset;
    offset += field.count * static_cast<std::size_t>(field.size);
    h.values_per_point += field.count;
    h.fields.push_back(std::move(field));
  }
  h.point_size = offset;

  if (!have_height) h.height = 1;
  if (h.width != 0 && h.height > std::numeric_limits<std::size_t>::max() / h.width)
    fail(height_line, fmt::format("WIDTH {} times HEIGHT {} overflows", h.width, h.height));
  const std::size_t grid = h.width * h.height;
  if (!have_points) h.points = grid;
  else if (h.points != grid)
    fail(points_line, fmt::format("POINTS {} differs from WIDTH*HEIGHT = {}*{} = {}", h.points, h.width, h.height, grid));
  return h;
}

enum class Role : std::uint8_t { X, Y, Z, NX, NY, NZ, Rgb, Rgba, Field };

// One value of a point read from the file: which field/component, and where it goes.
struct PcdSlot {
  Role role;
  std::size_t field;      // index into PcdHeader::fields
  std::size_t component;  // 0 .. count-1
  std::size_t token;      // index among the values of an ascii line
  std::size_t out = 0;    // index into the output fields for Role::Field
};

struct Layout {
  std::vector<PcdSlot> slots;
  std::vector<ScalarField> fields;  // output fields, values filled while reading
  bool normals = false, colours = false, alpha = false;
  std::size_t alpha_out = 0;
};

Layout make_layout(const PcdHeader& h, const std::string& name) {
  Layout layout;
  auto find = [&](std::initializer_list<std::string_view> names) -> int {
    for (std::size_t f = 0; f < h.fields.size(); ++f)
      for (std::string_view n : names)
        if (h.fields[f].name == n && h.fields[f].count == 1) return static_cast<int>(f);
    return -1;
  };
  const int x = find({"x"}), y = find({"y"}), z = find({"z"});
  if (x < 0 || y < 0 || z < 0)
    throw InputError(fmt::format("{}: line {}: FIELDS has no x, y and z (single-count fields); cannot read positions", name, h.data_line));
  const int nx = find({"normal_x", "nx"}), ny = find({"normal_y", "ny"}), nz = find({"normal_z", "nz"});
  layout.normals = nx >= 0 && ny >= 0 && nz >= 0;
  int colour = -1;
  for (std::size_t f = 0; f < h.fields.size(); ++f) {
    const PcdField& field = h.fields[f];
    if ((field.name == "rgb" || field.name == "rgba") && field.size == 4 && field.count == 1) { colour = static_cast<int>(f); break; }
  }
  layout.colours = colour >= 0;

  std::vector<std::string> used;
  auto add_field = [&](std::string field_name, ScalarType type) {
    if (std::find(used.begin(), used.end(), field_name) != used.end())
      throw InputError(fmt::format("{}: line {}: field '{}' appears twice", name, h.data_line, field_name));
    used.push_back(field_name);
    layout.fields.push_back(ScalarField{std::move(field_name), type, {}});
    return layout.fields.size() - 1;
  };
  std::size_t token = 0;
  for (std::size_t f = 0; f < h.fields.size(); ++f) {
    const PcdField& field = h.fields[f];
    const int fi = static_cast<int>(f);
    auto slot = [&](Role role) { layout.slots.push_back(PcdSlot{role, f, 0, token, 0}); };
    if (fi == x) slot(Role::X);
    else if (fi == y) slot(Role::Y);
    else if (fi == z) slot(Role::Z);
    else if (layout.normals && fi == nx) slot(Role::NX);
    else if (layout.normals && fi == ny) slot(Role::NY);
    else if (layout.normals && fi == nz) slot(Role::NZ);
    else if (fi == colour) slot(field.name == "rgba" ? Role::Rgba : Role::Rgb);
    else if (field.name != "_") {
      const ScalarType type = scalar_type_of(field.type, field.size);
      for (std::size_t c = 0; c < field.count; ++c) {
        const std::size_t out = add_field(field.count == 1 ? field.name : fmt::format("{}_{}", field.name, c), type);
        layout.slots.push_back(PcdSlot{Role::Field, f, c, token + c, out});
      }
    }
    token += field.count;
  }
  if (colour >= 0 && h.fields[static_cast<std::size_t>(colour)].name == "rgba" &&
      std::find(used.begin(), used.end(), "alpha") == used.end()) {
    layout.alpha = true;
    layout.alpha_out = add_field("alpha", ScalarType::UInt8);
  }
  return layout;
}

// Accumulates points; drops NaN points of organized clouds.
class PointSink {
public:
  PointSink(Layout& layout, PointCloud& cloud, bool organized, std::size_t reserve)
      : layout_(layout), cloud_(cloud), organized_(organized) {
    cloud_.positions.reserve(reserve);
    if (layout_.normals) cloud_.normals.reserve(reserve);
    if (layout_.colours) cloud_.colors.reserve(reserve);
    for (ScalarField& f : layout_.fields) f.values.reserve(reserve);
    values_.resize(layout_.slots.size());
  }
  // Per slot value of the current point; colour bits go in `bits`.
  double& value(std::size_t slot) { return values_[slot]; }
  std::uint32_t bits = 0;

  void push() {
    Vector3d p = Vector3d::Zero(), n = Vector3d::Zero();
    for (std::size_t s = 0; s < layout_.slots.size(); ++s) {
      const double v = values_[s];
      switch (layout_.slots[s].role) {
        case Role::X: p.x() = v; break;
        case Role::Y: p.y() = v; break;
        case Role::Z: p.z() = v; break;
        case Role::NX: n.x() = v; break;
        case Role::NY: n.y() = v; break;
        case Role::NZ: n.z() = v; break;
        default: break;
      }
    }
    if (organized_ && (std::isnan(p.x()) || std::isnan(p.y()) || std::isnan(p.z()))) {
      ++dropped;
      return;
    }
    cloud_.positions.push_back(p);
    if (layout_.normals) cloud_.normals.push_back(n);
    if (layout_.colours)
      cloud_.colors.emplace_back(static_cast<float>((bits >> 16) & 0xFF) / 255.0f, static_cast<float>((bits >> 8) & 0xFF) / 255.0f,
                                 static_cast<float>(bits & 0xFF) / 255.0f);
    if (layout_.alpha) layout_.fields[layout_.alpha_out].values.push_back(static_cast<double>(bits >> 24));
    for (std::size_t s = 0; s < layout_.slots.size(); ++s)
      if (layout_.slots[s].role == Role::Field) layout_.fields[layout_.slots[s].out].values.push_back(values_[s]);
  }

  std::size_t dropped = 0;

private:
  Layout& layout_;
  PointCloud& cloud_;
  bool organized_;
  std::vector<double> values_;
};

// Colour bits from an ascii token: PCL writes rgb as the integer of its 32 bits; older files
// hold the float whose bits they are (e.g. "4.2108e+06").
bool parse_colour_token(std::string_view token, std::uint32_t& bits) {
  long long i = 0;
  if (parse_number(token, i)) {
    if (i < 0 || i > 0xFFFFFFFFLL) return false;
    bits = static_cast<std::uint32_t>(i);
    return true;
  }
  double d = 0;
  if (!parse_number(token, d)) return false;
  const float f = static_cast<float>(d);
  std::memcpy(&bits, &f, sizeof(bits));
  return true;
}

// Returns the number of non-blank lines after the last point (ignored).
std::size_t read_ascii(std::string_view bytes, const PcdHeader& h, const Layout& layout, PointSink& sink, const std::string& name) {
  TextCursor cursor(bytes.substr(h.data_offset));
  std::string_view line;
  std::vector<std::string_view> tokens;
  std::size_t read = 0;
  std::size_t extra = 0;
  while (cursor.next_line(line)) {
    const std::string_view t = trim(line);
    if (t.empty()) continue;
    const std::size_t at = h.data_line + cursor.line_number();
    if (read == h.points) { ++extra; continue; }
    split_tokens(t, tokens);
    if (tokens.size() != h.values_per_point)
      throw InputError(fmt::format("{}: line {}: point {}: expected {} values, got {}", name, at, read, h.values_per_point, tokens.size()));
    for (std::size_t s = 0; s < layout.slots.size(); ++s) {
      const PcdSlot& slot = layout.slots[s];
      const std::string_view token = tokens[slot.token];
      const bool ok = slot.role == Role::Rgb || slot.role == Role::Rgba ? parse_colour_token(token, sink.bits)
                                                                        : parse_number(token, sink.value(s));
      if (!ok)
        throw InputError(fmt::format("{}: line {}, value {} ({}): '{}' is not a number", name, at, slot.token + 1,
                                     h.fields[slot.field].name, shown(token)));
      // A value declared F4 is a float whatever digits the text has, as in binary data.
      const PcdField& field = h.fields[slot.field];
      if (field.type == 'F' && field.size == 4) sink.value(s) = static_cast<double>(static_cast<float>(sink.value(s)));
    }
    sink.push();
    ++read;
  }
  if (read < h.points)
    throw InputError(fmt::format("{}: line {}: point {}: expected {} points (POINTS), file ends after {}", name,
                                 h.data_line + cursor.line_number() + 1, read, h.points, read));
  return extra;
}

// Reads `points` points from `data`: row-major (binary) or column-major (decompressed).
void read_binary(const char* data, const PcdHeader& h, const Layout& layout, PointSink& sink, bool column_major) {
  struct Access { std::size_t base, stride, size; char type; };
  std::vector<Access> access;
  for (const PcdSlot& slot : layout.slots) {
    const PcdField& f = h.fields[slot.field];
    const std::size_t size = static_cast<std::size_t>(f.size);
    if (column_major) access.push_back({h.points * f.offset + slot.component * size, f.count * size, size, f.type});
    else access.push_back({f.offset + slot.component * size, h.point_size, size, f.type});
  }
  for (std::size_t i = 0; i < h.points; ++i) {
    for (std::size_t s = 0; s < layout.slots.size(); ++s) {
      const Access& a = access[s];
      const char* p = data + a.base + i * a.stride;
      if (layout.slots[s].role == Role::Rgb || layout.slots[s].role == Role::Rgba) sink.bits = load_value<std::uint32_t>(p);
      else sink.value(s) = load_scalar(p, a.type, static_cast<int>(a.size));
    }
    sink.push();
  }
}

}  // namespace

RawData read_pcd(const std::filesystem::path& path, const ReadOptions&) {
  const std::string name = display_name(path);
  const FileBytes file_bytes(path);
  const std::string_view bytes = file_bytes.view();
  const PcdHeader h = parse_pcd_header(bytes, name);
  Layout layout = make_layout(h, name);

  RawData raw;
  raw.encoding = h.data;
  const bool organized = h.height > 1;
  const std::size_t available = bytes.size() - h.data_offset;

  if (h.data == "ascii") {
    // Each value takes at least two bytes (a digit and a separator), which bounds the reservation.
    PointSink sink(layout, raw.cloud, organized, std::min(h.points, available / (2 * h.values_per_point) + 1));
    const std::size_t extra = read_ascii(bytes, h, layout, sink, name);
    raw.dropped_nonfinite = sink.dropped;
    if (extra > 0) raw.warnings.push_back(fmt::format("{}: {} lines after the {} points (POINTS) ignored", name, extra, h.points));
  } else if (h.data == "binary") {
    if (h.points > available / h.point_size)
      throw InputError(fmt::format("{}: byte {}: binary data: header says {} points of {} bytes but only {} bytes follow (file truncated?)",
                                   name, h.data_offset, h.points, h.point_size, available));
    PointSink sink(layout, raw.cloud, organized, h.points);
    read_binary(bytes.data() + h.data_offset, h, layout, sink, false);
    raw.dropped_nonfinite = sink.dropped;
  } else {
    if (available < 8)
      throw InputError(fmt::format("{}: byte {}: binary_compressed data: expected the 8-byte sizes block, file ends", name, h.data_offset));
    const auto compressed = load_value<std::uint32_t>(bytes.data() + h.data_offset);
    const auto uncompressed = load_value<std::uint32_t>(bytes.data() + h.data_offset + 4);
    if (compressed > available - 8)
      throw InputError(fmt::format("{}: byte {}: binary_compressed data: block of {} bytes but only {} bytes follow (file truncated?)", name,
                                   h.data_offset + 8, compressed, available - 8));
    if (h.points > std::numeric_limits<std::uint32_t>::max() / h.point_size || h.points * h.point_size != uncompressed)
      throw InputError(fmt::format("{}: byte {}: binary_compressed data: uncompressed size {} differs from POINTS {} times {} bytes per point",
                                   name, h.data_offset + 4, uncompressed, h.points, h.point_size));
    // LZF expands at most about 90-fold, so a larger claim is corrupt; checked before allocating.
    if (uncompressed / 128 > compressed)
      throw InputError(fmt::format("{}: byte {}: binary_compressed data: {} compressed bytes cannot expand to {} bytes", name,
                                   h.data_offset, compressed, uncompressed));
    std::vector<char> plain(uncompressed);
    if (uncompressed > 0) {
      const unsigned got = lzf_decompress(bytes.data() + h.data_offset + 8, compressed, plain.data(), uncompressed);
      if (got != uncompressed)
        throw InputError(fmt::format("{}: byte {}: binary_compressed data: LZF decompression failed (got {} of {} bytes); the data is corrupt",
                                     name, h.data_offset + 8, got, uncompressed));
    }
    PointSink sink(layout, raw.cloud, organized, h.points);
    read_binary(plain.data(), h, layout, sink, true);
    raw.dropped_nonfinite = sink.dropped;
  }
  for (ScalarField& f : layout.fields) raw.cloud.fields.add(f.name, 0, f.type).values = std::move(f.values);
  if (organized)
    raw.warnings.push_back(fmt::format("{}: organized cloud {}x{} flattened; {} invalid (NaN) points dropped", name, h.width, h.height,
                                       raw.dropped_nonfinite));
  return raw;
}

namespace {

enum class Source : std::uint8_t { Position, Normal, Rgb, Field };

// Default positions are float32 when no coordinate moves by more than this share of the spacing.
constexpr double kFloatTolerance = 1e-4;

struct PcdColumn {
  std::string name;
  char type;
  int size;
  Source source;
  int component = 0;                 // 0..2 for positions and normals
  const ScalarField* field = nullptr;
};

char pcd_type_letter(ScalarType t) {
  if (scalar_type_is_float(t)) return 'F';
  switch (t) {
    case ScalarType::Int8: case ScalarType::Int16: case ScalarType::Int32: case ScalarType::Int64: return 'I';
    default: return 'U';
  }
}

std::uint32_t packed_rgb(const Vector3f& c) {
  auto byte = [](float v) { return static_cast<std::uint32_t>(std::lround(std::clamp(static_cast<double>(v), 0.0, 1.0) * 255.0)); };
  return (byte(c.x()) << 16) | (byte(c.y()) << 8) | byte(c.z());
}

double column_value(const PcdColumn& col, const PointCloud& cloud, std::size_t i) {
  switch (col.source) {
    case Source::Position: return cloud.positions[i][col.component];
    case Source::Normal: return cloud.normals[i][col.component];
    case Source::Field: return col.field->values[i];
    case Source::Rgb: break;
  }
  return 0.0;
}

void store(char* dst, const PcdColumn& col, const PointCloud& cloud, std::size_t i) {
  if (col.source == Source::Rgb) {
    const std::uint32_t bits = packed_rgb(cloud.colors[i]);
    std::memcpy(dst, &bits, 4);  // little-endian hosts only, like PCL itself
    return;
  }
  const double v = column_value(col, cloud, i);
  auto put = [&](auto x) { std::memcpy(dst, &x, sizeof(x)); };
  if (col.type == 'F') {
    if (col.size == 4) put(static_cast<float>(v));
    else put(v);
  } else if (col.type == 'I') {
    switch (col.size) {
      case 1: put(to_stored<std::int8_t>(v)); break;
      case 2: put(to_stored<std::int16_t>(v)); break;
      case 4: put(to_stored<std::int32_t>(v)); break;
      default: put(to_stored<std::int64_t>(v)); break;
    }
  } else {
    switch (col.size) {
      case 1: put(to_stored<std::uint8_t>(v)); break;
      case 2: put(to_stored<std::uint16_t>(v)); break;
      case 4: put(to_stored<std::uint32_t>(v)); break;
      default: put(to_stored<std::uint64_t>(v)); break;
    }
  }
}

void write_text_value(FileWriter& out, const PcdColumn& col, const PointCloud& cloud, std::size_t i, int precision) {
  char text[64];
  std::to_chars_result r{};
  if (col.source == Source::Rgb) {
    r = std::to_chars(text, text + sizeof(text), packed_rgb(cloud.colors[i]));
  } else {
    const double v = column_value(col, cloud, i);
    if (col.type == 'F' && col.size == 8) {
      out.write_double(v, precision);
      return;
    }
    if (col.type == 'F') r = std::to_chars(text, text + sizeof(text), static_cast<float>(v));
    else if (col.type == 'I') r = std::to_chars(text, text + sizeof(text), to_stored<std::int64_t>(v));
    else r = std::to_chars(text, text + sizeof(text), to_stored<std::uint64_t>(v));
  }
  out.write(text, static_cast<std::size_t>(r.ptr - text));
}

}  // namespace

void write_pcd(const std::filesystem::path& path, const PointCloud& cloud, const WriteOptions& options, std::vector<std::string>& notes) {
  const std::string name = display_name(path);
  const std::size_t n = cloud.size();

  bool single = options.single_precision;
  if (!single && !options.double_precision && n > 0) {
    // PCL's tools and Open3D 0.16 read F8 positions as zeros: float32 unless it would move a
    // point by more than 1e-4 of a spacing, estimated from the box (diagonal / sqrt(N), which
    // errs small for a surface sample) as io/ has no neighbour search.
    const double spacing = bounding_box(cloud.positions).diagonal() / std::sqrt(double(n));
    double worst = 0.0;
    for (const Vector3d& p : cloud.positions)
      for (int a = 0; a < 3; ++a) worst = std::max(worst, std::abs(double(float(p[a])) - p[a]));
    single = worst <= kFloatTolerance * spacing;
    if (!single)
      notes.push_back(fmt::format("{}: positions written as double (F8): float32 would move points by up to {:.3g}, more than {:g} of "
                                  "the spacing (about {:.3g}); PCL's tools and Open3D 0.16 read F8 positions as zeros, so for them "
                                  "move the cloud near the origin first",
                                  name, worst, kFloatTolerance, spacing));
  } else if (single && n > 0) {
    const BoundingBox box = bounding_box(cloud.positions);
    const double largest = std::max(box.min.cwiseAbs().maxCoeff(), box.max.cwiseAbs().maxCoeff());
    const float f = static_cast<float>(largest);
    const double step = static_cast<double>(std::nextafter(f, std::numeric_limits<float>::infinity())) - static_cast<double>(f);
    const double diagonal = box.diagonal();
    if (diagonal > 0 && step > 1e-5 * diagonal)
      throw UsageError(fmt::format("{}: single precision positions would step by {:g} at coordinate {:g}, more than 1e-5 of the "
                                   "bounding-box diagonal {:g}; write double precision (the default) or move the cloud near the origin",
                                   name, step, largest, diagonal));
  }

  std::vector<PcdColumn> columns;
  for (int k = 0; k < 3; ++k) columns.push_back({std::string(1, "xyz"[k]), 'F', single ? 4 : 8, Source::Position, k});
  if (cloud.has_normals())
    for (int k = 0; k < 3; ++k) columns.push_back({fmt::format("normal_{}", "xyz"[k]), 'F', 4, Source::Normal, k});
  // PCL's own writer declares rgb U in ascii files (the integer of the packed bits; a float
  // would not survive the text) and F in binary ones; its readers expect exactly that.
  if (cloud.has_colors()) columns.push_back({"rgb", options.ascii ? 'U' : 'F', 4, Source::Rgb});
  for (const ScalarField& f : cloud.fields) {
    const bool reserved = f.name == "_" || std::any_of(columns.begin(), columns.end(), [&](const PcdColumn& c) { return c.name == f.name; }) ||
                          f.name == "x" || f.name == "y" || f.name == "z" || f.name == "normal_x" || f.name == "normal_y" ||
                          f.name == "normal_z" || f.name == "nx" || f.name == "ny" || f.name == "nz" || f.name == "rgb" || f.name == "rgba";
    const bool bad_char = f.name.empty() || std::any_of(f.name.begin(), f.name.end(), [](char c) {
      return std::isspace(static_cast<unsigned char>(c)) || std::iscntrl(static_cast<unsigned char>(c));
    });
    if (reserved || bad_char)
      throw UsageError(fmt::format("{}: field '{}' cannot be written to PCD: {}; rename it", name, f.name,
                                   bad_char ? "PCD field names cannot be empty or hold spaces" : "the name is a PCD standard field"));
    columns.push_back({f.name, pcd_type_letter(f.type), scalar_type_size(f.type), Source::Field, 0, &f});
  }

  std::string fields_line = "FIELDS", size_line = "SIZE", type_line = "TYPE", count_line = "COUNT";
  std::size_t point_size = 0;
  for (const PcdColumn& c : columns) {
    fields_line += " " + c.name;
    size_line += fmt::format(" {}", c.size);
    type_line += fmt::format(" {}", c.type);
    count_line += " 1";
    point_size += static_cast<std::size_t>(c.size);
  }
  const std::string data = options.ascii ? "ascii" : options.pcd_compressed ? "binary_compressed" : "binary";

  // The compressed block stores its sizes as uint32 and liblzf takes unsigned lengths.
  if (data == "binary_compressed" && n > std::numeric_limits<std::uint32_t>::max() / 2 / point_size)
    throw UsageError(fmt::format("{}: {} points are too many for a binary_compressed PCD (2 GiB block limit); write binary PCD", name, n));

  FileWriter out(path);
  out.write(fmt::format("# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\n{}\n{}\n{}\n{}\nWIDTH {}\nHEIGHT 1\n"
                        "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS {}\nDATA {}\n",
                        fields_line, size_line, type_line, count_line, n, n, data));

  if (data == "ascii") {
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t c = 0; c < columns.size(); ++c) {
        if (c > 0) out.write(" ", 1);
        write_text_value(out, columns[c], cloud, i, options.precision);
      }
      out.write("\n", 1);
    }
  } else if (data == "binary") {
    std::vector<char> row(point_size);
    for (std::size_t i = 0; i < n; ++i) {
      char* p = row.data();
      for (const PcdColumn& c : columns) {
        store(p, c, cloud, i);
        p += c.size;
      }
      out.write(row.data(), row.size());
    }
  } else {
    // Column-major: all values of the first field, then the second, ... (PCL's layout, which
    // also compresses better).
    std::vector<char> plain(n * point_size);
    char* p = plain.data();
    for (const PcdColumn& c : columns)
      for (std::size_t i = 0; i < n; ++i, p += c.size) store(p, c, cloud, i);
    // Incompressible data grows by at most 1/32 plus a little; the margin avoids a retry.
    std::vector<char> packed(plain.size() + plain.size() / 16 + 64);
    unsigned compressed = 0;
    if (!plain.empty()) {
      compressed = lzf_compress(plain.data(), static_cast<unsigned>(plain.size()), packed.data(), static_cast<unsigned>(packed.size()));
      if (compressed == 0) throw Error(fmt::format("{}: LZF compression failed", name));
    }
    out.write_value<std::uint32_t>(compressed);
    out.write_value<std::uint32_t>(static_cast<std::uint32_t>(plain.size()));
    out.write(packed.data(), compressed);
  }
  out.close();
}

}  // namespace pointsurf::io::detail
