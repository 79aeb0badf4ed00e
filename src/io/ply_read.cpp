// SPDX-License-Identifier: GPL-3.0-or-later
// PLY (Stanford polygon format) reader: ascii, binary little endian and binary big endian (the
// writer: ply_write.cpp).
//
// Reading keeps the whole file in memory and decodes each vertex property through a decoder
// chosen once from its type and byte order, so the per-value work is one indirect call and a
// store; records of fixed size are addressed directly by index. Every count in the header is
// checked against the bytes left in the file before anything is allocated for it.
#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>

#include "io/detail/file_util.h"
#include "io/detail/formats.h"
#include "io/detail/ply_format.h"
#include "pointsurf/core/error.h"

namespace pointsurf::io::detail {
namespace {

using ply::Encoding;
using ply::encoding_name;

std::optional<ScalarType> parse_type(std::string_view name) {
  static constexpr std::array<std::pair<std::string_view, ScalarType>, 20> names{{
      {"char", ScalarType::Int8},      {"int8", ScalarType::Int8},       {"uchar", ScalarType::UInt8},
      {"uint8", ScalarType::UInt8},    {"short", ScalarType::Int16},     {"int16", ScalarType::Int16},
      {"ushort", ScalarType::UInt16},  {"uint16", ScalarType::UInt16},   {"int", ScalarType::Int32},
      {"int32", ScalarType::Int32},    {"uint", ScalarType::UInt32},     {"uint32", ScalarType::UInt32},
      {"float", ScalarType::Float32},  {"float32", ScalarType::Float32}, {"double", ScalarType::Float64},
      {"float64", ScalarType::Float64}, {"int64", ScalarType::Int64},    {"uint64", ScalarType::UInt64},
      {"long", ScalarType::Int64},     {"ulong", ScalarType::UInt64},
  }};
  for (const auto& [n, t] : names)
    if (n == name) return t;
  return std::nullopt;
}

struct Property {
  std::string name;
  ScalarType type = ScalarType::Float64;  // the value type (the item type of a list)
  bool is_list = false;
  ScalarType count_type = ScalarType::UInt8;
};

struct Element {
  std::string name;
  std::uint64_t count = 0;
  std::vector<Property> properties;
  std::size_t line = 0;  // header line that declared it

