// SPDX-License-Identifier: GPL-3.0-or-later
// PLY (Stanford polygon format) writer: ascii, binary little endian and binary big endian, each
// property encoded through an encoder chosen once from its type and the byte order (the reader:
// ply_read.cpp).
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

// ---- Encoding -------------------------------------------------------------------------------

using Encoder = char* (*)(double, char*);

template <typename T, bool Big>
char* encode(double v, char* out) {
  T value = to_stored<T>(v);
  if (Big != (std::endian::native == std::endian::big)) value = byteswap_value(value);
  std::memcpy(out, &value, sizeof(T));
  return out + sizeof(T);
}

template <typename T>
char* encode_text(double v, char* out) {
  // 32 bytes holds any shortest double, float or 64-bit integer.
  std::to_chars_result r;
  if constexpr (std::is_floating_point_v<T>) r = std::to_chars(out, out + 32, static_cast<T>(v));
  else r = std::to_chars(out, out + 32, to_stored<T>(v));
  return r.ptr;
}

template <int Precision>
char* encode_text_precision(double v, char* out) {
  return std::to_chars(out, out + 32, v, std::chars_format::general, Precision).ptr;
}

// Stored type of a field in PLY: 64-bit integers have no PLY type, so they go as double.
ScalarType ply_type(ScalarType type) {
  return (type == ScalarType::Int64 || type == ScalarType::UInt64) ? ScalarType::Float64 : type;
}

template <bool Big>
Encoder binary_encoder(ScalarType type) {
  switch (type) {
    case ScalarType::Int8: return &encode<std::int8_t, Big>;
    case ScalarType::UInt8: return &encode<std::uint8_t, Big>;
    case ScalarType::Int16: return &encode<std::int16_t, Big>;
    case ScalarType::UInt16: return &encode<std::uint16_t, Big>;
    case ScalarType::Int32: return &encode<std::int32_t, Big>;
    case ScalarType::UInt32: return &encode<std::uint32_t, Big>;
    case ScalarType::Float32: return &encode<float, Big>;
    default: return &encode<double, Big>;
  }
}

Encoder text_encoder(ScalarType type) {
  switch (type) {
    case ScalarType::Int8: return &encode_text<std::int8_t>;
    case ScalarType::UInt8: return &encode_text<std::uint8_t>;
    case ScalarType::Int16: return &encode_text<std::int16_t>;
    case ScalarType::UInt16: return &encode_text<std::uint16_t>;
    case ScalarType::Int32: return &encode_text<std::int32_t>;
    case ScalarType::UInt32: return &encode_text<std::uint32_t>;
    case ScalarType::Float32: return &encode_text<float>;
    default: return &encode_text<double>;
  }
}

Encoder text_encoder_with_precision(int precision) {
  switch (std::clamp(precision, 1, 16)) {
    case 1: return &encode_text_precision<1>;
    case 2: return &encode_text_precision<2>;
    case 3: return &encode_text_precision<3>;
    case 4: return &encode_text_precision<4>;
    case 5: return &encode_text_precision<5>;
    case 6: return &encode_text_precision<6>;
    case 7: return &encode_text_precision<7>;
    case 8: return &encode_text_precision<8>;
    case 9: return &encode_text_precision<9>;
    case 10: return &encode_text_precision<10>;
    case 11: return &encode_text_precision<11>;
    case 12: return &encode_text_precision<12>;
    case 13: return &encode_text_precision<13>;
    case 14: return &encode_text_precision<14>;
    case 15: return &encode_text_precision<15>;
    default: return &encode_text_precision<16>;
  }
}

// One vertex property to write: its source array and how to encode it.
struct OutColumn {
  std::string name;
  ScalarType type;
  const double* d = nullptr;
  const float* f = nullptr;
  std::size_t stride = 1;
  double scale = 1.0;
  Encoder encode = nullptr;

