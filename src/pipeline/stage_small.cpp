// SPDX-License-Identifier: GPL-3.0-or-later
// Small stages that the registry makes cheap: crop by box, range by field value, rigid
// transform, merge.
#include <cmath>
#include <limits>

#include <Eigen/Dense>

#include "pipeline/detail/declare.h"
#include "pipeline/detail/stage_util.h"
#include "pointsurf/core/error.h"
#include "pointsurf/core/rigid_transform.h"
#include "pointsurf/io/transform_file.h"
#include "pointsurf/pipeline/context.h"

namespace pointsurf::detail {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// What crop and range report (counts).
struct Selection {
  std::size_t input = 0, kept = 0, removed = 0;
};
const ResultTable<Selection>& selection_results() {
  static const ResultTable<Selection> table = [] {
    ResultTable<Selection> t;
    t.count("input", &Selection::input, "Points read");
    t.count("kept", &Selection::kept, "Points kept");
    t.count("removed", &Selection::removed, "Points removed");
    return t;
  }();
  return table;
}

// What transform reports.
struct Moved {
  std::size_t points = 0;
  std::vector<double> translation;
  double rotation_angle_deg = 0.0;
};
const ResultTable<Moved>& moved_counts() {
  static const ResultTable<Moved> table = [] {
    ResultTable<Moved> t;
    t.count("points", &Moved::points, "Points moved");
    return t;
  }();
  return table;
}
const ResultTable<Moved>& moved_metrics() {
  static const ResultTable<Moved> table = [] {
    ResultTable<Moved> t;
    t.numbers("translation", &Moved::translation, "Translation applied (x, y, z)").with_unit("cloud units");
    t.number("rotation_angle_deg", &Moved::rotation_angle_deg, "Rotation angle applied").with_unit("degrees");
    return t;
  }();
  return table;
}

// What merge reports (counts): the points of each input, by tag, then of the result.
struct Merged {
  std::vector<std::pair<std::string, std::size_t>> inputs;
  std::size_t points = 0;
};
const ResultTable<Merged>& merged_results() {
  static const ResultTable<Merged> table = [] {
    ResultTable<Merged> t;
    t.family("points_*", ResultType::Integer,
             [](const Merged& m) {
               std::vector<std::pair<std::string, ResultValue>> out;
               for (const auto& [tag, n] : m.inputs) out.emplace_back(tag, as_count(n));
               return out;
             },
             "Points of each input (`*`: its tag)");
    t.count("points", &Merged::points, "Points of the merged cloud");
    return t;
  }();
  return table;
}

void keep_selected(StageRun& run, const std::vector<std::size_t>& kept, const std::string& what) {
  DataItem& item = run.context.item(run.output);
  const std::size_t before = item.cloud().size();
  if (kept.size() != before) {
    drop_faces(item, run.record);
    item.cloud() = item.cloud().select(kept);
  }
  run.record.add_counts(selection_results(), Selection{before, kept.size(), before - kept.size()});
  run.record.summary = fmt::format("{}: kept {} of {} {}", run.record.type, plural(kept.size(), "point"), before, what);
  if (kept.empty()) throw InputError(fmt::format("no point is left ({} of {})", what, plural(before, "point")));
}

void run_crop(StageRun& run) {
  const std::vector<double>& lo = run.args.numbers("min");
  const std::vector<double>& hi = run.args.numbers("max");
  const bool outside = run.args.boolean("outside");
  const PointCloud& c = run.context.item(run.output).cloud();
  std::vector<std::size_t> kept;
  for (std::size_t i = 0; i < c.size(); ++i) {
    const Vector3d& p = c.positions[i];
    const bool in = p.x() >= lo[0] && p.y() >= lo[1] && p.z() >= lo[2] && p.x() <= hi[0] && p.y() <= hi[1] && p.z() <= hi[2];
    if (in != outside) kept.push_back(i);
  }
  keep_selected(run, kept, outside ? "outside the box" : "inside the box");
}

void run_range(StageRun& run) {
  const std::string& name = run.args.text("field");
  const double lo = run.args.number("min"), hi = run.args.number("max");
  const PointCloud& c = run.context.item(run.output).cloud();
  const int axis = name == "x" ? 0 : name == "y" ? 1 : name == "z" ? 2 : -1;
  const ScalarField* field = axis < 0 ? c.fields.find(name) : nullptr;
  if (axis < 0 && field == nullptr) {
    std::vector<std::string> names = {"x", "y", "z"};
    for (const ScalarField& f : c.fields) names.push_back(f.name);
    std::string list;
    for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
    throw key_error("field", fmt::format("the data has no field \"{}\" (it has {})", name, list));
  }
  std::vector<std::size_t> kept;
  for (std::size_t i = 0; i < c.size(); ++i) {
    const double v = axis >= 0 ? c.positions[i][axis] : field->values[i];
    if (v >= lo && v <= hi) kept.push_back(i);
  }
  keep_selected(run, kept, fmt::format("with {} in [{}, {}]", name, format_value(lo), format_value(hi)));
}

// The matrix given inline, or read from a T.json file (what `pointsurf register` writes).
RigidTransform transform_of(const StageArgs& a) {
  if (!a.text("file").empty()) return read_transform_file(a.text("file")).transform;
  const std::vector<double>& m = a.numbers("matrix");
  Eigen::Matrix4d t;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) t(r, c) = m[std::size_t(4 * r + c)];
  return RigidTransform::from_matrix(t);
}