  bool has_lists() const {
    return std::any_of(properties.begin(), properties.end(), [](const Property& p) { return p.is_list; });
  }
  // Bytes of the smallest possible binary record: scalars plus list counts with no items.
  std::size_t min_binary_size() const {
    std::size_t size = 0;
    for (const Property& p : properties) size += static_cast<std::size_t>(scalar_type_size(p.is_list ? p.count_type : p.type));
    return size;
  }
  // Values on the shortest possible ascii line (list counts included).
  std::size_t min_ascii_values() const { return properties.size(); }
};

struct Header {
  Encoding encoding = Encoding::Ascii;
  std::vector<Element> elements;
  std::size_t body_offset = 0;
  std::size_t lines = 0;  // header lines, so the body's line numbers continue from them
};

Header parse_header(std::string_view bytes, const std::string& file) {
  TextCursor cursor(bytes);
  std::string_view line;
  std::vector<std::string_view> tokens;
  if (!cursor.next_line(line) || line.substr(0, line.find_last_not_of(" \t") + 1) != "ply")
    throw InputError(fmt::format("{}: line 1: expected 'ply', the PLY magic word", file));
  Header header;
  bool have_format = false;
  bool ended = false;
  while (cursor.next_line(line)) {
    const std::size_t n = cursor.line_number();
    split_tokens(line, tokens);
    if (tokens.empty()) continue;
    const std::string_view key = tokens[0];
    if (key == "comment" || key == "obj_info") continue;
    if (key == "end_header") { ended = true; break; }
    if (key == "format") {
      if (tokens.size() != 3)
        throw InputError(fmt::format("{}: line {}: expected 'format <ascii|binary_little_endian|binary_big_endian> 1.0'", file, n));
      if (tokens[1] == "ascii") header.encoding = Encoding::Ascii;
      else if (tokens[1] == "binary_little_endian") header.encoding = Encoding::BinaryLittleEndian;
      else if (tokens[1] == "binary_big_endian") header.encoding = Encoding::BinaryBigEndian;
      else
        throw InputError(fmt::format("{}: line {}: unknown PLY encoding '{}': expected ascii, binary_little_endian or binary_big_endian",
                                     file, n, tokens[1]));
      double version = 0;
      if (!parse_number(tokens[2], version) || version < 1.0 || version >= 2.0)
        throw InputError(fmt::format("{}: line {}: unsupported PLY version '{}': expected 1.0", file, n, tokens[2]));
      have_format = true;
    } else if (key == "element") {
      long long count = -1;
      if (tokens.size() != 3 || !parse_number(tokens[2], count) || count < 0)
        throw InputError(fmt::format("{}: line {}: expected 'element <name> <count>' with a count >= 0", file, n));
      header.elements.push_back(Element{std::string(tokens[1]), static_cast<std::uint64_t>(count), {}, n});
    } else if (key == "property") {
      if (header.elements.empty())
        throw InputError(fmt::format("{}: line {}: property before any element", file, n));
      Property p;
      std::string_view type_name;
      if (tokens.size() >= 2 && tokens[1] == "list") {
        if (tokens.size() != 5)
          throw InputError(fmt::format("{}: line {}: expected 'property list <count type> <item type> <name>'", file, n));
        const auto count_type = parse_type(tokens[2]);
        if (!count_type)
          throw InputError(fmt::format("{}: line {}: unknown property type '{}': expected char, uchar, short, ushort, int, uint, "
                                       "float, double or int8 ... float64",
                                       file, n, tokens[2]));
        if (scalar_type_is_float(*count_type))
          throw InputError(fmt::format("{}: line {}: list count type '{}' is not an integer type", file, n, tokens[2]));
        p.is_list = true;
        p.count_type = *count_type;
        type_name = tokens[3];
        p.name = std::string(tokens[4]);
      } else {
        if (tokens.size() != 3) throw InputError(fmt::format("{}: line {}: expected 'property <type> <name>'", file, n));
        type_name = tokens[1];
        p.name = std::string(tokens[2]);
      }
      const auto type = parse_type(type_name);
      if (!type)
        throw InputError(fmt::format("{}: line {}: unknown property type '{}': expected char, uchar, short, ushort, int, uint, float, "
                                     "double or int8 ... float64",
                                     file, n, type_name));
      p.type = *type;
      for (const Property& other : header.elements.back().properties)
        if (other.name == p.name)
          throw InputError(fmt::format("{}: line {}: property '{}' declared twice in element '{}'", file, n, p.name,
                                       header.elements.back().name));
      header.elements.back().properties.push_back(std::move(p));
    } else {
      throw InputError(fmt::format("{}: line {}: unknown header keyword '{}': expected format, comment, obj_info, element, property "
                                   "or end_header",
                                   file, n, key));
    }
  }
  if (!ended) throw InputError(fmt::format("{}: the header has no end_header line (file ends after line {})", file, cursor.line_number()));
  if (!have_format) throw InputError(fmt::format("{}: the header has no 'format' line", file));
  header.body_offset = cursor.offset();
  header.lines = cursor.line_number();
  return header;
}

// ---- Decoding -------------------------------------------------------------------------------

using Decoder = double (*)(const char*);

template <typename T, bool Big>
double decode(const char* p) {
  return static_cast<double>(load_value<T>(p, Big));
}

template <bool Big>
Decoder decoder_for(ScalarType type) {
  switch (type) {
    case ScalarType::Int8: return &decode<std::int8_t, Big>;
    case ScalarType::UInt8: return &decode<std::uint8_t, Big>;
    case ScalarType::Int16: return &decode<std::int16_t, Big>;
    case ScalarType::UInt16: return &decode<std::uint16_t, Big>;
    case ScalarType::Int32: return &decode<std::int32_t, Big>;
    case ScalarType::UInt32: return &decode<std::uint32_t, Big>;
    case ScalarType::Int64: return &decode<std::int64_t, Big>;
    case ScalarType::UInt64: return &decode<std::uint64_t, Big>;
    case ScalarType::Float32: return &decode<float, Big>;
    case ScalarType::Float64: return &decode<double, Big>;
  }
  return &decode<double, Big>;
}

Decoder decoder_for(ScalarType type, bool big) { return big ? decoder_for<true>(type) : decoder_for<false>(type); }

// Where one vertex property goes: a double array (positions, normals, fields) or a float
// array (colours, divided into [0, 1]), with a stride in elements.
struct Sink {
  double* d = nullptr;
  float* f = nullptr;
  std::size_t stride = 1;
  float divisor = 1.0f;

