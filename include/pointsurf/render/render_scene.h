// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// Headless pictures of clouds and meshes: a software rasterizer (no display, no GPU) with a
// z-buffer, supersampling anti-aliasing, Blinn-Phong lighting of meshes (smooth or flat, with
// an optional wireframe), point splats shaded by eye-dome lighting, colour by RGB or by a field
// through a colour map with its legend, and auto-framed views. Rendered about the centre of
// the data's bounding box in double precision, so coordinates of 1e6 m draw as at the origin.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "pointsurf/core/fields.h"
#include "pointsurf/core/point_cloud.h"
#include "pointsurf/core/results.h"
#include "pointsurf/core/triangle_mesh.h"
#include "pointsurf/render/colormap.h"
#include "pointsurf/render/image.h"

namespace pointsurf {

/// Auto-framed views, looking at the centre, z up: front looks along +y, side along -x, top
/// down -z (y up on the picture), iso from (+1, -1, +1). All orthographic.
enum class View { Front, Side, Top, Iso };

/// "front", "side", "top", "iso".
const EnumNames<View>& view_names();

/// A picture's size in pixels, "WxH" as text (1024x768).
struct PictureSize {
  int width = 1024, height = 768;
  friend bool operator==(const PictureSize&, const PictureSize&) = default;
};
/// "1024x768".
std::string picture_size_text(const PictureSize& size);
/// Parses "WxH"; throws UsageError "size: ..." for another form or a size outside 8x8 .. 16384x16384.
PictureSize parse_picture_size(std::string_view text);

/// A given camera: perspective with a vertical field of view, or orthographic showing
/// `ortho_height` cloud units vertically when fov_deg is 0.
struct Camera {
  Vector3d eye = Vector3d(0, -10, 0), target = Vector3d::Zero(), up = Vector3d::UnitZ();  // cloud units
  double fov_deg = 40.0;       // vertical field of view, degrees; 0: orthographic
  double ortho_height = 1.0;   // cloud units shown top to bottom when orthographic
};

struct RenderParams {
  PictureSize size;                    // pixels, 8 .. 16384 each way
  View view = View::Iso;
  std::optional<Camera> camera;        // given: used instead of `view`
  int supersample = 3;                 // samples per pixel along each axis (1: no anti-aliasing)
  std::string field;                   // colour by this field ("" : RGB if present, else plain)
  std::optional<ColorScale> scale;     // for `field`; default: default_color_scale
  bool legend = true;                  // draw the colour bar with its values (field only)
  std::string title;                   // text at the top left ("" : none)
  bool flat_shading = false;           // meshes: one normal per face instead of smooth
  bool wireframe = false;              // meshes: draw the edges over the shading
  double point_size_px = 0.0;          // splat diameter, pixels; 0: from the projected density
  bool eye_dome = true;                // shade splats by eye-dome lighting (depth edges darken)
  double margin = 0.06;                // share of the picture left around the framed data
  std::string font_file = "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf";  // labels (FreeType)
  /// Key, unit, range and doc of each field (core/fields.h). camera and scale are internal (the
  /// render stage builds them from its own eye, target, up, fov_deg, range, tolerance, unit).
  static const FieldTable<RenderParams>& fields();
  /// Throws UsageError naming the first value out of range (size, supersample outside 1..4...).
  void validate() const;
};

struct RenderResult {
  Image image;
  ColorScale scale;              // the scale used (meaningful when colouring by a field)
  std::size_t points_drawn = 0;  // splats
  std::size_t triangles_drawn = 0;
  double pixels_per_unit = 0.0;  // orthographic views: picture pixels per cloud unit
  std::vector<std::string> warnings;  // e.g. the font could not be loaded: no labels

  /// The reported members (core/results.h): what was drawn; with `by_field` (coloured by a
  /// field) the colour scale after it.
  static const ResultTable<RenderResult>& results(bool by_field = false);
};

/// Renders `cloud` as points, or, when `triangles` is not empty, the mesh whose vertices (and
/// their normals, colours, fields) are the cloud. Throws InputError for an empty cloud, an
/// unknown field (naming the fields it has), an index out of range or a non-finite position;
/// UsageError for parameters out of range (RenderParams::validate) or a degenerate camera. Parallel over bands of rows (oneTBB); thread-safe.
RenderResult render_scene(const PointCloud& cloud, const std::vector<Triangle>& triangles, const RenderParams& params = {});

}  // namespace pointsurf