void run_transform(StageRun& run) {
  RigidTransform t = transform_of(run.args);
  if (run.args.boolean("invert")) t = t.inverse();
  DataItem& item = run.context.item(run.output);
  t.apply(item.cloud());
  const Vector3d shift = t.translation();
  const Moved moved{item.cloud().size(), {shift.x(), shift.y(), shift.z()}, t.angle_degrees()};
  run.record.add_counts(moved_counts(), moved);
  run.record.add(moved_metrics(), moved);
  run.record.summary = fmt::format("transform: moved {} (rotation {:.3g} degrees, translation {:.4g})", plural(item.cloud().size(), "point"),
                                   t.angle_degrees(), shift.norm());
}

void run_merge(StageRun& run) {
  PointCloud merged;
  std::size_t faces = 0;
  Merged counts;
  for (const std::string& tag : run.inputs) {
    const DataItem& item = run.context.item(tag);
    faces += item.mesh.triangles.size();
    merged.append(item.cloud());
    counts.inputs.emplace_back(tag, item.cloud().size());
  }
  if (faces > 0) run.record.warnings.push_back(fmt::format("merge works on points: {} dropped", plural(faces, "face")));
  counts.points = merged.size();
  run.record.add_counts(merged_results(), counts);
  run.record.summary = fmt::format("merge: {} from {} inputs", plural(merged.size(), "point"), run.inputs.size());
  run.context.set_cloud(run.output, std::move(merged), run.inputs.front());
}

}  // namespace

StageSpec crop_stage() {
  StageSpec s;
  s.name = "crop";
  s.summary = "Keep the points inside (or outside) an axis-aligned box";
  s.order = 10;
  s.consumes = {Slot{"cloud", DataKind::Any}};
  s.produces = Slot{"cloud", DataKind::Cloud};
  s.params = {P::vector3("min", {-kInf, -kInf, -kInf}, "Box corner with the smallest coordinates (bounds included)").unit("cloud units"),
              P::vector3("max", {kInf, kInf, kInf}, "Box corner with the largest coordinates (bounds included)").unit("cloud units"),
              P::boolean("outside", false, "Keep the points outside the box instead")};
  s.examples = {"pointsurf crop data/b9_training.ply part.ply --min 596680,243650,0 --max 596710,243700,100"};
  s.results = counted(selection_results().specs());
  s.run = run_crop;
  s.check = [](const StageArgs& a) {
    const auto& lo = a.numbers("min");
    const auto& hi = a.numbers("max");
    for (int i = 0; i < 3; ++i)
      if (lo[std::size_t(i)] > hi[std::size_t(i)])
        throw key_error("min", fmt::format(", max: min {} exceeds max {} along {}", format_value(lo[std::size_t(i)]), format_value(hi[std::size_t(i)]),
                                     "xyz"[i]));
  };
  return s;
}

