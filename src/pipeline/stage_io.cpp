// SPDX-License-Identifier: GPL-3.0-or-later
// The reader and writer stages: a file name in a pipeline stands for one of them.
#include <algorithm>
#include <cctype>

#include "pipeline/detail/declare.h"
#include "pipeline/detail/stage_util.h"
#include "pointsurf/core/error.h"
#include "pointsurf/io/formats.h"
#include "pointsurf/io/io.h"
#include "pointsurf/pipeline/context.h"

namespace pointsurf::detail {
namespace {

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

std::string upper(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  return s;
}

// The --format choices: "" (detect / from the extension) and every format of the table.
std::vector<std::string> format_choices() {
  std::vector<std::string> choices = {""};
  for (const std::string& name : format_names()) choices.push_back(name);
  return choices;
}

// "PLY, XYZ, PCD, ...": every format of the table.
std::string format_titles() {
  std::string out;
  for (const FileFormat& f : file_formats()) out += (out.empty() ? "" : ", ") + upper(f.name);
  return out;
}

bool holds_faces(const std::string& format) { return format_holds_faces(format); }

// What read and write report.
struct FileSummary {
  std::size_t scans = 0, points = 0, faces = 0, dropped_nonfinite = 0;
  std::string encoding;
  bool normals = false, colors = false;
  std::string fields;           // names of the scalar fields, comma-separated
  std::string mesh_built_from;  // write: the tag of the cloud a mesh was built from
};
using FileTable = ResultTable<FileSummary>;
// E57: counted when the file has several scans or they keep their own frames.
const FileTable& scan_counts() {
  static const FileTable table = [] {
    FileTable t;
    t.count("scans", &FileSummary::scans, "Scans in the file (several, or kept in their own frames)");
    return t;
  }();
  return table;
}
const FileTable& read_counts() {
  static const FileTable table = [] {
    FileTable t;
    t.count("points", &FileSummary::points, "Points read");
    t.count("faces", &FileSummary::faces, "Faces read");
    t.count("dropped_nonfinite", &FileSummary::dropped_nonfinite, "Points with NaN/Inf coordinates dropped").lower_is_better();
    return t;
  }();
  return table;
}
const FileTable& read_metrics() {
  static const FileTable table = [] {
    FileTable t;
    t.text("encoding", &FileSummary::encoding, "Encoding of the file (ascii, binary_little_endian, ...)");
    t.flag("normals", &FileSummary::normals, "The data has normals");
    t.flag("colors", &FileSummary::colors, "The data has colours");
    t.text("fields", &FileSummary::fields, "Its scalar fields, comma-separated");
    return t;
  }();
  return table;
}
const FileTable& write_counts() {
  static const FileTable table = [] {
    FileTable t;
    t.count("points", &FileSummary::points, "Points written");
    t.count("faces", &FileSummary::faces, "Faces written (0 where the format holds none)");
    return t;
  }();
  return table;
}
const FileTable& write_metrics() {  // a mesh only
  static const FileTable table = [] {
    FileTable t;
    t.text("mesh_built_from", &FileSummary::mesh_built_from, "Tag of the cloud the mesh was built from");
    return t;
  }();
  return table;
}

void run_read(StageRun& run) {
  const std::string& file = run.args.text("filename");
  ReadOptions options;
  options.strict = run.args.boolean("strict");
  options.apply_poses = !run.args.boolean("keep_poses");
  options.columns = run.args.text("columns");
  options.format = run.args.text("format");
  options.copc_level = static_cast<int>(run.args.integer("copc_level"));
  if (const std::vector<double>& b = run.args.numbers("bounds"); !b.empty()) options.bounds = std::array<double, 6>{b[0], b[1], b[2], b[3], b[4], b[5]};
  const std::string format = options.format.empty() ? detect_format(file) : options.format;
  if (holds_faces(format) && (options.bounds || options.copc_level >= 0))
    throw UsageError(fmt::format("{}: --bounds and --copc-level select points of a cloud; this is a {} mesh file", file, format));
  options.format = format;
  StageRecord& rec = run.record;
  std::size_t dropped = 0;
  std::vector<std::string> warnings;
  DataItem item;
  item.source = file;
  std::string encoding;
  if (holds_faces(format)) {
    MeshReadResult r = read_mesh(file, options);
    dropped = r.dropped_nonfinite;
    warnings = std::move(r.warnings);
    encoding = r.encoding;
    if (r.dropped_faces > 0) warnings.push_back(fmt::format("{} dropped (degenerate or on dropped vertices)", plural(r.dropped_faces, "face")));
    if (r.polygons_triangulated > 0) warnings.push_back(fmt::format("{} split into triangles", plural(r.polygons_triangulated, "polygon")));
    item.mesh = std::move(r.mesh);
    item.is_mesh = !item.mesh.triangles.empty();
  } else {
    CloudReadResult r = read_point_cloud(file, options);
    dropped = r.dropped_nonfinite;
    warnings = std::move(r.warnings);
    encoding = r.encoding;
    item.cloud() = std::move(r.cloud);
    FileSummary scans;
    scans.scans = r.scans.size();
    if (r.scans.size() > 1 || !options.apply_poses) rec.add_counts(scan_counts(), scans);
    if (options.apply_poses)
      for (const ScanPose& pose : r.scans) item.scanners.push_back(pose.translation);  // where each sensor stood, in the cloud's frame
    else
      item.scans = std::move(r.scans);
  }
  for (std::string& w : warnings) rec.warnings.push_back(w.rfind(file, 0) == 0 ? w : file + ": " + w);
  if (dropped > 0)
    rec.warnings.push_back(fmt::format("{}: {} with NaN/Inf coordinates dropped (strict makes this an error)", file, plural(dropped, "point")));
  if (item.cloud().empty()) throw InputError(fmt::format("{}: no points", file));
  rec.set_used("format", format);
  FileSummary read;
  read.points = item.cloud().size();
  read.faces = item.mesh.triangles.size();
  read.dropped_nonfinite = dropped;
  read.encoding = encoding;
  read.normals = item.cloud().has_normals();
  read.colors = item.cloud().has_colors();
  for (const ScalarField& f : item.cloud().fields) read.fields += (read.fields.empty() ? "" : ",") + f.name;
  rec.add_counts(read_counts(), read);
  rec.add(read_metrics(), read);
  rec.summary = fmt::format("read {}{} from {} ({})", plural(item.cloud().size(), "point"),
                            item.mesh.triangles.empty() ? "" : fmt::format(", {}", plural(item.mesh.triangles.size(), "face")), file, format);
  run.context.set(run.output, std::move(item));
}

// What the output format cannot hold, said before writing.
std::vector<std::string> lost_attributes(const std::string& path, const std::string& format, const DataItem& item) {
  std::vector<std::string> lost;
  const PointCloud& c = item.cloud();
  if (!item.mesh.triangles.empty() && !holds_faces(format)) lost.push_back(plural(item.mesh.triangles.size(), "face"));
  // Only PLY has per-face properties; a format that holds faces but no face properties loses
  // the face fields (a format without faces loses them with the faces, said above).
  const FileFormat& ff = file_format(format);
  if (!item.mesh.triangles.empty() && ff.holds_faces && !ff.holds_face_fields)
    for (const ScalarField& f : item.mesh.face_fields) lost.push_back(fmt::format("face field '{}'", f.name));
  if (!ff.holds_normals && c.has_normals()) lost.push_back("normals");
  if (!ff.holds_colors && c.has_colors()) lost.push_back("colours");
  const std::string ext = lower(std::filesystem::path(path).extension().string());
  for (const std::string& e : ff.extensions_without_field_names)
    if (ext == e && !c.fields.empty()) lost.push_back("field names (values are kept as columns)");
  if (!ff.holds_fields)
    for (const ScalarField& f : c.fields) lost.push_back(fmt::format("field '{}'", f.name));
  return lost;
}

void run_write(StageRun& run) {
  const std::string& file = run.args.text("filename");
  const DataItem& item = run.context.item(run.inputs.front());
  WriteOptions w;
  w.format = run.args.text("format");
  w.ascii = run.args.boolean("ascii");
  if (w.ascii) w.ply_encoding = PlyEncoding::Ascii;
  else if (run.args.boolean("big_endian")) w.ply_encoding = PlyEncoding::BinaryBigEndian;
  w.single_precision = run.args.boolean("float");
  w.double_precision = run.args.boolean("double");
  w.pcd_compressed = run.args.boolean("compressed");
  const std::vector<double>& offset = run.args.numbers("las_offset");
  if (offset.size() == 3) w.las_offset = Vector3d(offset[0], offset[1], offset[2]);
  if (run.args.given("las_scale")) w.las_scale = run.args.number("las_scale");
  if (run.args.given("e57_scale")) w.e57_scale = run.args.number("e57_scale");
  w.scan_poses = item.scans;
  const std::string format = w.format.empty() ? format_from_extension(file) : w.format;
  StageRecord& rec = run.record;
  rec.set_used("format", format);
  const std::vector<std::string> lost = lost_attributes(file, format, item);
  if (!lost.empty()) {
    std::string list;
    for (const std::string& l : lost) list += (list.empty() ? "" : ", ") + l;
    rec.warnings.push_back(fmt::format("{}: the {} format cannot hold: {}", file, format, list));
  }
  const WriteResult written = item.mesh.triangles.empty()
                                  ? write_point_cloud(file, item.cloud(), w)
                                  : write_mesh(file, item.mesh, w);
  for (const std::string& note : written.notes) rec.warnings.push_back(note);
  const std::size_t faces = holds_faces(format) ? item.mesh.triangles.size() : 0;
  FileSummary written_counts;
  written_counts.points = item.cloud().size();
  written_counts.faces = faces;
  written_counts.mesh_built_from = item.source;
  rec.add_counts(write_counts(), written_counts);
  if (item.is_mesh) rec.add(write_metrics(), written_counts);
  rec.summary = fmt::format("wrote {}{} to {}", plural(item.cloud().size(), "point"), faces > 0 ? fmt::format(", {}", plural(faces, "face")) : "",
                            file);
}

}  // namespace

StageSpec read_stage() {
  StageSpec s;
  s.name = "read";
  s.shape = CommandShape::Read;
  s.summary = "Read a cloud or mesh (" + format_titles() + "; format from the content)";
  s.description = "A file name at the start of a pipeline is a reader. Mesh files keep their faces.";
  s.order = 0;
  s.produces = Slot{"cloud", DataKind::Any};
  s.params = {
      P::text("filename", "", "File to read").meta("FILE"),
      P::choice("format", "", format_choices(), "Read as this format instead of detecting it from the content").meta("FORMAT"),
      P::boolean("keep_poses", !ReadOptions{}.apply_poses,
                 "E57: keep each scan in its own frame (field scan numbers them; an E57 output gets the poses back) instead of applying its pose"),
      P::text("columns", ReadOptions{}.columns,
              "Column meaning of XYZ/TXT/CSV input, e.g. x,y,z,_,i,r,g,b (_ skips a column; other names become fields)")
          .meta("SPEC"),
      P::boolean("strict", ReadOptions{}.strict, "Points with NaN/Inf coordinates are an error instead of being dropped and counted"),
      P::integer("copc_level", ReadOptions{}.copc_level, "COPC files: read the octree levels 0..N only (-1: all)").at_least(-1),
      P::numbers("bounds", {}, "Keep the points inside the box xmin,ymin,zmin,xmax,ymax,zmax (COPC: nodes outside are not decoded)")
          .meta("X0,Y0,Z0,X1,Y1,Z1")
          .unit("cloud units"),
  };
  s.results = counted(scan_counts().specs());
  append(s.results, counted(read_counts().specs()));
  append(s.results, read_metrics().specs());
  s.run = run_read;
  s.check = [](const StageArgs& a) {
    if (a.text("filename").empty()) throw key_error("filename", "missing (the file to read)");
    if (const std::size_t n = a.numbers("bounds").size(); n != 0 && n != 6)
      throw key_error("bounds", fmt::format("{} numbers given; expected 6 (xmin,ymin,zmin,xmax,ymax,zmax)", n));
  };
  return s;
}

StageSpec write_stage() {
  StageSpec s;
  s.name = "write";
  s.shape = CommandShape::Write;
  s.summary = "Write a cloud or mesh; the format follows the extension";
  s.description = "A file name after a stage is a writer; it writes the latest data (or its \"inputs\").";
  s.order = 1000;
  s.consumes = {Slot{"data", DataKind::Any}};
  const WriteOptions w;
  s.params = {
      P::text("filename", "", "File to write (" + known_extensions(" ") + ")").meta("FILE"),
      P::choice("format", w.format, format_choices(), "Write this format whatever the extension").meta("FORMAT"),
      P::boolean("ascii", w.ascii, "Write ascii PLY/PCD/STL instead of binary"),
      P::boolean("float", w.single_precision, "Write float32 positions (PLY, PCD); refused where float32 loses precision"),
      P::boolean("double", w.double_precision, "Write double PCD positions even where float32 keeps them (PCL and Open3D 0.16 read them as zeros)"),
      P::boolean("big_endian", w.ply_encoding == PlyEncoding::BinaryBigEndian, "Write binary big-endian PLY"),
      P::boolean("compressed", w.pcd_compressed, "Write PCD as binary_compressed (LZF)"),
      P::vector3("las_offset", {}, "LAS offset (default: the input LAS or LAZ file's, else near the data's minimum)").unit("cloud units"),
      P::number("las_scale", 0.0, "LAS scale, cloud units per count (default: the input LAS or LAZ file's, else 1e-4 or coarser for large extents)")
          .unit("cloud units")
          .positive()
          .meta("S"),
      P::number("e57_scale", 0.0, "E57: scaled-integer coordinates with this step (default: float64)").unit("cloud units").positive().meta("S"),
  };
  s.results = counted(write_counts().specs());
  append(s.results, write_metrics().specs());
  s.run = run_write;
  s.check = [](const StageArgs& a) {
    if (a.text("filename").empty()) throw key_error("filename", "missing (the file to write)");
    if (a.boolean("float") && a.boolean("double")) throw key_error("float", " and double: give only one");
    if (a.boolean("ascii") && a.boolean("big_endian")) throw key_error("ascii", " and big_endian: give only one (big_endian is a binary encoding)");
  };
  return s;
}

}  // namespace pointsurf::detail
