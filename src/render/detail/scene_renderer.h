// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
// render_scene as a phase object: the software rasterizer's shared state (framing, layout,
// projection, sample buffers) held as named members, so each phase can be run and checked alone.
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "pointsurf/core/point_cloud.h"
#include "pointsurf/render/render_scene.h"
#include "render/detail/text.h"

namespace pointsurf::detail {

inline constexpr float kNoDepth = std::numeric_limits<float>::infinity();
inline constexpr int kBandRows = 32;  // sample rows per band: a few dozen bands keep two to 64 cores busy

struct Basis {
  Vector3d right, up, forward;  // forward: from the eye into the scene
};

// Projection from centred coordinates to sample coordinates (x right, y down) and depth.
struct Projection {
  Basis basis;
  Vector3d eye = Vector3d::Zero();  // perspective: eye relative to the centre
  bool perspective = false;
  double scale = 1.0;               // orthographic: samples per unit; perspective: focal length in samples
  double cx = 0.0, cy = 0.0;        // sample coordinates of the optical axis
  double near = 0.0;                // perspective: nearer points are not drawn

  // x, y in samples; z: distance along the view direction (ortho: from the centre plane).
  Eigen::Vector3f operator()(const Vector3d& q) const {
    const Vector3d d = perspective ? Vector3d(q - eye) : q;
    const double x = d.dot(basis.right), y = d.dot(basis.up), z = d.dot(basis.forward);
    if (perspective) {
      if (z <= near) return {0.f, 0.f, kNoDepth};
      return {float(cx + scale * x / z), float(cy - scale * y / z), float(z)};
    }
    return {float(cx + scale * x), float(cy - scale * y), float(z)};
  }
};

struct Layout {
  int plot_x0 = 0, plot_y0 = 0, plot_w = 0, plot_h = 0;  // picture pixels for the data
  int legend_x = 0;                                       // left edge of the legend column
};

// The supersampled depth and colour buffers.
struct Buffers {
  int w = 0, h = 0;
  std::vector<float> depth;
  std::vector<std::uint32_t> color;  // packed RGB, meaningful where depth is set
  Buffers() = default;
  Buffers(int width, int height) : w(width), h(height), depth(std::size_t(width) * std::size_t(height), kNoDepth), color(depth.size()) {}
  std::size_t index(int x, int y) const { return std::size_t(y) * std::size_t(w) + std::size_t(x); }
};

// A sample's colour packed in 4 bytes (R, G, B; 8 bits each): a quarter of three floats, which
// at 9 samples per pixel is most of the renderer's memory and of its fixed cost.
inline std::uint32_t pack(const Eigen::Vector3f& c) {
  auto q = [](float v) { return std::uint32_t(std::clamp(v + 0.5f, 0.f, 255.f)); };
  return q(c.x()) | q(c.y()) << 8 | q(c.z()) << 16;
}
inline Eigen::Vector3f unpack(std::uint32_t c) { return Eigen::Vector3f(float(c & 255u), float((c >> 8) & 255u), float((c >> 16) & 255u)); }

struct Lights {
  Eigen::Vector3f key, fill, half;  // camera space: x right, y up, z towards the viewer
};

// Renders a cloud (splats) or a mesh whose vertices are the cloud. The phases run in the order
// they are declared, the mesh's or the cloud's branch between project_vertices and downsample;
// each reads the members named in its comment.
class SceneRenderer {
public:
  /// Checks the inputs (non-empty cloud, parameters, face indices); throws InputError or UsageError.
  SceneRenderer(const PointCloud& cloud, const std::vector<Triangle>& triangles, const RenderParams& params);

  /// Reads params.field; produces field (the values, x/y/z included) and result.scale.
  void select_field();
  /// Reads the positions (a mesh: its used vertices); produces used, centre and diagonal.
  void frame_box();
  /// Reads params (size, title, legend) and result.scale; produces text, legend, title_h and layout.
  void lay_out();
  /// Reads layout, centre and params (camera or view); produces projection and result.pixels_per_unit.
  void choose_projection();
  /// Reads projection and field; produces screen (per vertex), colors, buf and bands.
  void project_vertices();
  /// Mesh. Reads the faces; produces normals in camera space (per face when flat, else per vertex).
  void compute_normals();
  /// Mesh. Reads screen, colors and normals; rasterizes the faces into buf, counts triangles_drawn.
  void raster_mesh();
  /// Cloud. Reads screen (the projected density) or params.point_size_px; produces radius (samples).
  void size_splats();
  /// Cloud. Reads the cloud's normals; produces light (per point shading factor; empty without normals).
  void light_points();
  /// Cloud. Reads screen, colors, light and radius; rasterizes the splats into buf, counts points_drawn.
  void raster_points();
  /// Cloud. Reads buf's depths; darkens its colours by eye-dome lighting.
  void apply_eye_dome();
  /// Reads buf; produces image, the mean of each pixel's samples over the background.
  void downsample();
  /// Reads image, layout and result.pixels_per_unit; draws the legend, title and scale bar.
  void annotate();
  /// The picture and what was drawn.
  RenderResult result() &&;

  const PointCloud& cloud;
  const std::vector<Triangle>& triangles;
  const RenderParams& params;
  const bool mesh;     // triangles given
  const std::size_t n; // vertices
  const int s;         // supersampling: samples per pixel along each axis

  RenderResult out;                       // scale, counts, pixels_per_unit, warnings; image at the end
  std::vector<double> axis_values;        // select_field: x, y or z
  const std::vector<double>* field = nullptr;
  std::vector<char> used;                 // frame_box: a mesh's vertices in a face
  Vector3d centre = Vector3d::Zero();
  double diagonal = 0.0;
  std::optional<TextPainter> text;        // lay_out
  bool legend = false;
  int title_h = 0;
  Layout layout;
  Projection projection;                  // choose_projection
  ColorScale scale;                       // project_vertices: result's scale, as used
  std::vector<Eigen::Vector3f> screen;    //   per vertex: x, y (samples), z (depth)
  std::vector<Eigen::Vector3f> colors;    //   per vertex, 0..255
  Buffers buf;
  int bands = 0;
  Lights lights;
  std::vector<Eigen::Vector3f> normals;   // compute_normals
  float radius = 1.f;                     // size_splats
  std::vector<float> light;               // light_points
  Image image;                            // downsample

private:
  void aim_camera(const Camera& c);
  void frame_view();
  std::vector<std::array<std::int32_t, 2>> triangle_rows() const;
  std::vector<std::array<std::int32_t, 2>> splat_rows() const;
  Eigen::Vector3f to_camera(const Vector3d& v) const;
};

}  // namespace pointsurf::detail
