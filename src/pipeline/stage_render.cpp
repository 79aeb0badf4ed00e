// SPDX-License-Identifier: GPL-3.0-or-later
// The render stage: a PNG picture of a cloud or mesh (pointsurf/render/render_scene.h).
#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>

#include "pipeline/detail/declare.h"
#include "pipeline/detail/stage_util.h"
#include "pointsurf/core/error.h"
#include "pointsurf/io/formats.h"
#include "pointsurf/pipeline/context.h"
#include "pointsurf/render/render_scene.h"

namespace pointsurf::detail {
namespace {

// What render reports besides RenderResult: the file written.
struct Picture {
  std::size_t png_bytes = 0;
  std::string image;
};
const ResultTable<Picture>& picture_counts() {
  static const ResultTable<Picture> table = [] {
    ResultTable<Picture> t;
    t.count("png_bytes", &Picture::png_bytes, "Size of the PNG file").with_unit("bytes");
    return t;
  }();
  return table;
}
const ResultTable<Picture>& picture_metrics() {
  static const ResultTable<Picture> table = [] {
    ResultTable<Picture> t;
    t.text("image", &Picture::image, "The PNG file written");
    return t;
  }();
  return table;
}
std::vector<ResultSpec> render_specs() {
  std::vector<ResultSpec> out = RenderResult::results(true).specs();
  append(out, counted(picture_counts().specs()));
  append(out, picture_metrics().specs());
  return out;
}

void run_render(StageRun& run) {
  const StageArgs& a = run.args;
  const DataItem& item = run.context.item(run.inputs.front());
  RenderParams p = read_params<RenderParams>(a);
  const std::vector<double>& eye = a.numbers("eye");
  if (eye.size() == 3) {
    Camera c;
    c.eye = Vector3d(eye[0], eye[1], eye[2]);
    const std::vector<double>& target = a.numbers("target");
    if (target.size() == 3) c.target = Vector3d(target[0], target[1], target[2]);
    else c.target = bounding_box(item.cloud().positions).center();
    const std::vector<double>& up = a.numbers("up");
    c.up = Vector3d(up[0], up[1], up[2]);
    c.fov_deg = a.number("fov_deg");
    c.ortho_height = (c.target - c.eye).norm();
    p.camera = c;
  }
  // After evaluate: its field and tolerance unless given.
  const std::optional<MeasuredField>& measured = item.measured;
  if (measured && !a.given("field") && item.cloud().fields.contains(measured->field)) p.field = measured->field;
  const double tolerance = a.given("tolerance") || !measured || p.field != measured->field ? a.number("tolerance") : measured->tolerance;
  if (!p.field.empty()) {
    const ScalarField* f = item.cloud().fields.find(p.field);
    std::vector<double> axis;
    if (f == nullptr && (p.field == "x" || p.field == "y" || p.field == "z"))
      for (const Vector3d& q : item.cloud().positions) axis.push_back(q[p.field[0] - 'x']);
    if (f != nullptr || !axis.empty()) {
      ColorScale s =
          default_color_scale(f ? std::span<const double>(f->values) : std::span<const double>(axis), p.field, a.boolean("diverging"), tolerance);
      const std::vector<double>& range = a.numbers("range");
      if (range.size() == 2) {
        s.min = range[0];
        s.max = range[1];
      }
      s.unit = a.text("unit");
      p.scale = s;
    }
  }
  RenderResult r = render_scene(item.cloud(), item.mesh.triangles, p);
  const std::string& file = a.text("filename");
  const std::vector<std::uint8_t> png = encode_png(r.image);
  write_file_atomically(file, std::string_view(reinterpret_cast<const char*>(png.data()), png.size()));
  for (const std::string& w : r.warnings) run.record.warnings.push_back(w);
  const Picture picture{png.size(), file};
  run.record.add(RenderResult::results(!p.field.empty()), r);
  run.record.add_counts(picture_counts(), picture);
  run.record.add(picture_metrics(), picture);
  run.record.summary = fmt::format("render: {} view of {} to {} ({}x{})", p.camera ? "camera" : a.text("view"),
                                   item.mesh.triangles.empty() ? plural(item.cloud().size(), "point") : plural(item.mesh.triangles.size(), "triangle"),
                                   file, p.size.width, p.size.height);
}

}  // namespace

StageSpec render_stage() {
  const Camera c;
  StageSpec s;
  s.name = "render";
  s.shape = CommandShape::Picture;
  s.summary = "Draw a PNG picture of a cloud or mesh: shaded, coloured by a field with its legend, auto-framed views";
  s.description = "A software rasterizer (no display or GPU): z-buffer, supersampled anti-aliasing, Blinn-Phong lighting of meshes, "
                  "point splats with eye-dome lighting. A field named deviation or distance* gets a diverging map symmetric about 0, clipped "
                  "at the 99th percentile of |value| (at least twice the tolerance), with the values beyond it in over- and "
                  "under-range colours; others viridis between their 1st and 99th percentiles. After evaluate in a pipeline it "
                  "colours by evaluate's deviation and tolerance unless field or tolerance are given. In a pipeline it writes its file "
                  "and passes its input on.";
  s.order = 140;
  s.consumes = {Slot{"data", DataKind::Any}};
  s.writes_param = "filename";
  s.params = {P::text("filename", "", "PNG file to write").meta("FILE")};
  append(s.params, params_of(RenderParams::fields()));
  s.params.push_back(P::boolean("diverging", false, "Use the diverging (blue-white-red) map for any field"));
  s.params.push_back(P::numbers("range", {}, "Colour map range MIN,MAX (default from the data)").meta("MIN,MAX"));
  s.params.push_back(
      P::number("tolerance", ColorScale{}.tolerance, "Diverging map: values within +-tolerance are green (0: no band)").unit("field units").non_negative());
  s.params.push_back(P::text("unit", "", "Unit shown on the legend").meta("UNIT"));
  s.params.push_back(P::vector3("eye", {}, "Camera position: a perspective view instead of the auto-framed one").unit("cloud units"));
  s.params.push_back(P::vector3("target", {}, "Point the camera looks at (default the data's centre)").unit("cloud units"));
  s.params.push_back(P::vector3("up", as_list(c.up), "Camera up direction"));
  s.params.push_back(P::number("fov_deg", c.fov_deg, "Vertical field of view of the camera; 0: orthographic, as high as the eye is far from the target")
                         .unit("degrees")
                         .range(0, 179, false, true));
  s.examples = {"pointsurf reconstruct data/kitten.xyz mesh.ply", "pointsurf render mesh.ply mesh.png --view front --size 1600x1200",
                "pointsurf evaluate mesh.ply --reference data/kitten.xyz --out deviation.ply",
                "pointsurf render deviation.ply dev.png --field deviation --tolerance 0.001 --unit m"};
  s.results = render_specs();
  s.run = run_render;
  s.check = [](const StageArgs& a) {
    const std::string& file = a.text("filename");
    if (file.empty()) throw key_error("filename", "missing (the PNG file to write)");
    std::string ext = std::filesystem::path(file).extension().string();
    std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    if (ext != ".png") throw key_error("filename", fmt::format("{}: expected a .png file name", file));
    parse_picture_size(a.text("size"));
    if (a.numbers("range").size() != 0 && a.numbers("range").size() != 2)
      throw key_error("range", fmt::format("expected MIN,MAX, got {} numbers", a.numbers("range").size()));
    if (a.numbers("range").size() == 2 && !(a.numbers("range")[0] < a.numbers("range")[1]))
      throw key_error("range", "MIN must be below MAX");
    if (a.numbers("target").size() == 3 && a.numbers("eye").size() != 3) throw key_error("target", "give eye too (the camera position)");
  };
  return s;
}

}  // namespace pointsurf::detail
