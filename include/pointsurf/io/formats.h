// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// The one table of file formats: name, extensions, how the content is recognised, reader,
// writer and what each format holds. io's read/write dispatch, format detection, `pointsurf
// info`, the CLI's --input-format/--output-format choices, the pipeline's read/write stages
// and docs/formats.md all come from it; messages that list the known formats do too.
//
//   for (const FileFormat& f : file_formats()) std::printf("%s %s\n", f.name.c_str(), f.extensions.front().c_str());
//   const FileFormat& f = format_for_extension("scan.laz");   // f.name == "laz"
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "pointsurf/io/io.h"

namespace pointsurf {

namespace io::detail {
struct RawData;
}

/// The first bytes of a file, as format sniffers see them.
struct FileHead {
  std::string_view bytes;       // up to the first 4096 bytes
  std::uintmax_t size = 0;      // the whole file's size
  std::string_view first_line;  // first line that is neither blank nor a '#' comment
};

struct FileFormat {
  std::string name;                     // canonical name: "ply", "xyz", ... (read/write --format)
  std::string title;                    // for people: "PLY", "XYZ / TXT / PTS / CSV"
  std::vector<std::string> extensions;  // lower case with the dot; the first is the usual one
  std::vector<std::string> aliases;     // other names --format accepts ("csv" for xyz)
  std::string magic;                    // how the content is recognised, for people
  // Content detection: `sniff` is asked in `detect_order` (lower first); nullptr: the format
  // is never recognised by content (xyz is the fallback for text). `after_binary_check`:
  // asked only once the content is known to be text.
  bool (*sniff)(const FileHead&) = nullptr;
  int detect_order = 0;
  bool after_binary_check = false;
  bool text_fallback = false;           // headerless text that no sniffer claims is this format
  bool binary_by_extension = false;     // binary content with this extension goes to its reader, which says what is wrong
  bool header_required = false;         // text with this extension but without the format's header is an error
  bool reads_octree_levels = false;     // ReadOptions::copc_level applies (COPC)
  // Reader and writer. The writer writes the temporary file `tmp`; `target` is the final path
  // (its extension may choose a family member, e.g. .csv).
  io::detail::RawData (*read)(const std::filesystem::path& path, const ReadOptions& options) = nullptr;
  void (*write)(const std::filesystem::path& tmp, const std::filesystem::path& target, const PointCloud& cloud,
                const std::vector<Triangle>& triangles, const FieldSet& face_fields, const WriteOptions& options,
                std::vector<std::string>& notes) = nullptr;
  // What the format holds (a write of something it does not hold says so in a warning).
  bool holds_faces = false;
  bool holds_face_fields = false;
  bool holds_normals = true;
  bool holds_colors = true;
  bool holds_fields = true;
  std::vector<std::string> extensions_without_field_names;  // fields kept as unnamed columns (.pts)
};

/// Every format, in the order of the --format choices.
const std::vector<FileFormat>& file_formats();

/// The format named `name` (canonical name or alias, any case); nullptr when none.
const FileFormat* find_file_format(std::string_view name);
/// The format named `name`; throws UsageError listing the known names otherwise.
const FileFormat& file_format(std::string_view name);
/// The format of `path`'s extension; nullptr when the extension is unknown.
const FileFormat* find_format_for_extension(const std::filesystem::path& path);
/// The format of `path`'s extension; throws UsageError listing the known extensions otherwise.
const FileFormat& format_for_extension(const std::filesystem::path& path);
/// Whether the format named `name` holds faces (false for an unknown name).
bool format_holds_faces(std::string_view name);

/// "ply, xyz, pcd, ..." (canonical names) and ".ply .xyz .txt ..." (every extension), for messages.
std::string known_format_names(std::string_view separator = ", ");
std::string known_extensions(std::string_view separator = " ");
/// The canonical names, in table order.
std::vector<std::string> format_names();

/// The table as Markdown (docs/formats.md holds it between `<!-- format-table -->` markers).
std::string format_table_markdown();

/// Writes `bytes` to `path` through a temporary file in the same directory renamed when
/// complete: the file is whole or absent (an earlier file stays as it was on failure).
/// Throws Error naming the path on an I/O failure.
void write_file_atomically(const std::filesystem::path& path, std::string_view bytes);

}  // namespace pointsurf