  void store(std::size_t i, double v) const {
    if (d) d[i * stride] = v;
    else if (f) f[i * stride] = static_cast<float>(v) / divisor;
  }
};

// 8-bit colours are v / 255, 16-bit v / 65535; float colours are already in [0, 1].
float colour_divisor(ScalarType type) {
  if (type == ScalarType::UInt16) return 65535.0f;
  if (scalar_type_is_float(type)) return 1.0f;
  return 255.0f;
}

[[noreturn]] void bad_list_count(const std::string& file, const std::string& where, std::string_view count, bool negative) {
  throw InputError(fmt::format("{}: {}: list count {} is {}: expected an integer >= 0", file, where, count,
                               negative ? "negative" : "not an integer"));
}

class Reader {
public:
  Reader(std::string_view bytes, Header header, const std::string& file)
      : bytes_(bytes), header_(std::move(header)), file_(file), big_(header_.encoding == Encoding::BinaryBigEndian) {}

  RawData read() {
    raw_.encoding = std::string(encoding_name(header_.encoding));
    const Element* vertex = nullptr;
    for (const Element& e : header_.elements)
      if (e.name == "vertex") { vertex = &e; break; }
    if (!vertex) throw InputError(fmt::format("{}: the header has no 'element vertex'", file_));
    for (const char* axis : {"x", "y", "z"})
      if (std::none_of(vertex->properties.begin(), vertex->properties.end(), [&](const Property& p) { return p.name == axis && !p.is_list; }))
        throw InputError(fmt::format("{}: line {}: element vertex has no property '{}': expected x, y and z", file_, vertex->line, axis));
    pos_ = header_.body_offset;
    line_ = header_.lines;
    cursor_.emplace(bytes_.substr(header_.body_offset));
    check_counts_fit();
    bool seen_face = false;
    for (const Element& e : header_.elements) {
      if (&e == vertex) {
        read_vertices(e);
      } else if (e.name == "face" && !seen_face && face_list_index(e) >= 0) {
        seen_face = true;
        read_faces(e);
      } else {
        // PCL's PLY writer always declares "element face 0" with no properties for a point
        // cloud; an empty face element loses nothing, so it earns no warning.
        if (e.name == "face" && !seen_face && e.count > 0)
          raw_.warnings.push_back(fmt::format("element face has no vertex_indices list; {} faces skipped", e.count));
        skip_element(e);
      }
    }
    return std::move(raw_);
  }

private:
  bool ascii() const { return header_.encoding == Encoding::Ascii; }

