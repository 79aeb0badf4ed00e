// SPDX-License-Identifier: GPL-3.0-or-later
// LAS 1.0-1.4 header, VLRs and point records (formats 0-10, extra bytes of types 1-10), shared
// by the LAS and LAZ readers and writers, following the ASPRS LAS 1.4 R15 specification. All
// values are little endian.
#include "io/detail/las_format.h"

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include <fmt/format.h>

#include "io/detail/file_util.h"
#include "pointsurf/core/error.h"

namespace pointsurf::io::detail {
namespace {

// Byte offsets in the public header block.
constexpr std::size_t kVersionMajor = 24;
constexpr std::size_t kHeaderSize = 94;
constexpr std::size_t kOffsetToPoints = 96;
constexpr std::size_t kPointFormat = 104;
constexpr std::size_t kRecordLength = 105;
constexpr std::size_t kLegacyCount = 107;
constexpr std::size_t kScale = 131;
constexpr std::size_t kOffset = 155;
constexpr std::size_t kCount64 = 247;
constexpr std::size_t kHeaderSize12 = 227;  // LAS 1.0-1.2
constexpr std::size_t kHeaderSize14 = 375;

// Where the optional parts of a point record sit; -1 when the format lacks them.
struct PointLayout {
  std::size_t size = 0;  // bytes the format defines
  bool extended = false; // formats 6-10: 30-byte core, 4-bit returns, 8-bit classes
  int gps_time = -1;
  int rgb = -1;
  int nir = -1;
};

PointLayout point_layout(int format) {
  switch (format) {
    case 0: return {20, false, -1, -1, -1};
    case 1: return {28, false, 20, -1, -1};
    case 2: return {26, false, -1, 20, -1};
    case 3: return {34, false, 20, 28, -1};
    case 4: return {57, false, 20, -1, -1};  // format 1 + 29 bytes of wave packet
    case 5: return {63, false, 20, 28, -1};  // format 3 + wave packet
    case 6: return {30, true, 22, -1, -1};
    case 7: return {36, true, 22, 30, -1};
    case 8: return {38, true, 22, 30, 36};
    case 9: return {59, true, 22, -1, -1};   // format 6 + wave packet
    default: return {67, true, 22, 30, 36};  // 10: format 8 + wave packet
  }
}

// The extended formats store the scan angle in steps of 0.006 degrees.
constexpr double kScanAngleStepDeg = 0.006;

// LAS 1.4 extra bytes: a VLR "LASF_Spec" / 4 of 192-byte descriptors, one per value appended
// to each point record after the format's own bytes.
constexpr std::size_t kVlrHeaderSize = 54;
constexpr std::size_t kExtraBytesDescriptor = 192;
constexpr std::uint16_t kExtraBytesRecordId = 4;
constexpr std::size_t kExtraNameSize = 32;

// Extra bytes data types 1..10 (LAS 1.4 R15, table 24) are ScalarTypes in this order.
constexpr ScalarType kExtraTypes[] = {ScalarType::UInt8, ScalarType::Int8,  ScalarType::UInt16, ScalarType::Int16,   ScalarType::UInt32,
                                      ScalarType::Int32, ScalarType::UInt64, ScalarType::Int64, ScalarType::Float32, ScalarType::Float64};

int extra_bytes_code(ScalarType type) {
  for (int c = 0; c < 10; ++c)
    if (kExtraTypes[c] == type) return c + 1;
  return 10;
}

double load_extra(const char* p, ScalarType type) {
  switch (type) {
    case ScalarType::UInt8: return static_cast<unsigned char>(*p);
    case ScalarType::Int8: return static_cast<signed char>(*p);
    case ScalarType::UInt16: return load_value<std::uint16_t>(p);
    case ScalarType::Int16: return load_value<std::int16_t>(p);
    case ScalarType::UInt32: return load_value<std::uint32_t>(p);
    case ScalarType::Int32: return load_value<std::int32_t>(p);
    case ScalarType::UInt64: return static_cast<double>(load_value<std::uint64_t>(p));
    case ScalarType::Int64: return static_cast<double>(load_value<std::int64_t>(p));
    case ScalarType::Float32: return load_value<float>(p);
    case ScalarType::Float64: return load_value<double>(p);
  }
  return 0.0;
}

struct ExtraField {
  std::string name;
  ScalarType type = ScalarType::Float64;  // as stored
  std::size_t offset = 0;                 // bytes after the format's own record
  double scale = 1.0, shift = 0.0;        // applied when the descriptor's options say so
  bool scaled = false;
};

// The extra bytes descriptors of the VLRs between the header and the points; warnings for
// those skipped (undefined or array types).
std::vector<ExtraField> read_extra_bytes(std::string_view bytes, std::size_t header_size, std::size_t point_offset, std::uint32_t vlrs,
                                         std::size_t extra_room, const std::string& name, std::vector<std::string>& warnings) {
  std::vector<ExtraField> fields;
  std::size_t at = header_size;
  for (std::uint32_t v = 0; v < vlrs && at + kVlrHeaderSize <= point_offset; ++v) {
    const char* h = bytes.data() + at;
    const std::string_view user(h + 2, 16);
    const auto record_id = load_value<std::uint16_t>(h + 18);
    const std::size_t length = load_value<std::uint16_t>(h + 20);
    const std::size_t body = at + kVlrHeaderSize;
    if (body + length > point_offset) break;
    if (user.substr(0, user.find('\0')) == "LASF_Spec" && record_id == kExtraBytesRecordId) {
      std::size_t offset = 0;
      for (std::size_t d = 0; d + kExtraBytesDescriptor <= length; d += kExtraBytesDescriptor) {
        const char* e = bytes.data() + body + d;
        const int code = static_cast<unsigned char>(e[2]);
        const int options = static_cast<unsigned char>(e[3]);
        std::string field(e + 4, kExtraNameSize);
        field.resize(field.find('\0') == std::string::npos ? kExtraNameSize : field.find('\0'));
        if (code < 1 || code > 30) {
          // Undefined bytes (0: `options` is their count) and unknown types are skipped.
          const std::size_t size = code == 0 ? std::size_t(options) : 0;
          warnings.push_back(fmt::format("{}: extra bytes '{}' of data type {} skipped (only types 1-30 are read)", name, field, code));
          if (code != 0) return fields;  // the size is unknown here: later offsets would be wrong
          offset += size;
          continue;
        }
        // Types 11-20 and 21-30 are the (deprecated) 2- and 3-element arrays of types 1-10: one
        // field per element, named name_0, name_1, ...
        const int elements = (code - 1) / 10 + 1;
        for (int k = 0; k < elements; ++k) {
          ExtraField f;
          f.name = field.empty() ? fmt::format("extra_{}", fields.size()) : field;
          if (elements > 1) f.name += fmt::format("_{}", k);
          f.type = kExtraTypes[(code - 1) % 10];
          f.offset = offset;
          if (options & 0x08) f.scale = load_value<double>(e + 112 + 8 * k);  // bit 3: scale, bit 4: offset
          if (options & 0x10) f.shift = load_value<double>(e + 136 + 8 * k);
          f.scaled = (options & 0x18) != 0;
          offset += std::size_t(scalar_type_size(f.type));
          if (offset > extra_room) {
            warnings.push_back(fmt::format("{}: extra bytes '{}' lie beyond the {}-byte point record; skipped", name, f.name, extra_room));
            return fields;
          }
          fields.push_back(std::move(f));
        }
      }
    }
    at = body + length;
  }
  return fields;
}


// Values from a field, rounded and clamped to [lo, hi]; `fallback` when the field is absent or
// the value is not finite.
class FieldReader {
public:
  FieldReader(const PointCloud& cloud, std::string_view name, double fallback) : fallback_(fallback) {
    if (const ScalarField* f = cloud.fields.find(name)) values_ = &f->values;
  }
  double raw(std::size_t i) const {
    if (!values_) return fallback_;
    const double v = (*values_)[i];
    return std::isfinite(v) ? v : fallback_;
  }
  long long integer(std::size_t i, long long lo, long long hi) const {
    return static_cast<long long>(std::clamp(std::round(raw(i)), static_cast<double>(lo), static_cast<double>(hi)));
  }

private:
  const std::vector<double>* values_ = nullptr;
  double fallback_;
};

template <typename T>
void put(char* p, T value) {
  if constexpr (std::endian::native == std::endian::big) value = byteswap_value(value);
  std::memcpy(p, &value, sizeof(T));
}


void put_text(char* p, std::string_view text, std::size_t width) {
  std::memcpy(p, text.data(), std::min(text.size(), width));
}



// A point record slot: the field written there, its range (integers only unless `real`).
struct Slot {
  const char* name;
  double lo, hi;
  bool real;
};
constexpr Slot kSlots[] = {{"intensity", 0, 65535, false},      {"return_number", 0, 15, false},
                           {"number_of_returns", 0, 15, false}, {"classification", 0, 255, false},
                           {"user_data", 0, 255, false},        {"scan_angle", -32768 * kScanAngleStepDeg, 32767 * kScanAngleStepDeg, true},
                           {"point_source_id", 0, 65535, false}, {"gps_time", -1e300, 1e300, true}};

// Whether every value of `field` fits its slot (finite, in range, whole where the slot is).
bool fits_slot(const ScalarField& field, const Slot& slot) {
  return std::all_of(field.values.begin(), field.values.end(), [&](double v) {
    return std::isfinite(v) && v >= slot.lo && v <= slot.hi && (slot.real || v == std::round(v));
  });
}

// One value appended to each record as LAS 1.4 extra bytes.
struct ExtraOut {
  std::string name;
  ScalarType type;
  const std::vector<double>* values = nullptr;  // a field's, or null for a normal component
  int normal = -1;
};

// The extra bytes VLR describing `extras` (no_data, min, max, scale and offset unset).
std::string extra_bytes_vlr(const std::vector<ExtraOut>& extras) {
  std::string vlr(kVlrHeaderSize + kExtraBytesDescriptor * extras.size(), '\0');
  char* h = vlr.data();
  std::memcpy(h + 2, "LASF_Spec", 9);
  put<std::uint16_t>(h + 18, kExtraBytesRecordId);
  put<std::uint16_t>(h + 20, static_cast<std::uint16_t>(kExtraBytesDescriptor * extras.size()));
  std::memcpy(h + 22, "pointsurf fields", 16);
  for (std::size_t e = 0; e < extras.size(); ++e) {
    char* d = h + kVlrHeaderSize + kExtraBytesDescriptor * e;
    d[2] = static_cast<char>(extra_bytes_code(extras[e].type));
    std::memcpy(d + 4, extras[e].name.data(), extras[e].name.size());
  }
  return vlr;
}

void store_extra(char* p, ScalarType type, double v) {
  switch (type) {
    case ScalarType::UInt8: put(p, to_stored<std::uint8_t>(v)); break;
    case ScalarType::Int8: put(p, to_stored<std::int8_t>(v)); break;
    case ScalarType::UInt16: put(p, to_stored<std::uint16_t>(v)); break;
    case ScalarType::Int16: put(p, to_stored<std::int16_t>(v)); break;
    case ScalarType::UInt32: put(p, to_stored<std::uint32_t>(v)); break;
    case ScalarType::Int32: put(p, to_stored<std::int32_t>(v)); break;
    case ScalarType::UInt64: put(p, to_stored<std::uint64_t>(v)); break;
    case ScalarType::Int64: put(p, to_stored<std::int64_t>(v)); break;
    case ScalarType::Float32: put(p, static_cast<float>(v)); break;
    case ScalarType::Float64: put(p, v); break;
  }
}

}  // namespace

LasHeader parse_las_header(std::string_view bytes, std::uint64_t file_size, const std::string& name) {
  const char* data = bytes.data();
  if (bytes.size() < 4 || bytes.compare(0, 4, "LASF") != 0)
    throw InputError(fmt::format("{}: not a LAS file: expected the signature 'LASF' at byte 0", name));
  if (bytes.size() < kHeaderSize12)
    throw InputError(fmt::format("{}: header too short: the file has {} bytes, a LAS header needs at least {}", name, file_size, kHeaderSize12));
  LasHeader h;
  h.major = static_cast<unsigned char>(data[kVersionMajor]);
  h.minor = static_cast<unsigned char>(data[kVersionMajor + 1]);
  if (h.major != 1 || h.minor > 4)
    throw InputError(fmt::format("{}: unsupported LAS version {}.{}: expected 1.0 to 1.4", name, h.major, h.minor));

  h.header_size = load_value<std::uint16_t>(data + kHeaderSize);
  const std::size_t needed_header = h.minor >= 4 ? kHeaderSize14 : kHeaderSize12;
  if (h.header_size < needed_header)
    throw InputError(fmt::format("{}: header too short: header size field is {}, LAS {}.{} needs at least {}", name, h.header_size, h.major,
                                 h.minor, needed_header));
  if (h.header_size > file_size || h.header_size > bytes.size())
    throw InputError(fmt::format("{}: header size {} is larger than the file ({} bytes)", name, h.header_size, file_size));

  h.point_offset = load_value<std::uint32_t>(data + kOffsetToPoints);
  if (h.point_offset < h.header_size)
    throw InputError(fmt::format("{}: offset to point data {} lies inside the {}-byte header", name, h.point_offset, h.header_size));
  h.vlr_count = load_value<std::uint32_t>(data + 100);

  // Bits 7 and 6 flag LAZ compression; the low bits name the record format.
  const int format_byte = static_cast<unsigned char>(data[kPointFormat]);
  h.compressed = (format_byte & 0xC0) != 0;
  h.format = format_byte & 0x3F;
  if (h.format > 10) throw InputError(fmt::format("{}: point data record format {} is not supported: expected 0 to 10", name, h.format));
  const PointLayout layout = point_layout(h.format);
  h.record_length = load_value<std::uint16_t>(data + kRecordLength);
  if (h.record_length < layout.size)
    throw InputError(fmt::format("{}: point record length {} is shorter than the {} bytes point format {} needs", name, h.record_length,
                                 layout.size, h.format));

  // LAS 1.4 has a 64-bit count; the legacy 32-bit one must be 0 for formats 6-10 and for
  // files with more than 2^32 - 1 points, but some writers fill only the legacy field.
  h.count = load_value<std::uint32_t>(data + kLegacyCount);
  if (h.minor >= 4) {
    const auto count64 = load_value<std::uint64_t>(data + kCount64);
    if (count64 != 0) h.count = count64;
    h.evlr_start = load_value<std::uint64_t>(data + 235);
    h.evlr_count = load_value<std::uint32_t>(data + 243);
  }

  for (int a = 0; a < 3; ++a) {
    h.scale[a] = load_value<double>(data + kScale + 8 * a);
    h.offset[a] = load_value<double>(data + kOffset + 8 * a);
    if (!std::isfinite(h.scale[a]) || h.scale[a] == 0.0)
      throw InputError(fmt::format("{}: byte {}: {} scale factor is {}: expected a finite non-zero number", name, kScale + 8 * a,
                                   "xyz"[a], h.scale[a]));
    if (!std::isfinite(h.offset[a]))
      throw InputError(fmt::format("{}: byte {}: {} offset is {}: expected a finite number", name, kOffset + 8 * a, "xyz"[a], h.offset[a]));
  }
  return h;
}

std::vector<LasVlr> las_vlrs(std::string_view bytes, const LasHeader& header) {
  std::vector<LasVlr> vlrs;
  std::size_t at = header.header_size;
  const std::size_t end = std::min(bytes.size(), header.point_offset);
  for (std::uint32_t v = 0; v < header.vlr_count && at + kVlrHeaderSize <= end; ++v) {
    const char* h = bytes.data() + at;
    const std::string_view user(h + 2, 16);
    const std::size_t length = load_value<std::uint16_t>(h + 20);
    const std::size_t body = at + kVlrHeaderSize;
    if (body + length > end) break;
    vlrs.push_back({std::string(user.substr(0, user.find('\0'))), load_value<std::uint16_t>(h + 18), bytes.substr(body, length)});
    at = body + length;
  }
  return vlrs;
}

std::vector<LasVlr> las_evlrs(std::string_view tail, const LasHeader& header) {
  constexpr std::size_t kEvlrHeaderSize = 60;
  std::vector<LasVlr> vlrs;
  std::size_t at = 0;
  for (std::uint32_t v = 0; v < header.evlr_count && at + kEvlrHeaderSize <= tail.size(); ++v) {
    const char* h = tail.data() + at;
    const std::string_view user(h + 2, 16);
    const std::uint64_t length = load_value<std::uint64_t>(h + 20);
    const std::size_t body = at + kEvlrHeaderSize;
    if (length > tail.size() - body) break;
    vlrs.push_back({std::string(user.substr(0, user.find('\0'))), load_value<std::uint16_t>(h + 18), tail.substr(body, length)});
    at = body + static_cast<std::size_t>(length);
  }
  return vlrs;
}

std::string las_vlr(std::string_view user_id, std::uint16_t record_id, std::string_view description, std::string_view body) {
  std::string vlr(kVlrHeaderSize, '\0');
  char* h = vlr.data();
  std::memcpy(h + 2, user_id.data(), std::min<std::size_t>(user_id.size(), 16));
  put<std::uint16_t>(h + 18, record_id);
  put<std::uint16_t>(h + 20, static_cast<std::uint16_t>(body.size()));
  std::memcpy(h + 22, description.data(), std::min<std::size_t>(description.size(), 32));
  return vlr.append(body);
}

void read_las_crs(const std::vector<LasVlr>& vlrs, CoordinateSystem& crs) {
  auto bytes = [](std::string_view body) { return std::vector<std::uint8_t>(body.begin(), body.end()); };
  for (const LasVlr& v : vlrs) {
    if (v.user_id != kProjectionUserId) continue;
    if (v.record_id == kWktRecord) crs.wkt = std::string(v.body.substr(0, v.body.find('\0')));  // null-terminated
    else if (v.record_id == kGeoKeysRecord) crs.geokeys = bytes(v.body);
    else if (v.record_id == kGeoDoubleRecord) crs.geodouble = bytes(v.body);
    else if (v.record_id == kGeoAsciiRecord) crs.geoascii = bytes(v.body);
  }
}

std::string las_crs_vlrs(const CoordinateSystem& crs, int& count) {
  std::string out;
  auto add = [&](std::uint16_t record, std::string_view description, std::string_view body) {
    if (body.empty()) return;
    out += las_vlr(kProjectionUserId, record, description, body);
    ++count;
  };
  // The WKT VLR holds a null-terminated string (LAS 1.4 R15, 2.5.1).
  add(kWktRecord, "OGC coordinate system WKT", crs.wkt.empty() ? std::string_view() : std::string_view(crs.wkt.c_str(), crs.wkt.size() + 1));
  auto view = [](const std::vector<std::uint8_t>& b) { return std::string_view(reinterpret_cast<const char*>(b.data()), b.size()); };
  add(kGeoKeysRecord, "GeoTIFF GeoKeyDirectoryTag", view(crs.geokeys));
  add(kGeoDoubleRecord, "GeoTIFF GeoDoubleParamsTag", view(crs.geodouble));
  add(kGeoAsciiRecord, "GeoTIFF GeoAsciiParamsTag", view(crs.geoascii));
  return out;
}

struct LasRecordReader::State {
  std::string name;
  RawData* raw = nullptr;
  PointLayout layout;
  std::array<double, 3> scale{}, offset{};
  std::vector<double> intensity, return_number, number_of_returns, classification;
  std::vector<double> scan_angle, user_data, point_source_id, gps_time, nir;
  std::vector<std::array<std::uint16_t, 3>> rgb;
  std::vector<ExtraField> extras;
  std::vector<std::vector<double>> extra_values;
};

LasRecordReader::LasRecordReader(const LasHeader& header, std::string_view head_bytes, const std::string& name, RawData& raw)
    : s_(std::make_unique<State>()) {
  State& s = *s_;
  const std::size_t n = static_cast<std::size_t>(header.count);
  s.name = name;
  s.raw = &raw;
  s.layout = point_layout(header.format);
  s.scale = header.scale;
  s.offset = header.offset;
  raw.cloud.grid = {Vector3d(header.scale[0], header.scale[1], header.scale[2]), Vector3d(header.offset[0], header.offset[1], header.offset[2])};
  raw.cloud.positions.resize(n);
  for (auto* v : {&s.intensity, &s.return_number, &s.number_of_returns, &s.classification, &s.scan_angle, &s.user_data, &s.point_source_id})
    v->resize(n);
  if (s.layout.gps_time >= 0) s.gps_time.resize(n);
  if (s.layout.nir >= 0) s.nir.resize(n);
  if (s.layout.rgb >= 0) s.rgb.resize(n);
  s.extras = read_extra_bytes(head_bytes, header.header_size, std::min(head_bytes.size(), header.point_offset), header.vlr_count,
                              header.record_length - s.layout.size, name, raw.warnings);
  s.extra_values.assign(s.extras.size(), std::vector<double>(n));
  read_las_crs(las_vlrs(head_bytes, header), raw.cloud.crs);
}

LasRecordReader::~LasRecordReader() = default;

void LasRecordReader::read(std::size_t i, const char* record) {
  State& s = *s_;
  const PointLayout& layout = s.layout;
  for (std::size_t e = 0; e < s.extras.size(); ++e) {
    const ExtraField& f = s.extras[e];
    const double v = load_extra(record + layout.size + f.offset, f.type);
    s.extra_values[e][i] = f.scaled ? v * f.scale + f.shift : v;
  }
  const auto x = load_value<std::int32_t>(record);
  const auto y = load_value<std::int32_t>(record + 4);
  const auto z = load_value<std::int32_t>(record + 8);
  s.raw->cloud.positions[i] = Vector3d(x * s.scale[0] + s.offset[0], y * s.scale[1] + s.offset[1], z * s.scale[2] + s.offset[2]);
  s.intensity[i] = load_value<std::uint16_t>(record + 12);
  const auto returns = static_cast<unsigned char>(record[14]);
  if (layout.extended) {
    s.return_number[i] = returns & 0x0F;
    s.number_of_returns[i] = returns >> 4;
    s.classification[i] = static_cast<unsigned char>(record[16]);
    s.user_data[i] = static_cast<unsigned char>(record[17]);
    s.scan_angle[i] = load_value<std::int16_t>(record + 18) * kScanAngleStepDeg;
    s.point_source_id[i] = load_value<std::uint16_t>(record + 20);
  } else {
    s.return_number[i] = returns & 0x07;
    s.number_of_returns[i] = (returns >> 3) & 0x07;
    s.classification[i] = static_cast<unsigned char>(record[15]) & 0x1F;  // the top 3 bits are flags
    s.scan_angle[i] = static_cast<signed char>(record[16]);
    s.user_data[i] = static_cast<unsigned char>(record[17]);
    s.point_source_id[i] = load_value<std::uint16_t>(record + 18);
  }
  if (layout.gps_time >= 0) s.gps_time[i] = load_value<double>(record + layout.gps_time);
  if (layout.rgb >= 0)
    for (int c = 0; c < 3; ++c) s.rgb[i][c] = load_value<std::uint16_t>(record + layout.rgb + 2 * c);
  if (layout.nir >= 0) s.nir[i] = load_value<std::uint16_t>(record + layout.nir);
}

void LasRecordReader::finish() {
  State& s = *s_;
  RawData& raw = *s.raw;
  PointCloud& cloud = raw.cloud;
  const std::size_t n = cloud.positions.size();
  const std::vector<ExtraField>& extras = s.extras;
  const std::string& name = s.name;
  const PointLayout& layout = s.layout;
  auto &intensity = s.intensity, &return_number = s.return_number, &number_of_returns = s.number_of_returns,
       &classification = s.classification, &scan_angle = s.scan_angle, &user_data = s.user_data, &point_source_id = s.point_source_id,
       &gps_time = s.gps_time, &nir = s.nir;
  auto& extra_values = s.extra_values;
  const auto& rgb = s.rgb;

  // A slot every point leaves unset (zero; returns 1 of 1) says nothing: it becomes a field only
  // when some point has another value, so a cloud written and read back gains no fields. An
  // extra bytes field of the same name (a value the slot could not hold) takes its place.
  const auto named_extra = [&](std::string_view field) {
    return std::any_of(extras.begin(), extras.end(), [&](const ExtraField& e) { return e.name == field; });
  };
  auto add = [&](const char* field, std::vector<double>& values, ScalarType type, double unset) {
    if (named_extra(field) || std::all_of(values.begin(), values.end(), [&](double v) { return v == unset || v == 0.0; })) return;
    cloud.fields.add(field, 0, type).values = std::move(values);
  };
  add("intensity", intensity, ScalarType::UInt16, 0.0);
  // Return numbers go together: both when any point is not a single return.
  const bool single_returns = std::all_of(return_number.begin(), return_number.end(), [](double v) { return v <= 1.0; }) &&
                              std::all_of(number_of_returns.begin(), number_of_returns.end(), [](double v) { return v <= 1.0; });
  if (!single_returns) {
    add("return_number", return_number, ScalarType::UInt8, -1.0);
    add("number_of_returns", number_of_returns, ScalarType::UInt8, -1.0);
  }
  add("classification", classification, ScalarType::UInt8, 0.0);
  if (layout.gps_time >= 0) add("gps_time", gps_time, ScalarType::Float64, 0.0);
  add("scan_angle", scan_angle, ScalarType::Float32, 0.0);
  add("user_data", user_data, ScalarType::UInt8, 0.0);
  add("point_source_id", point_source_id, ScalarType::UInt16, 0.0);
  if (layout.nir >= 0) add("nir", nir, ScalarType::UInt16, 0.0);

  // Extra bytes nx, ny, nz are the normals (pointsurf writes them so); the rest keep their names.
  const auto find_extra = [&](std::string_view field) {
    return static_cast<std::size_t>(std::find_if(extras.begin(), extras.end(), [&](const ExtraField& e) { return e.name == field; }) - extras.begin());
  };
  const std::array<std::size_t, 3> normal_columns{find_extra("nx"), find_extra("ny"), find_extra("nz")};
  const bool has_normals = std::all_of(normal_columns.begin(), normal_columns.end(), [&](std::size_t c) { return c < extras.size(); });
  if (has_normals) {
    cloud.normals.resize(n);
    for (std::size_t i = 0; i < n; ++i)
      cloud.normals[i] = Vector3d(extra_values[normal_columns[0]][i], extra_values[normal_columns[1]][i], extra_values[normal_columns[2]][i]);
  }
  for (std::size_t e = 0; e < extras.size(); ++e) {
    if (has_normals && std::find(normal_columns.begin(), normal_columns.end(), e) != normal_columns.end()) continue;
    if (cloud.fields.contains(extras[e].name)) {
      raw.warnings.push_back(fmt::format("{}: extra bytes '{}' appear twice; the second is skipped", name, extras[e].name));
      continue;
    }
    cloud.fields.add(extras[e].name, 0, extras[e].scaled ? ScalarType::Float64 : extras[e].type).values = std::move(extra_values[e]);
  }

  if (layout.rgb >= 0) {
    // The standard says 16-bit colour, but many writers store 8-bit values unscaled; when no
    // channel exceeds 255 the data is taken as 8-bit.
    std::uint16_t max_channel = 0;
    for (const auto& c : rgb) max_channel = std::max({max_channel, c[0], c[1], c[2]});
    const float full = max_channel <= 255 ? 255.0f : 65535.0f;
    if (max_channel <= 255 && max_channel > 0) raw.warnings.push_back(fmt::format("{}: RGB values are 8-bit (none above 255); read as 0..255", name));
    cloud.colors.resize(n);
    for (std::size_t i = 0; i < n; ++i) cloud.colors[i] = Vector3f(rgb[i][0] / full, rgb[i][1] / full, rgb[i][2] / full);
  }
}

struct LasRecordWriter::State {
  const PointCloud* cloud = nullptr;
  bool colors = false;
  int format = 6;
  std::size_t core_length = 30, record_length = 30, extra_size = 0;
  std::vector<ExtraOut> extras;
  std::string vlr;  // the extra bytes VLR and the coordinate system VLRs, or empty
  int vlr_count = 0;
  std::array<double, 3> scale{}, offset{};
  std::string header;  // without the VLR counts and offsets
  std::vector<FieldReader> slots;  // in kSlots order
  std::int32_t quantise(std::size_t i, int a) const {
    return static_cast<std::int32_t>(std::llround((cloud->positions[i][a] - offset[a]) / scale[a]));
  }
};

// A point record's slots hold intensity, return_number, number_of_returns, classification,
// user_data, scan_angle (degrees), point_source_id and gps_time when every value fits the slot;
// the normals (as nx, ny, nz, float32) and every other field, or a standard one that does not
// fit, follow as LAS 1.4 extra bytes under their own name (at most 32 characters) and type, so
// the round trip keeps every field by name. Points without a return_number field are written
// as return 1 of 1.
LasRecordWriter::LasRecordWriter(const PointCloud& cloud, const WriteOptions& options, const std::string& name, std::vector<std::string>& notes)
    : s_(std::make_unique<State>()) {
  State& s = *s_;
  s.cloud = &cloud;
  const std::size_t n = cloud.size();
  std::vector<ExtraOut>& extras = s.extras;
  std::vector<std::string> in_slots;
  if (cloud.has_normals())
    for (int a = 0; a < 3; ++a) extras.push_back({std::string("n") + "xyz"[a], ScalarType::Float32, nullptr, a});
  for (const ScalarField& f : cloud.fields) {
    const auto slot = std::find_if(std::begin(kSlots), std::end(kSlots), [&](const Slot& sl) { return f.name == sl.name; });
    if (slot != std::end(kSlots) && fits_slot(f, *slot)) {
      in_slots.push_back(f.name);
      continue;
    }
    if (f.name.empty() || f.name.size() > kExtraNameSize || (cloud.has_normals() && (f.name == "nx" || f.name == "ny" || f.name == "nz")))
      throw UsageError(fmt::format("{}: field '{}' cannot be LAS extra bytes: {}; rename it", name, f.name,
                                   f.name.empty() ? "the name is empty"
                                   : f.name.size() > kExtraNameSize ? "names hold at most 32 characters"
                                                                    : "the normals are written as nx, ny, nz"));
    extras.push_back({f.name, f.type, &f.values});
  }
  for (const ExtraOut& e : extras) s.extra_size += std::size_t(scalar_type_size(e.type));
  for (std::size_t k = 0; k < std::size(kSlots); ++k) {
    const char* field = kSlots[k].name;
    const double fallback = k == 1 || k == 2 ? 1 : 0;  // return 1 of 1
    const bool used = std::find(in_slots.begin(), in_slots.end(), field) != in_slots.end();
    s.slots.emplace_back(cloud, used ? field : "", fallback);
  }
  for (std::size_t i = 0; i < n; ++i)
    if (!cloud.positions[i].allFinite())
      throw UsageError(fmt::format("{}: point {} has a non-finite coordinate; LAS stores integers and cannot hold it", name, i));

  const BoundingBox box = bounding_box(cloud.positions);
  const Vector3d lo = box.empty() ? Vector3d::Zero() : box.min;
  const Vector3d hi = box.empty() ? Vector3d::Zero() : box.max;

  std::array<double, 3>& scale = s.scale;
  std::array<double, 3>& offset = s.offset;
  constexpr double kIntMax = std::numeric_limits<std::int32_t>::max();
  // The source file's grid (a cloud read from LAS or LAZ), for what the options leave open, while
  // every point still fits it in 32 bits.
  const CoordinateGrid& grid = cloud.grid;
  bool keep_grid = !grid.empty() && !(options.las_scale && options.las_offset);
  for (int a = 0; a < 3 && keep_grid; ++a) {
    offset[a] = options.las_offset ? (*options.las_offset)[a] : grid.offset[a];
    scale[a] = options.las_scale ? *options.las_scale : grid.scale[a];
    const double reach = std::max(std::abs(hi[a] - offset[a]), std::abs(lo[a] - offset[a]));
    keep_grid = std::isfinite(offset[a]) && std::isfinite(scale[a]) && scale[a] > 0.0 && reach / scale[a] <= kIntMax - 1;
  }
  if (!grid.empty() && !keep_grid && !(options.las_scale && options.las_offset))
    notes.push_back(fmt::format("the points no longer fit the input's LAS grid (scale {} {} {}, offset {} {} {}) in 32 bits: written "
                                "with the default scale and offset",
                                grid.scale.x(), grid.scale.y(), grid.scale.z(), grid.offset.x(), grid.offset.y(), grid.offset.z()));
  for (int a = 0; a < 3 && !keep_grid; ++a) {
    // A round offset keeps the stored integers easy to read (truncated towards zero, so data
    // near the origin keeps offset 0); 1e-4 keeps 0.05 mm quantisation.
    offset[a] = options.las_offset ? (*options.las_offset)[a] : std::trunc(lo[a] / 1000.0) * 1000.0;
    if (!std::isfinite(offset[a])) throw UsageError(fmt::format("{}: LAS offset {} is not finite", name, "xyz"[a]));
    const double reach = std::max(std::abs(hi[a] - offset[a]), std::abs(lo[a] - offset[a]));
    if (options.las_scale) {
      scale[a] = *options.las_scale;
      if (!std::isfinite(scale[a]) || scale[a] <= 0.0)
        throw UsageError(fmt::format("{}: LAS scale {} must be a positive number", name, scale[a]));
      if (reach / scale[a] > kIntMax - 1)
        throw UsageError(fmt::format("{}: LAS scale {} with offset {} cannot hold {} = {} in 32 bits: use a scale of at least {:g}", name,
                                     scale[a], offset[a], "xyz"[a], std::abs(hi[a] - offset[a]) >= std::abs(lo[a] - offset[a]) ? hi[a] : lo[a],
                                     reach / (kIntMax - 1)));
    } else {
      scale[a] = 1e-4;
      while (reach / scale[a] > kIntMax - 1) scale[a] *= 10.0;
      // An offset given far from the data must not coarsen the default scale unsaid: the
      // offset the writer would choose keeps 1e-4 wherever the data's extent allows it.
      const double own_offset = std::trunc(lo[a] / 1000.0) * 1000.0;
      const double own_reach = std::max(std::abs(hi[a] - own_offset), std::abs(lo[a] - own_offset));
      if (options.las_offset && scale[a] > 1e-4 && own_reach / 1e-4 <= kIntMax - 1)
        throw UsageError(fmt::format("{}: LAS offset {} = {} is too far from the data ({} up to {}) for the default scale 1e-4: it "
                                     "would need {:g}; give that scale explicitly (--las-scale) or an offset near the data",
                                     name, "xyz"[a], offset[a], lo[a], hi[a], scale[a]));
    }
  }

  s.colors = cloud.has_colors();
  s.format = s.colors ? 7 : 6;
  s.core_length = point_layout(s.format).size;
  s.record_length = s.core_length + s.extra_size;
  if (s.record_length > 65535)
    throw UsageError(fmt::format("{}: {} extra bytes per point make a record longer than LAS's 65535 bytes", name, s.extra_size));
  s.vlr = extras.empty() ? std::string() : extra_bytes_vlr(extras);
  s.vlr_count = extras.empty() ? 0 : 1;
  // LAS 1.4 formats 6-10 name the CRS by WKT; GeoTIFF keys a source file carried are written too
  // (readers of 1.4 files ignore them, older tools still use them) so the round trip keeps them.
  s.vlr += las_crs_vlrs(cloud.crs, s.vlr_count);

  // The header comes first but holds the quantised bounds and the counts per return number:
  // one pass gathers them, a second streams the records.
  std::array<std::uint64_t, 15> by_return{};
  std::array<std::int32_t, 3> qmin{}, qmax{};
  qmin.fill(std::numeric_limits<std::int32_t>::max());
  qmax.fill(std::numeric_limits<std::int32_t>::min());
  for (std::size_t i = 0; i < n; ++i) {
    for (int a = 0; a < 3; ++a) {
      const std::int32_t q = s.quantise(i, a);
      qmin[a] = std::min(qmin[a], q);
      qmax[a] = std::max(qmax[a], q);
    }
    const long long ret = s.slots[1].integer(i, 0, 15);
    if (ret >= 1) ++by_return[static_cast<std::size_t>(ret - 1)];
  }

  s.header.assign(kHeaderSize14, '\0');
  char* h = s.header.data();
  put_text(h, "LASF", 4);
  // Bit 4 (WKT) must be set for formats 6-10 even without a coordinate system (LAS 1.4 R15);
  // PDAL refuses such files otherwise. Bit 0 stays clear: the GPS time type is unknown.
  put<std::uint16_t>(h + 6, 0x10);
  h[kVersionMajor] = 1;
  h[kVersionMajor + 1] = 4;
  put_text(h + 26, "OTHER", 32);
  put_text(h + 58, "pointsurf", 32);
  {
    using namespace std::chrono;
    const auto today = floor<days>(system_clock::now());
    const year_month_day ymd(today);
    const auto day_of_year = (today - sys_days(ymd.year() / January / 1)).count() + 1;
    put<std::uint16_t>(h + 90, static_cast<std::uint16_t>(day_of_year));
    put<std::uint16_t>(h + 92, static_cast<std::uint16_t>(static_cast<int>(ymd.year())));
  }
  put<std::uint16_t>(h + kHeaderSize, static_cast<std::uint16_t>(kHeaderSize14));
  h[kPointFormat] = static_cast<char>(s.format);
  put<std::uint16_t>(h + kRecordLength, static_cast<std::uint16_t>(s.record_length));
  // Legacy counts (bytes 107-130) stay 0: LAS 1.4 requires that for formats 6-10.
  for (int a = 0; a < 3; ++a) {
    put<double>(h + kScale + 8 * a, scale[a]);
    put<double>(h + kOffset + 8 * a, offset[a]);
    const double top = n ? qmax[a] * scale[a] + offset[a] : 0.0;
    const double bottom = n ? qmin[a] * scale[a] + offset[a] : 0.0;
    put<double>(h + 179 + 16 * a, top);
    put<double>(h + 187 + 16 * a, bottom);
  }
  // Bytes 227-246: waveform start, EVLR start and EVLR count, all 0.
  put<std::uint64_t>(h + kCount64, n);
  for (int r = 0; r < 15; ++r) put<std::uint64_t>(h + 255 + 8 * r, by_return[r]);
}

LasRecordWriter::~LasRecordWriter() = default;
int LasRecordWriter::format() const { return s_->format; }
std::size_t LasRecordWriter::record_length() const { return s_->record_length; }
std::size_t LasRecordWriter::extra_bytes() const { return s_->extra_size; }

std::string LasRecordWriter::head(const std::string& more_vlrs, int more_vlr_count, int format_bits) const {
  std::string out = s_->header;
  char* h = out.data();
  put<std::uint32_t>(h + kOffsetToPoints, static_cast<std::uint32_t>(kHeaderSize14 + s_->vlr.size() + more_vlrs.size()));
  put<std::uint32_t>(h + 100, static_cast<std::uint32_t>(s_->vlr_count + more_vlr_count));
  h[kPointFormat] = static_cast<char>(s_->format | format_bits);
  return out + s_->vlr + more_vlrs;
}

void LasRecordWriter::record(std::size_t i, char* r) const {
  const State& s = *s_;
  const auto& slot = s.slots;  // intensity, return_number, number_of_returns, classification, user_data, scan_angle, point_source_id, gps_time
  std::memset(r, 0, s.core_length);
  for (int a = 0; a < 3; ++a) put<std::int32_t>(r + 4 * a, s.quantise(i, a));
  put<std::uint16_t>(r + 12, static_cast<std::uint16_t>(slot[0].integer(i, 0, 65535)));
  const auto ret = static_cast<unsigned>(slot[1].integer(i, 0, 15));
  const auto rets = static_cast<unsigned>(slot[2].integer(i, 0, 15));
  r[14] = static_cast<char>(ret | (rets << 4));
  r[15] = 0;  // classification flags, scanner channel, scan direction, edge of flight line
  r[16] = static_cast<char>(slot[3].integer(i, 0, 255));
  r[17] = static_cast<char>(slot[4].integer(i, 0, 255));
  const double angle = std::round(slot[5].raw(i) / kScanAngleStepDeg);
  put<std::int16_t>(r + 18, static_cast<std::int16_t>(std::clamp(angle, -32768.0, 32767.0)));
  put<std::uint16_t>(r + 20, static_cast<std::uint16_t>(slot[6].integer(i, 0, 65535)));
  const PointLayout layout = point_layout(s.format);
  if (layout.gps_time >= 0) put<double>(r + layout.gps_time, slot[7].raw(i));
  if (s.colors)
    for (int c = 0; c < 3; ++c)
      put<std::uint16_t>(r + layout.rgb + 2 * c,
                         static_cast<std::uint16_t>(std::lround(std::clamp(s.cloud->colors[i][c], 0.0f, 1.0f) * 65535.0f)));
  char* extra = r + s.core_length;
  for (const ExtraOut& e : s.extras) {
    store_extra(extra, e.type, e.values ? (*e.values)[i] : s.cloud->normals[i][e.normal]);
    extra += scalar_type_size(e.type);
  }
}

}  // namespace pointsurf::io::detail
