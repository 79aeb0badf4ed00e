// SPDX-License-Identifier: GPL-3.0-or-later
// XYZ-family text clouds (.xyz, .txt, .pts, .csv, .asc): one point per line, columns separated
// by whitespace, commas or semicolons.
//
// Reading. Blank lines and lines starting with '#' or '//' are skipped. The first non-blank
// line may be
//   - a header of names (no token is a number), optionally "//"-prefixed as CloudCompare writes
//     it: the names give the meaning of the columns (x y z, nx ny nz or normal_x.., r g b or
//     red green blue, i or intensity, anything else kept as a field of that name);
//   - a PTS point count (a single integer), checked against the points found (a warning when
//     they differ).
// Without a header or ReadOptions::columns, the layout is inferred from the values of the first
// 1000 lines (infer_layout below): 3 columns x y z, 4 x y z intensity, 6 normals or colours, 7
// PTS (x y z intensity r g b) or CloudCompare's orders (colours then a field, a field then
// normals) or normals then a field, 9 normals and colours either way round, 10 pointsurf's
// x y z normals colours field or CloudCompare's default export x y z r g b SF nx ny nz; any
// other count, or no layout that fits, x y z and fields "field3", "field4", ... (named by
// 0-based column). More than 3 columns inferred so are named in a warning; two layouts that fit
// equally well are an InputError that asks for --columns.
// Colours are [0,1] when every colour value is <= 1, else 0..255, else 0..65535.
//
// A first line "# x y z ..." naming the columns is a header too (pointsurf writes it; other
// readers skip it as a comment).
//
// Writing. .xyz/.txt/.asc are x y z [nx ny nz] [r g b as 0..255] [fields]; with more than x y z,
// a first line "# x y z [nx ny nz] [r g b] name..." names the columns (a comment to other
// readers), so the round trip keeps every attribute and field by name (fields as Float64: text
// has no types) without inferring a layout; x y z alone, plain numbers. .pts has the PTS count
// line and no names: the layouts read back by their values are xyz, xyz+field (read as
// "intensity"), xyz+normals, xyz+rgb, xyz+field+rgb (written in the PTS order x y z i r g b),
// xyz+normals+field ("field6"), xyz+normals+rgb and xyz+normals+rgb+field ("field9"). .csv
// writes a header line of names and keeps every field with its name.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <optional>
#include <string>
#include <string_view>
#include <tuple>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "io/detail/file_util.h"
#include "io/detail/formats.h"
#include "pointsurf/core/error.h"

namespace pointsurf::io::detail {
namespace {

enum class Column : std::uint8_t { X, Y, Z, NX, NY, NZ, R, G, B, Field, Skip };

// Meaning of every column of the data lines.
struct ColumnSpec {
  std::vector<Column> roles;
  std::vector<int> field_of_column;  // index into field_names for Column::Field, else -1
  std::vector<std::string> field_names;