  // Refuses, before any allocation, element counts that need more bytes than the file holds.
  void check_counts_fit() {
    const std::size_t size = bytes_.size();
    std::size_t pos = header_.body_offset;
    for (const Element& e : header_.elements) {
      const std::size_t left = size - pos;
      if (ascii()) {
        // An ascii record takes at least one line end, and two bytes (digit and separator) per value.
        const std::size_t min_bytes = std::max<std::size_t>(1, 2 * e.min_ascii_values());
        if (e.count > left / min_bytes) {
          // The body is too short; a pass that stores nothing finds the line where it goes
          // wrong, which says more than the byte count.
          for (const Element& other : header_.elements) read_ascii_element(other, [](std::size_t, std::size_t, double) {}, nullptr);
          throw InputError(fmt::format("{}: the header declares {} {} elements of at least {} values each, but the ascii body has "
                                       "only {} bytes left (file ends at byte {})",
                                       file_, e.count, e.name, e.min_ascii_values(), left, size));
        }
        pos += static_cast<std::size_t>(e.count) * min_bytes;
      } else {
        const std::size_t min_bytes = e.min_binary_size();
        if (min_bytes == 0) continue;
        if (e.count > left / min_bytes) {
          const std::uint64_t index = left / min_bytes;
          throw InputError(fmt::format("{}: {} {} of {}: file ends at byte {}, expected {}{} bytes", file_, e.name, index, e.count, size,
                                       e.has_lists() ? "at least " : "", min_bytes));
        }
        pos += static_cast<std::size_t>(e.count) * min_bytes;
      }
    }
  }

  static int face_list_index(const Element& e) {
    for (std::size_t i = 0; i < e.properties.size(); ++i)
      if (e.properties[i].is_list && (e.properties[i].name == "vertex_indices" || e.properties[i].name == "vertex_index"))
        return static_cast<int>(i);
    return -1;
  }

  // ---- vertices ----

  std::vector<Sink> vertex_sinks(const Element& e) {
    const std::size_t n = static_cast<std::size_t>(e.count);
    PointCloud& cloud = raw_.cloud;
    cloud.positions.resize(n);
    auto find = [&](std::string_view name) -> int {
      for (std::size_t i = 0; i < e.properties.size(); ++i)
        if (e.properties[i].name == name && !e.properties[i].is_list) return static_cast<int>(i);
      return -1;
    };
    std::vector<Sink> sinks(e.properties.size());
    std::vector<bool> used(e.properties.size(), false);
    double* pos = cloud.positions.empty() ? nullptr : cloud.positions.front().data();
    const char* axes[3] = {"x", "y", "z"};
    for (int a = 0; a < 3; ++a) {
      const int i = find(axes[a]);
      sinks[i] = Sink{pos ? pos + a : nullptr, nullptr, 3, 1.0f};
      used[i] = true;
    }
    const int nx = find("nx"), ny = find("ny"), nz = find("nz");
    if (nx >= 0 && ny >= 0 && nz >= 0) {
      cloud.normals.assign(n, Vector3d::Zero());
      double* base = cloud.normals.empty() ? nullptr : cloud.normals.front().data();
      const int idx[3] = {nx, ny, nz};
      for (int a = 0; a < 3; ++a) { sinks[idx[a]] = Sink{base ? base + a : nullptr, nullptr, 3, 1.0f}; used[idx[a]] = true; }
    }
    for (const char* prefix : {"", "diffuse_"}) {
      const int r = find(std::string(prefix) + "red"), g = find(std::string(prefix) + "green"), b = find(std::string(prefix) + "blue");
      if (r < 0 || g < 0 || b < 0 || used[r] || used[g] || used[b] || cloud.has_colors()) continue;
      cloud.colors.assign(n, Vector3f::Zero());
      float* base = cloud.colors.empty() ? nullptr : cloud.colors.front().data();
      const int idx[3] = {r, g, b};
      for (int a = 0; a < 3; ++a) {
        sinks[idx[a]] = Sink{nullptr, base ? base + a : nullptr, 3, colour_divisor(e.properties[idx[a]].type)};
        used[idx[a]] = true;
      }
    }
    // Every other scalar property is a named field that keeps its type.
    std::vector<std::size_t> field_props;
    for (std::size_t i = 0; i < e.properties.size(); ++i)
      if (!used[i] && !e.properties[i].is_list) {
        cloud.fields.add(e.properties[i].name, n, e.properties[i].type);
        field_props.push_back(i);
      }
    // Pointers taken after every field exists: adding a field may move the others.
    for (std::size_t i : field_props) {
      ScalarField* field = cloud.fields.find(e.properties[i].name);
      sinks[i] = Sink{field->values.empty() ? nullptr : field->values.data(), nullptr, 1, 1.0f};
    }
    return sinks;
  }