  double value(std::size_t i) const { return d ? d[i * stride] : std::clamp(static_cast<double>(f[i * stride]), 0.0, 1.0) * scale; }
};

// Refuses float32 positions when they would lose more than 1e-5 of the cloud's extent.
void check_single_precision(const std::string& file, const PointCloud& cloud) {
  double largest = 0;
  BoundingBox box;
  for (const Vector3d& p : cloud.positions) {
    if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z())) continue;
    largest = std::max(largest, p.cwiseAbs().maxCoeff());
    box.extend(p);
  }
  const double diagonal = box.diagonal();
  if (largest == 0 || diagonal == 0) return;
  if (largest >= static_cast<double>(std::numeric_limits<float>::max()))
    throw UsageError(fmt::format("{}: single precision: coordinate {:g} does not fit in float32; write double", file, largest));
  // Spacing of float32 values at `largest`: 2^(exponent - 23).
  const double step = std::ldexp(1.0, std::ilogb(largest) - 23);
  if (step > 1e-5 * diagonal)
    throw UsageError(fmt::format("{}: single precision refused: float32 steps are {:g} at {:g}, coarser than 1e-5 of the bounding-box "
                                 "diagonal {:g}; write double (drop single precision)",
                                 file, step, largest, diagonal));
}

void check_field_name(const std::string& file, const std::string& name, const char* what) {
  if (name.empty() || name.find_first_of(" \t\r\n") != std::string::npos)
    throw UsageError(fmt::format("{}: {} name '{}' cannot be written to PLY: names must be non-empty without spaces", file, what, name));
}

}  // namespace