StageSpec range_stage() {
  StageSpec s;
  s.name = "range";
  s.summary = "Keep the points whose field (or x, y, z) lies in [min, max]";
  s.order = 11;
  s.consumes = {Slot{"cloud", DataKind::Any}};
  s.produces = Slot{"cloud", DataKind::Cloud};
  s.params = {P::text("field", "z", "Field to test: x, y, z or a scalar field of the input (classification, intensity, ...)").meta("NAME"),
              P::number("min", -kInf, "Smallest value kept (included)"),
              P::number("max", kInf, "Largest value kept (included)")};
  s.examples = {"pointsurf range data/b9_training.ply label2.ply --field label --min 2 --max 2"};
  s.results = counted(selection_results().specs());
  s.run = run_range;
  s.check = [](const StageArgs& a) {
    if (a.number("min") > a.number("max"))
      throw key_error("min", fmt::format(" {} exceeds max {}", format_value(a.number("min")), format_value(a.number("max"))));
  };
  return s;
}

StageSpec transform_stage() {
  StageSpec s;
  s.name = "transform";
  s.summary = "Apply a rigid 4x4 transform (rotation and translation) to points and normals";
  s.order = 12;
  s.consumes = {Slot{"cloud", DataKind::Any}};
  s.produces = Slot{"cloud", DataKind::Any};
  s.params = {P::numbers("matrix", {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1},
                         "16 numbers, row by row: [R t; 0 0 0 1] with R a rotation (orthonormal, det +1)")
                  .meta("M11,...,M44"),
              P::text("file", "", "Read the matrix from a T.json file (as `pointsurf register --out` writes it) instead of --matrix")
                  .meta("T.json"),
              P::boolean("invert", false, "Apply the inverse transform (a T.json maps the source onto the target: this maps back)")};
  s.examples = {"pointsurf transform data/kitten.xyz moved.ply --matrix 1,0,0,10,0,1,0,0,0,0,1,0,0,0,0,1",
                "pointsurf transform moved.ply back.ply --matrix 1,0,0,10,0,1,0,0,0,0,1,0,0,0,0,1 --invert"};
  s.results = counted(moved_counts().specs());
  append(s.results, moved_metrics().specs());
  s.run = run_transform;
  s.check = [](const StageArgs& a) {
    if (a.given("matrix") && !a.text("file").empty()) throw key_error("matrix", ", file: give one of them, not both");
    const auto& m = a.numbers("matrix");
    if (m.size() != 16) throw key_error("matrix", fmt::format("expected 16 numbers (4x4, row by row), got {}", m.size()));
    Eigen::Matrix3d r;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) r(i, j) = m[std::size_t(4 * i + j)];
    const double err = (r * r.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    if (err > 1e-6 || r.determinant() < 0.0)
      throw key_error("matrix", "the upper-left 3x3 block is not a rotation (orthonormal with determinant +1): the transform must be rigid");
    if (m[12] != 0.0 || m[13] != 0.0 || m[14] != 0.0 || m[15] != 1.0) throw key_error("matrix", "the last row must be 0,0,0,1");
  };
  return s;
}

StageSpec merge_stage() {
  StageSpec s;
  s.name = "merge";
  s.shape = CommandShape::Merge;
  s.summary = "Merge several clouds into one (attributes present in only some are zero-filled)";
  s.order = 13;
  s.consumes = {Slot{"clouds", DataKind::Any}};
  s.produces = Slot{"cloud", DataKind::Cloud};
  s.examples = {"pointsurf merge data/kitten.xyz data/b9_training.ply both.ply"};
  s.results = counted(merged_results().specs());
  s.run = run_merge;
  return s;
}

}  // namespace pointsurf::detail