  void read_vertices(const Element& e) {
    std::vector<Sink> sinks = vertex_sinks(e);
    if (ascii()) {
      read_ascii_element(e, [&](std::size_t i, std::size_t p, double v) { sinks[p].store(i, v); }, nullptr);
      return;
    }
    if (!e.has_lists()) {
      // Fixed-size records: each property at a known offset; the counts check guaranteed the bytes.
      struct Column {
        std::size_t offset;
        Decoder decode;
        Sink sink;
      };
      std::vector<Column> columns;
      std::size_t offset = 0;
      for (std::size_t p = 0; p < e.properties.size(); ++p) {
        columns.push_back(Column{offset, decoder_for(e.properties[p].type, big_), sinks[p]});
        offset += static_cast<std::size_t>(scalar_type_size(e.properties[p].type));
      }
      const std::size_t record = offset;
      const char* base = bytes_.data() + pos_;
      const std::size_t n = static_cast<std::size_t>(e.count);
      if (record > 0 && n > (bytes_.size() - pos_) / record) truncated(e, (bytes_.size() - pos_) / record, record);
      // The common layout (x y z as little-endian doubles or floats at the front) gets a
      // loop without indirect calls for the positions.
      const bool le = !big_;
      std::size_t first = 0;
      if (le && std::endian::native == std::endian::little && columns.size() >= 3 && e.properties[0].name == "x" &&
          e.properties[1].name == "y" && e.properties[2].name == "z" && e.properties[0].type == e.properties[1].type &&
          e.properties[1].type == e.properties[2].type &&
          (e.properties[0].type == ScalarType::Float64 || e.properties[0].type == ScalarType::Float32)) {
        Vector3d* out = raw_.cloud.positions.data();
        if (e.properties[0].type == ScalarType::Float64) {
          for (std::size_t i = 0; i < n; ++i) std::memcpy(out[i].data(), base + i * record, 3 * sizeof(double));
        } else {
          for (std::size_t i = 0; i < n; ++i) {
            float xyz[3];
            std::memcpy(xyz, base + i * record, sizeof(xyz));
            out[i] = Vector3d(xyz[0], xyz[1], xyz[2]);
          }
        }
        first = 3;
      }
      for (std::size_t i = 0; i < n; ++i) {
        const char* rec = base + i * record;
        for (std::size_t c = first; c < columns.size(); ++c) columns[c].sink.store(i, columns[c].decode(rec + columns[c].offset));
      }
      pos_ += n * record;
      return;
    }
    read_binary_element(e, [&](std::size_t i, std::size_t p, double v) { sinks[p].store(i, v); }, nullptr);
  }

  // ---- faces ----