  bool has(Column c) const { return std::find(roles.begin(), roles.end(), c) != roles.end(); }
  void add(Column c, std::string field_name = {}) {
    roles.push_back(c);
    if (c == Column::Field) {
      field_of_column.push_back(static_cast<int>(field_names.size()));
      field_names.push_back(std::move(field_name));
    } else {
      field_of_column.push_back(-1);
    }
  }
};

// Spreadsheets quote header cells: "x","y","z".
std::string_view unquote(std::string_view s) {
  if (s.size() >= 2 && (s.front() == '"' || s.front() == '\'') && s.back() == s.front()) return s.substr(1, s.size() - 2);
  return s;
}

bool is_number(std::string_view token) {
  double v;
  return parse_number(token, v);
}

bool is_comment(std::string_view trimmed) { return trimmed.front() == '#' || trimmed.starts_with("//"); }

Column classify(std::string_view name) {
  const std::string n = lower(name);
  if (n == "x") return Column::X;
  if (n == "y") return Column::Y;
  if (n == "z") return Column::Z;
  if (n == "nx" || n == "normal_x" || n == "normalx") return Column::NX;
  if (n == "ny" || n == "normal_y" || n == "normaly") return Column::NY;
  if (n == "nz" || n == "normal_z" || n == "normalz") return Column::NZ;
  if (n == "r" || n == "red") return Column::R;
  if (n == "g" || n == "green") return Column::G;
  if (n == "b" || n == "blue") return Column::B;
  if (n == "_") return Column::Skip;
  return Column::Field;
}

std::string field_name_for(std::string_view name) {
  const std::string n = lower(name);
  if (n == "i" || n == "intensity") return "intensity";
  return std::string(name);
}

// Column spec from names (a header line or ReadOptions::columns). Normals and colours count
// only when all three of their columns are named; from a header an incomplete group is kept as
// fields under the names given, from --columns it is an error. `fail` throws.
template <typename Fail>
ColumnSpec spec_from_names(const std::vector<std::string>& names, bool from_options, Fail fail) {
  std::vector<Column> roles;
  for (const std::string& n : names) roles.push_back(classify(n));
  auto count = [&](Column c) { return std::count(roles.begin(), roles.end(), c); };
  for (Column c : {Column::X, Column::Y, Column::Z, Column::NX, Column::NY, Column::NZ, Column::R, Column::G, Column::B})
    if (count(c) > 1) {
      const auto it = std::find(roles.begin(), roles.end(), c);
      const auto again = std::find(it + 1, roles.end(), c);
      fail(fmt::format("columns {} and {} both mean '{}'", it - roles.begin() + 1, again - roles.begin() + 1,
                       names[static_cast<std::size_t>(again - roles.begin())]));
    }
  for (auto [a, b, c, what] : {std::tuple{Column::X, Column::Y, Column::Z, "x, y and z"},
                               std::tuple{Column::NX, Column::NY, Column::NZ, "nx, ny and nz"},
                               std::tuple{Column::R, Column::G, Column::B, "r, g and b"}}) {
    const auto n = count(a) + count(b) + count(c);
    if (n == 0 || n == 3) continue;
    if (from_options || a == Column::X) fail(fmt::format("{} must all be given (got {} of them)", what, n));
    for (std::size_t i = 0; i < roles.size(); ++i)
      if (roles[i] == a || roles[i] == b || roles[i] == c) roles[i] = Column::Field;
  }
  if (count(Column::X) == 0) fail("no x, y, z columns");
  ColumnSpec spec;
  std::vector<std::string> seen;
  for (std::size_t i = 0; i < roles.size(); ++i) {
    if (roles[i] != Column::Field) {
      spec.add(roles[i]);
      continue;
    }
    std::string name = field_name_for(names[i]);
    if (name.empty()) fail(fmt::format("column {} has an empty name", i + 1));
    if (std::find(seen.begin(), seen.end(), name) != seen.end())
      fail(fmt::format("column {}: field '{}' appears twice", i + 1, name));
    seen.push_back(name);
    spec.add(Column::Field, std::move(name));
  }
  return spec;
}

// Headerless text: the layouts that tools write, recognised by their values. Colour triples
// are integers 0..255 (or 0..65535), or numbers in [0, 1]; normal triples have unit length (or
// are zero, undefined); other columns may hold anything. Tuned on the exports of CloudCompare
// (ASCII cloud: X Y Z [R G B] [scalar fields] [Nx Ny Nz], no header by default), Open3D
// (.xyzn, .xyzrgb), Leica PTS (x y z intensity r g b) and pointsurf's own .pts files.
struct TextLayout {
  const char* names;  // one name per column, as --columns takes them
  const char* whose;  // who writes it, for the warning
  bool pts = false;   // an order of .pts files (PTS, pointsurf's): preferred there when another fits as well
};

constexpr TextLayout kTextLayouts[] = {
    {"x y z", "x y z"},
    {"x y z intensity", "intensity in column 4"},
    {"x y z nx ny nz", "unit normals"},
    {"x y z r g b", "colours"},
    {"x y z intensity r g b", "PTS: intensity, then colours", true},
    {"x y z r g b field6", "CloudCompare: colours, then a scalar field"},
    {"x y z field3 nx ny nz", "CloudCompare: a scalar field, then normals"},
    {"x y z nx ny nz field6", "normals, then a field (pointsurf .pts)"},
    {"x y z nx ny nz r g b", "normals, then colours (pointsurf .pts)", true},
    {"x y z r g b nx ny nz", "CloudCompare: colours, then normals"},
    {"x y z nx ny nz r g b field9", "normals, colours, then a field (pointsurf .pts)", true},
    {"x y z r g b field6 nx ny nz", "CloudCompare's default ASCII export: colours, a scalar field, normals"},
};

std::vector<std::string> layout_names(const TextLayout& layout) {
  std::vector<std::string_view> tokens;
  split_tokens(layout.names, tokens);
  return {tokens.begin(), tokens.end()};
}

// How strongly the sampled rows say that columns c..c+2 are colours (2: integers in range, 1:
// numbers in [0, 1], 0: not colours) or normals (2: unit vectors, 0: not).
int colour_evidence(const std::vector<std::vector<double>>& rows, std::size_t c) {
  bool integers = true, unit_range = true;
  for (const std::vector<double>& row : rows)
    for (std::size_t k = c; k < c + 3; ++k) {
      const double v = row[k];
      integers = integers && v >= 0.0 && v <= 65535.0 && v == std::floor(v);
      unit_range = unit_range && v >= 0.0 && v <= 1.0;
    }
  // Integers that are all 0 or 1 say no more than numbers in [0, 1] do (an axis-aligned normal).
  bool binary = true;
  for (const std::vector<double>& row : rows)
    for (std::size_t k = c; k < c + 3; ++k) binary = binary && (row[k] == 0.0 || row[k] == 1.0);
  return integers && !binary ? 2 : unit_range ? 1 : 0;
}

int normal_evidence(const std::vector<std::vector<double>>& rows, std::size_t c) {
  bool any_unit = false;
  for (const std::vector<double>& row : rows) {
    const double len = std::sqrt(row[c] * row[c] + row[c + 1] * row[c + 1] + row[c + 2] * row[c + 2]);
    if (std::abs(len - 1.0) <= 1e-2) any_unit = true;
    else if (len != 0.0) return 0;
  }
  return any_unit ? 2 : 0;
}

// The layout's score on the sampled rows: the sum of its groups' evidence, -1 when a group does
// not fit.
int layout_score(const std::vector<std::string>& names, const std::vector<std::vector<double>>& rows) {
  int score = 0;
  for (std::size_t c = 0; c < names.size(); ++c) {
    const int evidence = names[c] == "r" ? colour_evidence(rows, c) : names[c] == "nx" ? normal_evidence(rows, c) : 3;
    if (evidence == 0) return -1;
    if (evidence < 3) score += evidence;
  }
  return score;
}

// The first data lines (up to 1000) as numbers; stops at a line that is not `columns` numbers
// (the main loop reports it).
std::vector<std::vector<double>> sample_rows(TextCursor cursor, std::string_view first_line, std::size_t columns) {
  std::vector<std::vector<double>> rows;
  std::vector<std::string_view> tokens;
  std::string_view line = first_line;
  while (rows.size() < 1000) {
    const std::string_view t = trim(line);
    if (!t.empty() && !is_comment(t)) {
      split_tokens(t, tokens, true);
      if (tokens.size() != columns) break;
      std::vector<double> row(columns);
      for (std::size_t k = 0; k < columns; ++k)
        if (!parse_number(tokens[k], row[k])) return rows;
      rows.push_back(std::move(row));
    }
    if (!cursor.next_line(line)) break;
  }
  return rows;
}

struct InferredLayout {
  std::vector<std::string> names;
  std::string whose;  // empty for the generic x y z field3 ...
};

// The layout of headerless text by its values: the best-scoring of kTextLayouts with this many
// columns (in a .pts file the PTS order breaks a tie); x y z field3 field4 ... when none fits.
// Throws InputError naming --columns when two layouts fit equally well.
InferredLayout infer_layout(const std::vector<std::vector<double>>& rows, std::size_t columns, bool pts_file, const std::string& name,
                            std::size_t line) {
  const TextLayout* best = nullptr;
  const TextLayout* tied = nullptr;
  std::pair<int, int> best_score{-1, 0};
  for (const TextLayout& layout : kTextLayouts) {
    const std::vector<std::string> names = layout_names(layout);
    if (names.size() != columns) continue;
    const std::pair<int, int> score{layout_score(names, rows), pts_file && layout.pts ? 1 : 0};
    if (score.first < 0) continue;
    if (score > best_score) {
      best = &layout;
      tied = nullptr;
      best_score = score;
    } else if (score == best_score) {
      tied = &layout;
    }
  }
  if (tied != nullptr) {
    std::string spec = best->names;
    std::replace(spec.begin(), spec.end(), ' ', ',');
    throw InputError(fmt::format("{}: line {}: the {} columns without a header fit two layouts by their values: {} ({}) and {} ({}); "
                                 "say which with --columns (e.g. --columns {})",
                                 name, line, columns, best->names, best->whose, tied->names, tied->whose, spec));
  }
  if (best != nullptr) return {layout_names(*best), best->whose};
  InferredLayout generic{{"x", "y", "z"}, {}};
  for (std::size_t c = 3; c < columns; ++c) generic.names.push_back(fmt::format("field{}", c));
  return generic;
}

bool is_separator(char c) { return c == ' ' || c == '\t' || c == ',' || c == ';' || c == '\v' || c == '\f'; }

// Parses a data line where its numbers stand, without splitting it first (splitting was a
// sixth of the reading time). False for anything unusual (a wrong count, a '+' sign, a bad or out-of-range
// token); the caller then takes the slow path, which accepts the same lines and words the error.
bool parse_line_fast(std::string_view line, const std::vector<Column>& roles, double* row) {
  const char* p = line.data();
  const char* const end = p + line.size();
  const std::size_t columns = roles.size();
  std::size_t c = 0;
  for (;;) {
    while (p < end && is_separator(*p)) ++p;
    if (p == end) break;
    if (c == columns) return false;
    if (roles[c] == Column::Skip) {
      while (p < end && !is_separator(*p)) ++p;
    } else {
      const auto [q, ec] = std::from_chars(p, end, row[c]);
      if (ec != std::errc() || (q < end && !is_separator(*q))) return false;
      p = q;
    }
    ++c;
  }
  return c == columns;
}

std::vector<std::string> parse_option_columns(std::string_view text) {
  std::vector<std::string_view> tokens;
  split_tokens(text, tokens, true);
  std::vector<std::string> names;
  for (std::string_view t : tokens) names.emplace_back(t);
  return names;
}

}  // namespace

RawData read_xyz(const std::filesystem::path& path, const ReadOptions& options) {
  const std::string name = display_name(path);
  const FileBytes file_bytes(path);
  const std::string_view text = file_bytes.view();
  std::string_view body(text);
  if (body.starts_with("\xEF\xBB\xBF")) body.remove_prefix(3);  // UTF-8 byte order mark

  RawData raw;
  raw.encoding = "ascii";
  TextCursor cursor(body);
  std::vector<std::string_view> tokens;
  std::string_view line;

  // Leading lines: an optional header of names or PTS count, comments, blank lines.
  std::optional<std::vector<std::string>> header;
  std::size_t header_line = 0;
  bool header_slashes = false;
  std::optional<long long> declared_count;
  std::size_t count_line = 0;
  std::string_view first_data;
  bool seen_content = false;
  while (cursor.next_line(line)) {
    const std::string_view t = trim(line);
    if (t.empty()) continue;
    const bool first = !seen_content;
    seen_content = true;
    if (first) {
      // "//x y z" (CloudCompare) and "# x y z" (pointsurf) headers are comments to other readers.
      const bool slashes = t.starts_with("//") || t.front() == '#';
      split_tokens(t.substr(t.starts_with("//") ? 2 : t.front() == '#' ? 1 : 0), tokens, true);
      if (!tokens.empty() && std::none_of(tokens.begin(), tokens.end(), is_number)) {
        header.emplace();
        for (std::string_view tok : tokens) header->emplace_back(unquote(tok));
        header_line = cursor.line_number();
        header_slashes = slashes;
        continue;
      }
      long long count = 0;
      if (!slashes && tokens.size() == 1 && parse_number(tokens[0], count) && count >= 0) {
        declared_count = count;
        count_line = cursor.line_number();
        continue;
      }
    }
    if (is_comment(t)) continue;
    first_data = t;
    break;
  }
  if (first_data.empty()) {
    if (declared_count && *declared_count != 0)
      raw.warnings.push_back(fmt::format("{}: line {}: point count {} but the file holds no points", name, count_line, *declared_count));
    return raw;
  }
  const std::size_t first_data_line = cursor.line_number();
  split_tokens(first_data, tokens, true);
  const std::size_t columns = tokens.size();

  ColumnSpec spec;
  if (!options.columns.empty()) {
    const std::vector<std::string> names = parse_option_columns(options.columns);
    spec = spec_from_names(names, true, [&](const std::string& why) -> void {
      throw UsageError(fmt::format("column spec '{}': {}; expected names such as x,y,z,nx,ny,nz,r,g,b,i, other names for fields, _ to skip",
                                   options.columns, why));
    });
    if (columns < spec.roles.size())
      throw InputError(fmt::format("{}: line {}: expected {} values (column spec '{}'), got {}", name, first_data_line,
                                   spec.roles.size(), options.columns, columns));
    if (columns > spec.roles.size()) {
      raw.warnings.push_back(fmt::format("{}: columns {}-{} are not in the column spec '{}' and were skipped", name,
                                         spec.roles.size() + 1, columns, options.columns));
      while (spec.roles.size() < columns) spec.add(Column::Skip);
    }
  } else if (header && header->size() == columns && std::any_of(header->begin(), header->end(), [](const std::string& n) {
               const Column c = classify(n);
               return c == Column::X || c == Column::Y || c == Column::Z;
             })) {
    spec = spec_from_names(*header, false, [&](const std::string& why) -> void {
      throw InputError(fmt::format("{}: line {}: header: {}; use a column spec (--columns) to say what the columns are", name, header_line, why));
    });
  } else {
    // A "//" line that is no header of this data is an ordinary comment; a plain line of words
    // is most likely a title, worth a warning since the columns are then inferred from the values.
    if (header && !header_slashes)
      raw.warnings.push_back(fmt::format("{}: line {}: first line is not a header of x, y, z columns for the {} columns of the data; "
                                         "ignored, columns inferred from the values (use a column spec to say what they are)",
                                         name, header_line, columns));
    if (columns < 3)
      throw InputError(fmt::format("{}: line {}: expected at least 3 values (x y z), got {}", name, first_data_line, columns));
    const bool pts_file = lower(path.extension().string()) == ".pts";
    const std::vector<std::vector<double>> rows = sample_rows(cursor, first_data, columns);
    const InferredLayout layout = infer_layout(rows, columns, pts_file, name, first_data_line);
    spec = spec_from_names(layout.names, false, [](const std::string&) {});
    if (columns > 3)
      raw.warnings.push_back(fmt::format("{}: no header: columns taken as {} ({}), inferred from the values of the first {} lines; "
                                         "give --columns to say otherwise",
                                         name, fmt::join(layout.names, " "),
                                         layout.whose.empty() ? "no known layout fits: fields by column" : layout.whose, rows.size()));
  }

  // One pass over the data lines, parsing each token in place.
  const bool normals = spec.has(Column::NX);
  const bool colours = spec.has(Column::R);
  const std::size_t line_estimate = static_cast<std::size_t>(std::count(body.begin() + static_cast<std::ptrdiff_t>(cursor.offset()), body.end(), '\n')) + 1;
  PointCloud& cloud = raw.cloud;
  cloud.positions.reserve(line_estimate);
  if (normals) cloud.normals.reserve(line_estimate);
  if (colours) cloud.colors.reserve(line_estimate);
  std::vector<std::vector<double>> field_values(spec.field_names.size());
  for (auto& v : field_values) v.reserve(line_estimate);

  std::vector<double> row(columns);
  line = first_data;
  std::size_t line_number = first_data_line;
  for (;;) {
    const std::string_view t = trim(line);
    if (!t.empty() && !is_comment(t)) {
      if (!parse_line_fast(t, spec.roles, row.data())) {
        split_tokens(t, tokens, true);
        if (tokens.size() != columns)
          throw InputError(fmt::format("{}: line {}: expected {} values, got {}", name, line_number, columns, tokens.size()));
        for (std::size_t c = 0; c < columns; ++c) {
          if (spec.roles[c] == Column::Skip) continue;
          if (!parse_number(tokens[c], row[c]))
            throw InputError(fmt::format("{}: line {}, column {}: '{}' is not a number", name, line_number, c + 1, shown(tokens[c])));
        }
      }
      Vector3d p = Vector3d::Zero(), n = Vector3d::Zero();
      Vector3f rgb = Vector3f::Zero();
      for (std::size_t c = 0; c < columns; ++c) {
        const double v = row[c];
        switch (spec.roles[c]) {
          case Column::X: p.x() = v; break;
          case Column::Y: p.y() = v; break;
          case Column::Z: p.z() = v; break;
          case Column::NX: n.x() = v; break;
          case Column::NY: n.y() = v; break;
          case Column::NZ: n.z() = v; break;
          case Column::R: rgb.x() = static_cast<float>(v); break;
          case Column::G: rgb.y() = static_cast<float>(v); break;
          case Column::B: rgb.z() = static_cast<float>(v); break;
          case Column::Field: field_values[static_cast<std::size_t>(spec.field_of_column[c])].push_back(v); break;
          case Column::Skip: break;
        }
      }
      cloud.positions.push_back(p);
      if (normals) cloud.normals.push_back(n);
      if (colours) cloud.colors.push_back(rgb);
    }
    if (!cursor.next_line(line)) break;
    line_number = cursor.line_number();
  }

  if (colours) {
    // The scale is a property of the file, so it is chosen from every colour value at once.
    float max_value = 0.0f;
    for (const Vector3f& c : cloud.colors) max_value = std::max(max_value, c.maxCoeff());
    const float scale = max_value <= 1.0f ? 1.0f : max_value <= 255.0f ? 1.0f / 255.0f : 1.0f / 65535.0f;
    for (Vector3f& c : cloud.colors) c = (c * scale).cwiseMax(0.0f).cwiseMin(1.0f);
  }
  for (std::size_t f = 0; f < field_values.size(); ++f) {
    ScalarField& field = cloud.fields.add(spec.field_names[f], 0, ScalarType::Float64);
    field.values = std::move(field_values[f]);
  }
  if (declared_count && static_cast<unsigned long long>(*declared_count) != cloud.size())
    raw.warnings.push_back(fmt::format("{}: line {}: point count {} differs from the {} points in the file", name, count_line,
                                       *declared_count, cloud.size()));
  return raw;
}

namespace {

// Which member of the family to write: the dispatch passes the target's extension as
// options.format ("csv", "pts", "xyz"), so the temporary path's name plays no part.
std::string output_kind(const WriteOptions& options) {
  const std::string forced = lower(options.format);
  if (forced == "csv" || forced == "pts") return forced;
  return "xyz";
}

}  // namespace

void write_xyz(const std::filesystem::path& path, const PointCloud& cloud, const WriteOptions& options) {
  const std::string kind = output_kind(options);
  const bool csv = kind == "csv";
  const char separator = csv ? ',' : ' ';
  const bool normals = cloud.has_normals();
  const bool colours = cloud.has_colors();

  std::vector<const ScalarField*> fields;
  for (const ScalarField& f : cloud.fields) fields.push_back(&f);
  // One field with colours and no normals goes between xyz and rgb: the PTS layout that the
  // 7-column default reads back.
  const bool pts_order = !csv && !normals && colours && fields.size() == 1;

  const auto header_name = [](const std::string& name) {
    const bool bad_char = std::any_of(name.begin(), name.end(), [](char c) {
      return c == ',' || c == ';' || c == '"' || std::isspace(static_cast<unsigned char>(c)) || c == '#';
    });
    return !(name.empty() || bad_char || is_number(name) || classify(name) != Column::Field || name.starts_with("//"));
  };
  if (csv) {
    for (const ScalarField* f : fields)
      if (!header_name(f->name))
        throw UsageError(fmt::format("{}: field '{}' cannot be a CSV column name (it would not read back as that field); rename it",
                                     display_name(path), f->name));
  }
  // .xyz/.txt with more than x y z: a "# x y z ... name" line, a comment to other readers, names the
  // columns for ours (a name that could not read back leaves the file headerless, as before).
  const bool comment_header = kind == "xyz" && (!fields.empty() || normals || colours) &&
                              std::all_of(fields.begin(), fields.end(), [&](const ScalarField* f) { return header_name(f->name); });

  FileWriter out(path);
  if (kind == "pts") out.write(fmt::format("{}\n", cloud.size()));
  if (csv || comment_header) {
    const char* sep = csv ? "," : " ";
    std::string header = fmt::format("{}x{}y{}z", csv ? "" : "# ", sep, sep);
    if (normals) header += fmt::format("{0}nx{0}ny{0}nz", sep);
    if (pts_order) header += sep + fields[0]->name;
    if (colours) header += fmt::format("{0}r{0}g{0}b", sep);
    if (!pts_order)
      for (const ScalarField* f : fields) header += sep + f->name;
    header += '\n';
    out.write(header);
  }

  const int precision = options.precision;
  auto put = [&](double v) {
    out.write(&separator, 1);
    out.write_double(v, precision);
  };
  auto put_colour = [&](const Vector3f& c) {
    for (int k = 0; k < 3; ++k) {
      char text[8] = {separator};
      const long v = std::lround(std::clamp(static_cast<double>(c[k]), 0.0, 1.0) * 255.0);
      const auto r = std::to_chars(text + 1, text + sizeof(text), v);
      out.write(text, static_cast<std::size_t>(r.ptr - text));
    }
  };
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const Vector3d& p = cloud.positions[i];
    out.write_double(p.x(), precision);
    put(p.y());
    put(p.z());
    if (normals)
      for (int k = 0; k < 3; ++k) put(cloud.normals[i][k]);
    if (pts_order) {
      put(fields[0]->values[i]);
      put_colour(cloud.colors[i]);
    } else {
      if (colours) put_colour(cloud.colors[i]);
      for (const ScalarField* f : fields) put(f->values[i]);
    }
    out.write("\n", 1);
  }
  out.close();
}

}  // namespace pointsurf::io::detail
