// SPDX-License-Identifier: GPL-3.0-or-later
// LAS 1.0-1.4 reader (point data record formats 0-10, extra bytes of types 1-10) and LAS 1.4
// writer (format 6, or 7 with colours, plus extra bytes for normals and other fields), following
// the ASPRS LAS 1.4 R15 specification. The header, VLRs and records are in las_format.cpp.
#include <vector>

#include <fmt/format.h>

#include "io/detail/file_util.h"
#include "io/detail/formats.h"
#include "io/detail/las_format.h"
#include "pointsurf/core/error.h"

namespace pointsurf::io::detail {

RawData read_las(const std::filesystem::path& path, const ReadOptions&) {
  const std::string name = display_name(path);
  const FileBytes file_bytes(path);
  const std::string_view bytes = file_bytes.view();
  const std::size_t file_size = bytes.size();
  const LasHeader header = parse_las_header(bytes, file_size, name);

  // Check the announced points against the file size before allocating anything for them.
  const std::size_t available = header.point_offset <= file_size ? file_size - header.point_offset : 0;
  if (header.count > available / header.record_length)
    throw InputError(fmt::format("{}: point {} of {}: file ends at byte {} (records of {} bytes from byte {})", name,
                                 available / header.record_length, header.count, file_size, header.record_length, header.point_offset));
  const std::size_t n = static_cast<std::size_t>(header.count);

  RawData raw;
  raw.encoding = fmt::format("LAS {}.{} point format {}", header.major, header.minor, header.format);
  LasRecordReader records(header, bytes, name, raw);
  if (header.evlr_count > 0 && header.evlr_start >= header.point_offset && header.evlr_start < file_size)
    read_las_crs(las_evlrs(bytes.substr(header.evlr_start), header), raw.cloud.crs);
  const char* record = bytes.data() + header.point_offset;
  for (std::size_t i = 0; i < n; ++i, record += header.record_length) records.read(i, record);
  records.finish();
  return raw;
}

void write_las(const std::filesystem::path& path, const PointCloud& cloud, const WriteOptions& options, std::vector<std::string>& notes) {
  const LasRecordWriter writer(cloud, options, display_name(path), notes);
  FileWriter out(path);
  out.write(writer.head("", 0, 0));
  std::vector<char> r(writer.record_length());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    writer.record(i, r.data());
    out.write(r.data(), r.size());
  }
  out.close();
}

}  // namespace pointsurf::io::detail