  void read_faces(const Element& e) {
    const int list = face_list_index(e);
    const std::size_t n = static_cast<std::size_t>(e.count);
    raw_.triangles.reserve(n);
    std::vector<int> corners;
    bool started = false;
    auto finish_face = [&]() {
      if (!started) return;
      if (raw_.polygons.empty() && corners.size() == 3) {
        raw_.triangles.emplace_back(corners[0], corners[1], corners[2]);
      } else {
        if (raw_.polygons.empty()) {
          // First face that is not a triangle: keep every face as a polygon from here on so
          // that the face order is preserved.
          raw_.polygons.reserve(n);
          for (const Triangle& t : raw_.triangles) raw_.polygons.push_back({t[0], t[1], t[2]});
          raw_.triangles.clear();
          raw_.triangles.shrink_to_fit();
        }
        raw_.polygons.push_back(corners);
      }
    };
    auto on_count = [&](std::size_t) {
      finish_face();
      started = true;
      corners.clear();
    };
    auto on_item = [&](std::size_t face, double v) {
      if (!(v >= INT_MIN && v <= INT_MAX) || v != std::floor(v))
        throw InputError(fmt::format("{}: face {}: vertex index {} is not an integer index", file_, face, v));
      corners.push_back(static_cast<int>(v));
    };
    ListHandler handler{static_cast<std::size_t>(list), on_count, on_item};
    // Every scalar face property is a face field that keeps its type (other lists are skipped).
    std::vector<double*> sinks(e.properties.size(), nullptr);
    for (const Property& p : e.properties)
      if (!p.is_list) raw_.face_fields.add(p.name, n, p.type);
    for (std::size_t p = 0; p < e.properties.size(); ++p)
      if (!e.properties[p].is_list) sinks[p] = raw_.face_fields.find(e.properties[p].name)->values.data();
    auto on_scalar = [&](std::size_t i, std::size_t p, double v) {
      if (sinks[p]) sinks[p][i] = v;
    };
    if (ascii()) read_ascii_element(e, on_scalar, &handler);
    else read_binary_element(e, on_scalar, &handler);
    finish_face();
  }

  void skip_element(const Element& e) {
    auto ignore = [](std::size_t, std::size_t, double) {};
    if (ascii()) read_ascii_element(e, ignore, nullptr);
    else if (!e.has_lists()) {
      const std::size_t record = e.min_binary_size();
      const std::size_t n = static_cast<std::size_t>(e.count);
      if (record > 0 && n > (bytes_.size() - pos_) / record) truncated(e, (bytes_.size() - pos_) / record, record);
      pos_ += n * record;
    } else {
      read_binary_element(e, ignore, nullptr);
    }
  }

  // ---- generic record walkers ----

  // Receives the items of one list property (the face corners).
  struct ListHandler {
    std::size_t property;
    std::function<void(std::size_t)> on_count;         // element index; called before its items
    std::function<void(std::size_t, double)> on_item;  // element index, value
  };

  [[noreturn]] void truncated(const Element& e, std::uint64_t index, std::size_t need) const {
    throw InputError(fmt::format("{}: {} {} of {}: file ends at byte {}, expected {} bytes", file_, e.name, index, e.count, bytes_.size(), need));
  }

  template <typename OnScalar>
  void read_binary_element(const Element& e, OnScalar&& on_scalar, const ListHandler* list) {
    std::vector<Decoder> decoders, count_decoders;
    for (const Property& p : e.properties) {
      decoders.push_back(decoder_for(p.type, big_));
      count_decoders.push_back(decoder_for(p.count_type, big_));
    }
    const std::size_t n = static_cast<std::size_t>(e.count);
    const std::size_t size = bytes_.size();
    for (std::size_t i = 0; i < n; ++i) {
      for (std::size_t p = 0; p < e.properties.size(); ++p) {
        const Property& prop = e.properties[p];
        if (!prop.is_list) {
          const std::size_t s = static_cast<std::size_t>(scalar_type_size(prop.type));
          if (size - pos_ < s) truncated(e, i, s);
          on_scalar(i, p, decoders[p](bytes_.data() + pos_));
          pos_ += s;
          continue;
        }
        const std::size_t cs = static_cast<std::size_t>(scalar_type_size(prop.count_type));
        if (size - pos_ < cs) truncated(e, i, cs);
        const double count = count_decoders[p](bytes_.data() + pos_);
        pos_ += cs;
        if (count < 0)
          bad_list_count(file_, fmt::format("{} {}, property '{}'", e.name, i, prop.name), fmt::format("{}", static_cast<long long>(count)), true);
        const std::size_t is = static_cast<std::size_t>(scalar_type_size(prop.type));
        const std::size_t left = size - pos_;
        if (count > static_cast<double>(left / is))
          throw InputError(fmt::format("{}: {} {} of {}: list '{}' of {} items needs {} bytes, file ends at byte {}", file_, e.name, i, e.count,
                                       prop.name, static_cast<std::uint64_t>(count), static_cast<std::uint64_t>(count) * is, size));
        const std::size_t items = static_cast<std::size_t>(count);
        if (list && list->property == p) {
          list->on_count(i);
          for (std::size_t k = 0; k < items; ++k) list->on_item(i, decoders[p](bytes_.data() + pos_ + k * is));
        }
        pos_ += items * is;
      }
    }
  }

