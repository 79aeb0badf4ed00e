// SPDX-License-Identifier: GPL-3.0-or-later
// LAZ (LASzip-compressed LAS) reader and writer. The header, VLRs and point records are LAS's
// (las_format.cpp); the point data is a sequence of chunks, each decoded on its own by the
// LASzip item coders (detail/laz_items.cpp), followed by a chunk table of their sizes. The file
// is read chunk by chunk: memory holds one chunk's bytes besides the cloud.
#include <algorithm>
#include <array>
#include <cstring>
#include <cstdio>
#include <limits>
#include <map>
#include <stdexcept>
#include <vector>

#include <fmt/format.h>

#include "io/detail/file_util.h"
#include "io/detail/formats.h"
#include "io/detail/las_format.h"
#include "io/detail/laz_items.h"
#include "io/detail/laz_layered.h"
#include "pointsurf/core/error.h"

namespace pointsurf::io::detail {
namespace {

// Positioned reads from a file; every failure is an InputError naming it.
class InputFile {
public:
  InputFile(const std::filesystem::path& path, std::string name) : name_(std::move(name)) {
    file_ = std::fopen(path.c_str(), "rb");
    if (!file_) throw InputError(fmt::format("{}: cannot open for reading", name_));
    std::error_code ec;
    size_ = std::filesystem::file_size(path, ec);
    if (ec) throw InputError(fmt::format("{}: cannot read its size", name_));
  }
  ~InputFile() { std::fclose(file_); }
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;
  std::uint64_t size() const { return size_; }
  // `count` bytes at `offset`; false when the file ends first.
  bool read(std::uint64_t offset, std::size_t count, void* out) {
    if (offset > size_ || count > size_ - offset) return false;
    if (fseeko(file_, static_cast<off_t>(offset), SEEK_SET) != 0) return false;
    return std::fread(out, 1, count, file_) == count;
  }
  std::string read(std::uint64_t offset, std::size_t count) {
    std::string s(count, '\0');
    if (!read(offset, count, s.data())) throw InputError(fmt::format("{}: file ends before byte {}", name_, offset + count));
    return s;
  }

private:
  std::string name_;
  std::FILE* file_ = nullptr;
  std::uint64_t size_ = 0;
};

std::string describe(const laz::LaszipVlr& v) {
  static const char* const kCompressors[] = {"none", "point-wise", "point-wise chunked", "layered chunked"};
  return fmt::format("LASzip {}.{}r{}, {} compressor, {}", v.version_major, v.version_minor, v.revision,
                     v.compressor < 4 ? kCompressors[v.compressor] : "unknown",
                     v.chunk_size == laz::kVariableChunks ? std::string("variable chunks") : fmt::format("chunk size {}", v.chunk_size));
}

// COPC: the "copc" info VLR (record 1) gives the octree's root cube; the hierarchy pages give
// each node's key (level d and integer position x, y, z) and the file offset of its chunk.
struct CopcNode {
  int level = 0;
  std::array<int, 3> key{};
};

struct CopcOctree {
  std::array<double, 3> center{};
  double halfsize = 0;
  std::map<std::uint64_t, CopcNode> nodes;  // by chunk offset
  // Whether the node's cube meets the box (xmin, ymin, zmin, xmax, ymax, zmax).
  bool meets(const CopcNode& node, const std::array<double, 6>& box) const {
    if (node.level > 60) return true;
    const double side = 2.0 * halfsize / double(std::uint64_t(1) << node.level);
    for (int a = 0; a < 3; ++a) {
      const double lo = center[a] - halfsize + side * node.key[a];
      if (lo > box[3 + a] || lo + side < box[a]) return false;
    }
    return true;
  }
};

CopcOctree read_copc(InputFile& file, std::string_view info, const std::string& name) {
  if (info.size() < 56) throw InputError(fmt::format("{}: COPC info VLR has {} bytes, needs 160", name, info.size()));
  CopcOctree tree;
  for (int a = 0; a < 3; ++a) std::memcpy(&tree.center[a], info.data() + 8 * a, 8);
  std::memcpy(&tree.halfsize, info.data() + 24, 8);
  std::uint64_t root_offset = 0, root_size = 0;
  std::memcpy(&root_offset, info.data() + 40, 8);
  std::memcpy(&root_size, info.data() + 48, 8);
  std::vector<std::pair<std::uint64_t, std::uint64_t>> pages{{root_offset, root_size}};
  // Each page holds 32-byte entries; a page is read once, so the walk ends within the file.
  std::uint64_t read_bytes = 0;
  for (std::size_t p = 0; p < pages.size(); ++p) {
    const auto [offset, size] = pages[p];
    read_bytes += size;
    if (size % 32 != 0 || offset > file.size() || size > file.size() - offset || read_bytes > file.size())
      throw InputError(fmt::format("{}: COPC hierarchy page of {} bytes at byte {} lies outside the file or is not whole entries", name, size, offset));
    const std::string page = file.read(offset, static_cast<std::size_t>(size));
    for (std::size_t e = 0; e < page.size(); e += 32) {
      std::int32_t key[4], bytes = 0, points = 0;
      std::uint64_t at = 0;
      std::memcpy(key, page.data() + e, 16);
      std::memcpy(&at, page.data() + e + 16, 8);
      std::memcpy(&bytes, page.data() + e + 24, 4);
      std::memcpy(&points, page.data() + e + 28, 4);
      if (points == -1) pages.emplace_back(at, static_cast<std::uint64_t>(bytes));
      else if (points > 0) tree.nodes[at] = {key[0], {key[1], key[2], key[3]}};
    }
  }
  return tree;
}

}  // namespace

RawData read_laz(const std::filesystem::path& path, const ReadOptions& options) {
  const std::string name = display_name(path);
  InputFile file(path, name);
  const std::uint64_t file_size = file.size();
  std::string head = file.read(0, static_cast<std::size_t>(std::min<std::uint64_t>(file_size, 375)));
  LasHeader header = parse_las_header(head, file_size, name);
  if (header.point_offset > file_size)
    throw InputError(fmt::format("{}: offset to point data {} lies beyond the file's {} bytes", name, header.point_offset, file_size));
  head = file.read(0, header.point_offset);
  header = parse_las_header(head, file_size, name);

  const std::vector<LasVlr> vlrs = las_vlrs(head, header);
  const auto found = std::find_if(vlrs.begin(), vlrs.end(), [](const LasVlr& v) {
    return v.user_id == laz::kLaszipUserId && v.record_id == laz::kLaszipRecordId;
  });
  if (found == vlrs.end())
    throw InputError(fmt::format("{}: compressed point data without the LASzip VLR ('{}', record {}) that describes it", name,
                                 laz::kLaszipUserId, laz::kLaszipRecordId));
  laz::LaszipVlr lz;
  std::unique_ptr<laz::ChunkDecoder> decoder;
  try {
    lz = laz::LaszipVlr::parse(found->body);
    decoder = std::make_unique<laz::ChunkDecoder>(lz);
  } catch (const std::runtime_error& e) {
    throw InputError(fmt::format("{}: LASzip VLR: {}", name, e.what()));
  }
  if (lz.record_size() != header.record_length)
    throw InputError(fmt::format("{}: the LASzip items make {}-byte records, the header says {}", name, lz.record_size(), header.record_length));
  if (lz.chunk_size == 0) throw InputError(fmt::format("{}: LASzip VLR: chunk size 0", name));

  // Where each chunk starts and how many points it holds.
  const std::uint64_t n = header.count;
  std::vector<std::uint64_t> chunk_start, chunk_bytes, chunk_points;
  if (lz.compressor == 1) {
    if (n > 1 + 4096 * (file_size - header.point_offset))
      throw InputError(fmt::format("{}: {} points cannot fit in the file's {} bytes of point data", name, n, file_size - header.point_offset));
    chunk_start.push_back(header.point_offset);
    chunk_bytes.push_back(file_size - header.point_offset);
    chunk_points.push_back(n);
  } else {
    std::int64_t table_at = 0;
    if (!file.read(header.point_offset, 8, &table_at))
      throw InputError(fmt::format("{}: file ends at byte {} before the chunk table offset at byte {}", name, file_size, header.point_offset));
    const std::uint64_t first = header.point_offset + 8;
    if (table_at == -1 && file_size >= first + 8) file.read(file_size - 8, 8, &table_at);  // written last by a streaming writer
    if (table_at < static_cast<std::int64_t>(first) || static_cast<std::uint64_t>(table_at) + 8 > file_size)
      throw InputError(fmt::format("{}: chunk table offset {} (byte {}) lies outside the file ({} bytes): truncated or corrupt", name,
                                   table_at, header.point_offset, file_size));
    const std::size_t table_size = static_cast<std::size_t>(std::min<std::uint64_t>(file_size - table_at, std::uint64_t(64) << 20));
    const std::string table_bytes = file.read(static_cast<std::uint64_t>(table_at), table_size);
    const bool variable = lz.chunk_size == laz::kVariableChunks;
    laz::ChunkTable table;
    try {
      table = laz::decode_chunk_table(reinterpret_cast<const unsigned char*>(table_bytes.data()), table_bytes.size(), variable);
    } catch (const std::runtime_error& e) {
      throw InputError(fmt::format("{}: chunk table at byte {}: {}", name, table_at, e.what()));
    }
    std::uint64_t at = first, points = 0;
    for (std::size_t c = 0; c < table.bytes.size() && points < n; ++c) {
      const std::uint64_t count = variable ? table.points[c] : std::min<std::uint64_t>(lz.chunk_size, n - points);
      if (at + table.bytes[c] > static_cast<std::uint64_t>(table_at))
        throw InputError(fmt::format("{}: chunk {} of {}: the chunk table gives it {} bytes from byte {}, past the chunk table at byte {}", name,
                                     c, table.bytes.size(), table.bytes[c], at, table_at));
      // Every point after a chunk's first costs at least one symbol of a 64- or 128-symbol model,
      // over 0.002 bits: more than 4096 points a byte cannot be intact (and would only make the
      // reader allocate for points that are not there).
      if (count > 1 + 4096 * (table.bytes[c] > header.record_length ? table.bytes[c] - header.record_length : 0))
        throw InputError(fmt::format("{}: chunk {} of {}: {} points cannot fit in its {} bytes: the chunk table or header is corrupt", name, c,
                                     table.bytes.size(), count, table.bytes[c]));
      chunk_start.push_back(at);
      chunk_bytes.push_back(table.bytes[c]);
      chunk_points.push_back(count);
      at += table.bytes[c];
      points += count;
    }
    if (points < n)
      throw InputError(fmt::format("{}: the chunk table's {} chunks hold {} points; the header announces {}", name, table.bytes.size(), points, n));
  }

  RawData raw;
  raw.encoding = fmt::format("LAZ {}.{} point format {} ({})", header.major, header.minor, header.format, describe(lz));

  // COPC: the chunks of the octree nodes asked for (levels, bounds); the rest is not decoded.
  std::vector<bool> wanted(chunk_start.size(), true);
  const auto copc = std::find_if(vlrs.begin(), vlrs.end(), [](const LasVlr& v) { return v.user_id == "copc" && v.record_id == 1; });
  if (options.copc_level >= 0 && copc == vlrs.end())
    throw UsageError(fmt::format("{}: an octree level needs a COPC file; this LAZ file has no COPC info VLR", name));
  if (copc != vlrs.end() && (options.copc_level >= 0 || options.bounds)) {
    const CopcOctree tree = read_copc(file, copc->body, name);
    std::uint64_t nodes = 0;
    for (std::size_t c = 0; c < chunk_start.size(); ++c) {
      const auto node = tree.nodes.find(chunk_start[c]);
      if (node == tree.nodes.end()) continue;
      wanted[c] = (options.copc_level < 0 || node->second.level <= options.copc_level) && (!options.bounds || tree.meets(node->second, *options.bounds));
      nodes += wanted[c];
    }
    raw.encoding += fmt::format(", COPC octree: {} of {} nodes read", nodes, tree.nodes.size());
    header.count = 0;
    for (std::size_t c = 0; c < chunk_start.size(); ++c)
      if (wanted[c]) header.count += chunk_points[c];
  }
  const std::uint64_t n_read = header.count;
  LasRecordReader records(header, head, name, raw);
  if (header.evlr_count > 0 && header.evlr_start >= header.point_offset && header.evlr_start < file_size)
    read_las_crs(las_evlrs(file.read(header.evlr_start, static_cast<std::size_t>(file_size - header.evlr_start)), header), raw.cloud.crs);
  std::vector<char> record(header.record_length);
  std::vector<unsigned char> chunk;
  std::uint64_t i = 0, total = 0;  // points read, points before this chunk in the file
  for (std::size_t c = 0; c < chunk_start.size() && i < n_read; total += chunk_points[c], ++c) {
    if (!wanted[c]) continue;
    const std::uint64_t first = total, first_read = i;
    const auto fail = [&](std::string_view what) {
      return InputError(fmt::format("{}: chunk {} of {} (points {} to {}, {} bytes at byte {}): {}", name, c, chunk_start.size(), first,
                                    first + chunk_points[c] - 1, chunk_bytes[c], chunk_start[c], what));
    };
    chunk.resize(static_cast<std::size_t>(chunk_bytes[c]));
    if (!file.read(chunk_start[c], chunk.size(), chunk.data())) throw fail(fmt::format("file ends at byte {}", file_size));
    decoder->start(chunk.data(), chunk.size());
    const std::uint64_t end = std::min(n_read, i + chunk_points[c]);
    bool intact = true;
    try {
      for (; i < end && (intact = decoder->next(record.data())); ++i) records.read(static_cast<std::size_t>(i), record.data());
    } catch (const std::runtime_error& e) {  // from the decoder: what it found corrupt
      throw fail(fmt::format("corrupt: {}", e.what()));
    }
    if (!intact) throw fail(fmt::format("truncated or corrupt: the compressed data ends at point {}", first + (i - first_read)));
  }
  records.finish();
  return raw;
}

// Written as the LAS writer writes (LAS 1.4, point format 6, or 7 with colours, extra bytes for
// the other fields) with LASzip's layered chunked compressor, 50,000 points per chunk.
void write_laz(const std::filesystem::path& path, const PointCloud& cloud, const WriteOptions& options, std::vector<std::string>& notes) {
  const std::string name = display_name(path);
  const LasRecordWriter writer(cloud, options, name, notes);
  laz::LaszipVlr lz;
  lz.compressor = 3;
  lz.items = laz::layered_items(writer.format(), writer.extra_bytes());
  const std::string head = writer.head(las_vlr(laz::kLaszipUserId, laz::kLaszipRecordId, "pointsurf", lz.body()), 1, 0x80);

  FileWriter out(path);
  out.write(head);
  out.write_value<std::int64_t>(0);  // the chunk table's offset, patched below
  std::uint64_t at = head.size() + 8;
  std::vector<unsigned char> chunk;
  laz::ChunkEncoder encoder(lz, chunk);
  laz::ChunkTable table;
  std::vector<char> record(writer.record_length());
  const std::size_t n = cloud.size();
  for (std::size_t first = 0; first < n; first += lz.chunk_size) {
    const std::size_t last = std::min<std::size_t>(n, first + lz.chunk_size);
    chunk.clear();
    encoder.start();
    for (std::size_t i = first; i < last; ++i) {
      writer.record(i, record.data());
      encoder.add(record.data());
    }
    encoder.finish();
    out.write(chunk.data(), chunk.size());
    table.points.push_back(last - first);
    table.bytes.push_back(chunk.size());
    at += chunk.size();
  }
  out.write(laz::encode_chunk_table(table, false));
  out.close();

  std::FILE* f = std::fopen(path.c_str(), "r+b");
  const auto offset = static_cast<std::int64_t>(at);
  const bool ok = f && fseeko(f, static_cast<off_t>(head.size()), SEEK_SET) == 0 && std::fwrite(&offset, 8, 1, f) == 1;
  if (f && std::fclose(f) != 0) throw Error(fmt::format("{}: cannot write the chunk table offset", name));
  if (!ok) throw Error(fmt::format("{}: cannot write the chunk table offset", name));
}

}  // namespace pointsurf::io::detail