void write_ply(const std::filesystem::path& path, const PointCloud& cloud, const std::vector<Triangle>& triangles,
               const FieldSet& face_fields, const WriteOptions& options) {
  const std::string file = display_name(path);
  const Encoding encoding = options.ascii ? Encoding::Ascii
                            : options.ply_encoding == PlyEncoding::Ascii          ? Encoding::Ascii
                            : options.ply_encoding == PlyEncoding::BinaryBigEndian ? Encoding::BinaryBigEndian
                                                                                   : Encoding::BinaryLittleEndian;
  if (options.single_precision) check_single_precision(file, cloud);
  const std::size_t n = cloud.size();

  std::vector<OutColumn> columns;
  const ScalarType position_type = options.single_precision ? ScalarType::Float32 : ScalarType::Float64;
  const double* pos = n ? cloud.positions.front().data() : nullptr;
  for (int a = 0; a < 3; ++a) columns.push_back(OutColumn{std::string(1, "xyz"[a]), position_type, pos ? pos + a : nullptr, nullptr, 3});
  if (cloud.has_normals()) {
    const double* base = cloud.normals.front().data();
    for (int a = 0; a < 3; ++a) columns.push_back(OutColumn{std::string("n") + "xyz"[a], position_type, base + a, nullptr, 3});
  }
  if (cloud.has_colors()) {
    const float* base = cloud.colors.front().data();
    const char* names[3] = {"red", "green", "blue"};
    for (int a = 0; a < 3; ++a) columns.push_back(OutColumn{names[a], ScalarType::UInt8, nullptr, base + a, 3, 255.0});
  }
  for (const ScalarField& field : cloud.fields) {
    check_field_name(file, field.name, "field");
    for (const OutColumn& c : columns)
      if (c.name == field.name)
        throw UsageError(fmt::format("{}: field '{}' clashes with the PLY property of the same name; rename the field", file, field.name));
    columns.push_back(OutColumn{field.name, ply_type(field.type), field.values.empty() ? nullptr : field.values.data(), nullptr, 1});
  }
  // Face fields follow the corner list of each face (none without faces).
  std::vector<OutColumn> face_columns;
  if (!triangles.empty())
    for (const ScalarField& field : face_fields) {
      check_field_name(file, field.name, "face field");
      if (field.name == "vertex_indices")
        throw UsageError(fmt::format("{}: face field 'vertex_indices' clashes with the PLY corner list; rename the field", file));
      if (field.values.size() != triangles.size())
        throw UsageError(fmt::format("{}: face field '{}' has {} values for {} faces", file, field.name, field.values.size(), triangles.size()));
      face_columns.push_back(OutColumn{field.name, ply_type(field.type), field.values.data(), nullptr, 1});
    }
  const Encoder precise_text = options.precision < 17 ? text_encoder_with_precision(options.precision) : nullptr;
  auto set_encoder = [&](OutColumn& col, bool position) {
    switch (encoding) {
      case Encoding::Ascii: col.encode = (position && precise_text) ? precise_text : text_encoder(col.type); break;
      case Encoding::BinaryLittleEndian: col.encode = binary_encoder<false>(col.type); break;
      case Encoding::BinaryBigEndian: col.encode = binary_encoder<true>(col.type); break;
    }
  };
  for (std::size_t c = 0; c < columns.size(); ++c) set_encoder(columns[c], c < 3);
  for (OutColumn& col : face_columns) set_encoder(col, false);

  FileWriter out(path);
  std::string header = fmt::format("ply\nformat {} 1.0\ncomment written by pointsurf\nelement vertex {}\n", encoding_name(encoding), n);
  for (const OutColumn& c : columns) header += fmt::format("property {} {}\n", scalar_type_ply_name(c.type), c.name);
  if (!triangles.empty()) {
    header += fmt::format("element face {}\nproperty list uchar int vertex_indices\n", triangles.size());
    for (const OutColumn& c : face_columns) header += fmt::format("property {} {}\n", scalar_type_ply_name(c.type), c.name);
  }
  header += "end_header\n";
  out.write(header);

  // Records are assembled in a chunk buffer and handed to the writer in large pieces.
  const bool text = encoding == Encoding::Ascii;
  const std::size_t max_record = (columns.size() + face_columns.size() + 4) * (text ? 33 : 8) + 1;
  std::vector<char> chunk(std::max<std::size_t>(1 << 16, 2 * max_record));
  char* p = chunk.data();
  char* const flush_at = chunk.data() + chunk.size() - max_record;
  for (std::size_t i = 0; i < n; ++i) {
    if (text) {
      for (std::size_t c = 0; c < columns.size(); ++c) {
        if (c) *p++ = ' ';
        p = columns[c].encode(columns[c].value(i), p);
      }
      *p++ = '\n';
    } else {
      for (const OutColumn& c : columns) p = c.encode(c.value(i), p);
    }
    if (p >= flush_at) { out.write(chunk.data(), static_cast<std::size_t>(p - chunk.data())); p = chunk.data(); }
  }
  const bool big = encoding == Encoding::BinaryBigEndian;
  for (std::size_t f = 0; f < triangles.size(); ++f) {
    const Triangle& t = triangles[f];
    if (text) {
      *p++ = '3';
      for (int k = 0; k < 3; ++k) {
        *p++ = ' ';
        p = std::to_chars(p, p + 16, t[k]).ptr;
      }
      for (const OutColumn& c : face_columns) {
        *p++ = ' ';
        p = c.encode(c.value(f), p);
      }
      *p++ = '\n';
    } else {
      *p++ = 3;
      for (int k = 0; k < 3; ++k) {
        std::int32_t v = t[k];
        if (big != (std::endian::native == std::endian::big)) v = byteswap_value(v);
        std::memcpy(p, &v, 4);
        p += 4;
      }
      for (const OutColumn& c : face_columns) p = c.encode(c.value(f), p);
    }
    if (p >= flush_at) { out.write(chunk.data(), static_cast<std::size_t>(p - chunk.data())); p = chunk.data(); }
  }
  out.write(chunk.data(), static_cast<std::size_t>(p - chunk.data()));
  out.close();
}

}  // namespace pointsurf::io::detail