  template <typename OnScalar>
  void read_ascii_element(const Element& e, OnScalar&& on_scalar, const ListHandler* list) {
    const std::size_t n = static_cast<std::size_t>(e.count);
    std::string_view line;
    for (std::size_t i = 0; i < n; ++i) {
      // Blank lines carry no record; a record is one line.
      do {
        if (!cursor_->next_line(line))
          throw InputError(fmt::format("{}: {} {} of {}: file ends after line {}, expected {} values", file_, e.name, i, e.count,
                                       line_ + cursor_->line_number(), e.min_ascii_values()));
      } while (!e.properties.empty() && line.find_first_not_of(" \t\v\f") == std::string_view::npos);
      const std::size_t line_no = line_ + cursor_->line_number();
      split_tokens(line, tokens_);
      std::size_t t = 0;
      std::size_t expected = e.properties.size();
      auto value = [&](std::size_t p) {
        double v = 0;
        if (!parse_number(tokens_[t], v))
          throw InputError(fmt::format("{}: line {} ({} {}): '{}' is not a number (property '{}')", file_, line_no, e.name, i, tokens_[t],
                                       e.properties[p].name));
        ++t;
        return v;
      };
      auto need = [&](std::size_t more) {
        if (tokens_.size() - t < more)
          throw InputError(fmt::format("{}: line {} ({} {}): expected {} values, got {}", file_, line_no, e.name, i, expected, tokens_.size()));
      };
      for (std::size_t p = 0; p < e.properties.size(); ++p) {
        const Property& prop = e.properties[p];
        need(1);
        const double v = value(p);
        if (!prop.is_list) {
          on_scalar(i, p, v);
          continue;
        }
        if (v < 0 || v != std::floor(v))
          bad_list_count(file_, fmt::format("line {} ({} {}), property '{}'", line_no, e.name, i, prop.name), tokens_[t - 1], v < 0);
        if (v > static_cast<double>(tokens_.size() - t))
          throw InputError(fmt::format("{}: line {} ({} {}): list '{}' has count {} but only {} values follow it on the line", file_, line_no,
                                       e.name, i, prop.name, tokens_[t - 1], tokens_.size() - t));
        const std::size_t items = static_cast<std::size_t>(v);
        expected += items;
        const bool wanted = list && list->property == p;
        if (wanted) list->on_count(i);
        for (std::size_t k = 0; k < items; ++k) {
          const double item = value(p);
          if (wanted) list->on_item(i, item);
        }
      }
      if (t != tokens_.size())
        throw InputError(fmt::format("{}: line {} ({} {}): expected {} values, got {}", file_, line_no, e.name, i, expected, tokens_.size()));
    }
  }

  std::string_view bytes_;
  Header header_;
  const std::string& file_;
  bool big_;
  RawData raw_;
  std::size_t pos_ = 0;   // binary: offset of the next record
  std::size_t line_ = 0;  // ascii: header lines before the body
  std::optional<TextCursor> cursor_;
  std::vector<std::string_view> tokens_;
};

}  // namespace

RawData read_ply(const std::filesystem::path& path, const ReadOptions&) {
  const std::string file = display_name(path);
  const FileBytes bytes(path);
  Header header = parse_header(bytes.view(), file);
  Reader reader(bytes.view(), std::move(header), file);
  return reader.read();
}

}  // namespace pointsurf::io::detail
