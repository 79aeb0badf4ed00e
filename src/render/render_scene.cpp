// SPDX-License-Identifier: GPL-3.0-or-later
// The software rasterizer. Why not OpenGL through Mesa: a rasterizer of our own needs no
// driver, gives the same picture on every machine (the tests compare pixels), and measured
// faster than llvmpipe's start-up alone for one picture (docs/render.md).
//
// Shape: positions are moved to the centre of the bounding box in double, then projected to
// float sample coordinates of a supersampled buffer (supersample^2 samples per pixel). The
// primitives are binned into bands of sample rows; oneTBB rasterizes the bands in parallel, each
// with its own rows of the depth and colour buffers, so no two threads touch one sample.
// Triangles are rasterized with edge functions and shaded forward (Blinn-Phong, two-sided);
// points are depth-tested discs, darkened afterwards by eye-dome lighting (Boucheny 2009),
// which shows shape from depth alone. The buffer is box-filtered down to the picture, and the
// legend and labels are drawn on it through FreeType.
#include "pointsurf/render/render_scene.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <regex>
#include <string>

#include <Eigen/Geometry>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "pointsurf/core/error.h"
#include "render/detail/scene_renderer.h"
#include "render/detail/text.h"

namespace pointsurf {

const EnumNames<View>& view_names() {
  static const EnumNames<View> names{{{View::Front, "front"}, {View::Side, "side"}, {View::Top, "top"}, {View::Iso, "iso"}}};
  return names;
}

std::string picture_size_text(const PictureSize& size) { return fmt::format("{}x{}", size.width, size.height); }

PictureSize parse_picture_size(std::string_view text) {
  static const std::regex form(R"(^(\d{1,5})x(\d{1,5})$)");
  const std::string t(text);
  std::smatch m;
  if (!std::regex_match(t, m, form)) throw key_error("size", fmt::format("\"{}\" is not WIDTHxHEIGHT (e.g. 1024x768)", t));
  const PictureSize size{std::stoi(m[1].str()), std::stoi(m[2].str())};
  if (size.width < 8 || size.height < 8 || size.width > 16384 || size.height > 16384)
    throw key_error("size", fmt::format("{} is outside 8x8 .. 16384x16384", t));
  return size;
}

const FieldTable<RenderParams>& RenderParams::fields() {
  static const FieldTable<RenderParams> table = [] {
    using P = RenderParams;
    FieldTable<P> t;
    t.custom<PictureSize>(
         "size", &P::size, ParamType::String, "Picture size in pixels",
         [](const PictureSize& s) { return ParamValue(picture_size_text(s)); },
         [](PictureSize& s, const ParamValue& v) { s = parse_picture_size(std::get<std::string>(v)); })
        .meta("WxH");
    t.choice("view", &P::view, view_names(), "Auto-framed orthographic view (z up): front, side, top or iso");
    t.text("field", &P::field, "Colour by this field (or x, y, z); default RGB when present, else plain").meta("NAME");
    t.boolean("legend", &P::legend, "Draw the colour bar with its values");
    t.text("title", &P::title, "Text at the top left");
    t.boolean("flat", &P::flat_shading, "Meshes: flat shading (one normal per face)");
    t.boolean("wireframe", &P::wireframe, "Meshes: draw the edges");
    t.number("point_size", &P::point_size_px, "Splat diameter; 0: from the projected density").unit("pixels").non_negative();
    t.boolean("eye_dome", &P::eye_dome, "Shade splats by eye-dome lighting");
    t.integer("supersample", &P::supersample, "Samples per pixel along each axis (anti-aliasing)").range(1, 4);
    // Built by the caller (the render stage: from eye, target, up, fov_deg; range, tolerance, unit).
    t.custom<std::optional<Camera>>(
         "camera", &P::camera, ParamType::String, "A given camera, used instead of view",
         [](const std::optional<Camera>& c) { return ParamValue(std::string(c ? "given" : "")); },
         [](std::optional<Camera>& c, const ParamValue& v) {
           if (std::get<std::string>(v).empty()) c.reset();
         })
        .internal();
    t.custom<std::optional<ColorScale>>(
         "scale", &P::scale, ParamType::String, "The field's colour scale; default: default_color_scale",
         [](const std::optional<ColorScale>& s) { return ParamValue(std::string(s ? "given" : "")); },
         [](std::optional<ColorScale>& s, const ParamValue& v) {
           if (std::get<std::string>(v).empty()) s.reset();
         })
        .internal();
    t.number("margin", &P::margin, "Share of the picture left around the framed data").range(0.0, 0.5, false, true).internal();
    t.text("font_file", &P::font_file, "Font of the labels (FreeType)").meta("FILE").internal();
    return t;
  }();
  return table;
}

void RenderParams::validate() const {
  if (size.width < 8 || size.height < 8 || size.width > 16384 || size.height > 16384)
    throw UsageError(fmt::format("render_scene: size: {} is outside 8x8 .. 16384x16384", picture_size_text(size)));
  fields().validate(*this, "render_scene");
}

namespace {

using Rgb = std::array<std::uint8_t, 3>;
using detail::Basis;
using detail::Buffers;
using detail::kBandRows;
using detail::kNoDepth;
using detail::Layout;
using detail::Lights;
using detail::pack;
using detail::Projection;
using detail::unpack;

Basis basis_of(const Vector3d& forward_in, const Vector3d& up_in) {
  Basis b;
  b.forward = forward_in.normalized();
  b.right = b.forward.cross(up_in);
  if (b.right.norm() < 1e-9) throw key_error("camera", "the up vector is parallel to the viewing direction");
  b.right.normalize();
  b.up = b.right.cross(b.forward);
  return b;
}

Basis view_basis(View v) {
  switch (v) {
    case View::Front: return basis_of(Vector3d(0, 1, 0), Vector3d::UnitZ());
    case View::Side: return basis_of(Vector3d(-1, 0, 0), Vector3d::UnitZ());
    case View::Top: return basis_of(Vector3d(0, 0, -1), Vector3d::UnitY());
    case View::Iso: return basis_of(Vector3d(-1, 1, -1), Vector3d::UnitZ());
  }
  return basis_of(Vector3d(-1, 1, -1), Vector3d::UnitZ());
}

// Per-vertex colour (0..255, as float for interpolation).
std::vector<Eigen::Vector3f> vertex_colors(const PointCloud& cloud, const RenderParams& p, bool mesh, ColorScale& scale,
                                           const std::vector<double>* field) {
  std::vector<Eigen::Vector3f> out(cloud.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cloud.size(), 65536), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      if (field) {
        const Rgb c = scale.color((*field)[i]);
        out[i] = Eigen::Vector3f(c[0], c[1], c[2]);
      } else if (cloud.has_colors()) {
        out[i] = cloud.colors[i].cwiseMax(0.f).cwiseMin(1.f) * 255.f;
      } else {
        out[i] = mesh ? Eigen::Vector3f(190, 196, 206) : Eigen::Vector3f(70, 110, 170);
      }
    }
  });
  (void)p;
  return out;
}

Lights make_lights() {
  Lights l;
  l.key = Eigen::Vector3f(-0.35f, 0.55f, 0.76f).normalized();
  l.fill = Eigen::Vector3f(0.6f, -0.2f, 0.5f).normalized();
  l.half = (l.key + Eigen::Vector3f(0, 0, 1)).normalized();
  return l;
}

// Blinn-Phong, two-sided: a face seen from behind is lit as if turned towards the viewer.
inline Eigen::Vector3f shade(Eigen::Vector3f n, const Eigen::Vector3f& base, const Lights& l) {
  const float len = n.norm();
  if (len > 0.f) n /= len;
  if (n.z() < 0.f) n = -n;
  const float diffuse = std::max(0.f, n.dot(l.key));
  const float fill = std::max(0.f, n.dot(l.fill));
  // The specular term's power 40 by squaring (x^32 x^8): std::pow per sample was a third of the time.
  const float h1 = std::max(0.f, n.dot(l.half)), h2 = h1 * h1, h4 = h2 * h2, h8 = h4 * h4, h32 = h8 * h8 * h8 * h8;
  const float spec = h32 * h8;
  Eigen::Vector3f c = base * (0.22f + 0.68f * diffuse + 0.18f * fill) + Eigen::Vector3f::Constant(70.f * spec);
  return c.cwiseMin(255.f);
}

// Bins primitive i into the bands its rows [lo, hi] span.
struct Bins {
  std::vector<std::uint32_t> start, items;
};

Bins bin_by_rows(std::size_t count, int bands, const std::vector<std::array<std::int32_t, 2>>& rows) {
  Bins b;
  b.start.assign(std::size_t(bands) + 1, 0);
  for (std::size_t i = 0; i < count; ++i)
    if (rows[i][0] <= rows[i][1])
      for (int k = rows[i][0] / kBandRows; k <= rows[i][1] / kBandRows; ++k) ++b.start[std::size_t(k) + 1];
  for (int k = 0; k < bands; ++k) b.start[std::size_t(k) + 1] += b.start[std::size_t(k)];
  b.items.resize(b.start.back());
  std::vector<std::uint32_t> fill(b.start.begin(), b.start.end() - 1);
  for (std::size_t i = 0; i < count; ++i)
    if (rows[i][0] <= rows[i][1])
      for (int k = rows[i][0] / kBandRows; k <= rows[i][1] / kBandRows; ++k) b.items[fill[std::size_t(k)]++] = std::uint32_t(i);
  return b;
}

struct MeshInputs {
  const std::vector<Triangle>* triangles;
  const std::vector<Eigen::Vector3f>* screen;   // per vertex: x, y (samples), z (depth)
  const std::vector<Eigen::Vector3f>* colors;   // per vertex, 0..255
  const std::vector<Eigen::Vector3f>* normals;  // per vertex (smooth) or per face (flat), camera space
  bool flat = false, perspective = false, wireframe = false;
  float line_half_width = 1.f;  // samples
};

void raster_triangles_band(const MeshInputs& in, const Bins& bins, int band, Buffers& buf, const Lights& lights) {
  const int y_lo = band * kBandRows, y_hi = std::min(buf.h, y_lo + kBandRows) - 1;
  const auto& scr = *in.screen;
  for (std::uint32_t b = bins.start[std::size_t(band)]; b < bins.start[std::size_t(band) + 1]; ++b) {
    const std::uint32_t t = bins.items[b];
    const Triangle& tri = (*in.triangles)[t];
    const Eigen::Vector3f& a = scr[std::size_t(tri[0])];
    const Eigen::Vector3f& bb = scr[std::size_t(tri[1])];
    const Eigen::Vector3f& c = scr[std::size_t(tri[2])];
    const float area = (bb.x() - a.x()) * (c.y() - a.y()) - (bb.y() - a.y()) * (c.x() - a.x());
    if (!(std::abs(area) > 1e-12f)) continue;  // edge-on or degenerate: covers no sample
    const int x0 = std::max(0, int(std::floor(std::min({a.x(), bb.x(), c.x()}))));
    const int x1 = std::min(buf.w - 1, int(std::ceil(std::max({a.x(), bb.x(), c.x()}))));
    const int r0 = std::max(y_lo, int(std::floor(std::min({a.y(), bb.y(), c.y()}))));
    const int r1 = std::min(y_hi, int(std::ceil(std::max({a.y(), bb.y(), c.y()}))));
    const float inv_area = 1.f / area;
    // Edge functions w0 (opposite a), w1 (opposite b), w2 (opposite c), stepped along x.
    const float e0x = bb.y() - c.y(), e1x = c.y() - a.y(), e2x = a.y() - bb.y();
    const float len0 = std::hypot(c.x() - bb.x(), c.y() - bb.y()), len1 = std::hypot(a.x() - c.x(), a.y() - c.y()),
                len2 = std::hypot(bb.x() - a.x(), bb.y() - a.y());
    const Eigen::Vector3f& ca = (*in.colors)[std::size_t(tri[0])];
    const Eigen::Vector3f& cb = (*in.colors)[std::size_t(tri[1])];
    const Eigen::Vector3f& cc = (*in.colors)[std::size_t(tri[2])];
    const bool uniform = ca == cb && cb == cc;
    Eigen::Vector3f face_color = ca;
    if (in.flat) face_color = shade((*in.normals)[t], ca, lights);
    for (int y = r0; y <= r1; ++y) {
      const float py = float(y) + 0.5f;
      const float px0 = float(x0) + 0.5f;
      float w0 = ((c.x() - bb.x()) * (py - bb.y()) - (c.y() - bb.y()) * (px0 - bb.x()));
      float w1 = ((a.x() - c.x()) * (py - c.y()) - (a.y() - c.y()) * (px0 - c.x()));
      float w2 = ((bb.x() - a.x()) * (py - a.y()) - (bb.y() - a.y()) * (px0 - a.x()));
      // d(w)/dx of each edge function is minus the y difference of its edge.
      for (int x = x0; x <= x1; ++x, w0 += e0x, w1 += e1x, w2 += e2x) {
        const float l0 = w0 * inv_area, l1 = w1 * inv_area, l2 = w2 * inv_area;
        if (l0 < 0.f || l1 < 0.f || l2 < 0.f) continue;
        float z, k0 = l0, k1 = l1, k2 = l2;
        if (in.perspective) {
          const float q0 = l0 / a.z(), q1 = l1 / bb.z(), q2 = l2 / c.z();
          z = 1.f / (q0 + q1 + q2);
          k0 = q0 * z;
          k1 = q1 * z;
          k2 = q2 * z;
        } else {
          z = l0 * a.z() + l1 * bb.z() + l2 * c.z();
        }
        const std::size_t i = buf.index(x, y);
        if (!(z < buf.depth[i])) continue;
        buf.depth[i] = z;
        Eigen::Vector3f col;
        if (in.flat) {
          col = uniform ? face_color : shade((*in.normals)[t], k0 * ca + k1 * cb + k2 * cc, lights);
        } else {
          const auto& n = *in.normals;
          const Eigen::Vector3f nn = k0 * n[std::size_t(tri[0])] + k1 * n[std::size_t(tri[1])] + k2 * n[std::size_t(tri[2])];
          col = shade(nn, uniform ? ca : Eigen::Vector3f(k0 * ca + k1 * cb + k2 * cc), lights);
        }
        if (in.wireframe) {
          const float d = std::min({std::abs(w0) / len0, std::abs(w1) / len1, std::abs(w2) / len2});
          if (d < in.line_half_width) col = col * 0.25f + Eigen::Vector3f(20, 24, 30) * 0.75f;
        }
        buf.color[i] = pack(col);
      }
    }
  }
}

struct PointInputs {
  const std::vector<Eigen::Vector3f>* screen;
  const std::vector<Eigen::Vector3f>* colors;
  const std::vector<float>* light;  // per point shading factor, or null
  float radius = 1.f;               // samples
};

void raster_points_band(const PointInputs& in, const Bins& bins, int band, Buffers& buf) {
  const int y_lo = band * kBandRows, y_hi = std::min(buf.h, y_lo + kBandRows) - 1;
  const float r = in.radius, r2 = r * r;
  for (std::uint32_t b = bins.start[std::size_t(band)]; b < bins.start[std::size_t(band) + 1]; ++b) {
    const std::uint32_t i = bins.items[b];
    const Eigen::Vector3f& s = (*in.screen)[i];
    const int x0 = std::max(0, int(std::floor(s.x() - r))), x1 = std::min(buf.w - 1, int(std::ceil(s.x() + r)));
    const int r0 = std::max(y_lo, int(std::floor(s.y() - r))), r1 = std::min(y_hi, int(std::ceil(s.y() + r)));
    Eigen::Vector3f shaded = (*in.colors)[i];
    if (in.light) shaded *= (*in.light)[i];
    const std::uint32_t col = pack(shaded);
    for (int y = r0; y <= r1; ++y) {
      const float dy = float(y) + 0.5f - s.y();
      for (int x = x0; x <= x1; ++x) {
        const float dx = float(x) + 0.5f - s.x();
        if (dx * dx + dy * dy > r2) continue;
        const std::size_t k = buf.index(x, y);
        if (!(s.z() < buf.depth[k])) continue;
        buf.depth[k] = s.z();
        buf.color[k] = col;
      }
    }
  }
}

// Eye-dome lighting: each covered sample is darkened by how far its neighbours at `step`
// samples lie in front of it (background counts as `edge`); relative to the scene's depth range.
// Steps below `ignore` (about a splat's diameter) are left out: they are neighbouring splats of
// one surface, whose outlines would otherwise cover the picture in bubbles.
void eye_dome(Buffers& buf, int step, float depth_range, float ignore) {
  const float edge = 0.04f * depth_range;
  const float strength = 12.f / depth_range;
  std::vector<float> factor(buf.depth.size(), 1.f);
  constexpr int dx[8] = {1, -1, 0, 0, 1, 1, -1, -1}, dy[8] = {0, 0, 1, -1, 1, -1, 1, -1};
  tbb::parallel_for(tbb::blocked_range<int>(0, buf.h, 16), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y != rows.end(); ++y)
      for (int x = 0; x < buf.w; ++x) {
        const std::size_t i = buf.index(x, y);
        const float z = buf.depth[i];
        if (z == kNoDepth) continue;
        float sum = 0.f;
        for (int k = 0; k < 8; ++k) {
          const int nx = x + dx[k] * step, ny = y + dy[k] * step;
          const float nz = (nx < 0 || ny < 0 || nx >= buf.w || ny >= buf.h) ? kNoDepth : buf.depth[buf.index(nx, ny)];
          sum += nz == kNoDepth ? edge : std::clamp(z - nz - ignore, 0.f, edge);  // a hole: no darker than an outline
        }
        factor[i] = std::exp(-strength * sum / 8.f * 4.f);
      }
  });
  tbb::parallel_for(std::size_t(0), buf.depth.size(), std::size_t(65536), [&](std::size_t start) {
    const std::size_t end = std::min(buf.depth.size(), start + 65536);
    for (std::size_t i = start; i < end; ++i)
      if (factor[i] < 1.f) buf.color[i] = pack(unpack(buf.color[i]) * factor[i]);
  });
}

Eigen::Vector3f background(int y, int h) {
  const float t = float(y) / float(std::max(1, h - 1));
  return Eigen::Vector3f(255, 255, 255) * (1.f - t) + Eigen::Vector3f(222, 226, 234) * t;
}

std::string number_label(double v) {
  if (v == 0.0) return "0";
  return fmt::format("{:.3g}", v);
}

std::string legend_head(const std::string& field, const ColorScale& scale) {
  return field + (scale.unit.empty() ? "" : " [" + scale.unit + "]");
}

std::string legend_band(const ColorScale& scale) {
  return scale.kind == ColorMapKind::Diverging && scale.tolerance > 0.0 ? fmt::format("green: |d| <= {}", number_label(scale.tolerance)) : "";
}

int legend_font(int height) { return std::max(10, height / 48); }

// Pixels of the annotations: anything outside the picture (a legend on a small one) is dropped.
void paint(Image& img, int x, int y, const Rgb& c) {
  if (x < 0 || y < 0 || x >= img.width || y >= img.height) return;
  std::copy(c.begin(), c.end(), img.at(x, y));
}
void paint(Image& img, int x, int y, std::uint8_t grey) { paint(img, x, y, Rgb{grey, grey, grey}); }

void draw_legend(Image& img, const Layout& lay, const ColorScale& scale, const std::string& field, detail::TextPainter& text) {
  const int font = legend_font(img.height);
  const int bar_w = std::max(10, img.width / 60);
  // Room above the bar for the title (and the over-range box), below it for the under-range box
  // and the band's text, even on a small picture.
  const int boxes = scale.out_of_range ? font + font / 2 : 0;
  const int top = std::max(lay.plot_y0 + img.height / 8, lay.plot_y0 + 2 * font + boxes + 2);
  const int bottom = std::max(top + 2 * font, std::min(lay.plot_y0 + lay.plot_h - img.height / 8, img.height - 3 * font - boxes - 2));
  const int x = lay.legend_x + font;
  const double lo = scale.low(), hi = scale.high();
  auto row_of = [&](double v) { return int(std::lround(bottom - (v - lo) / (hi - lo) * double(bottom - top))); };
  for (int y = top; y <= bottom; ++y) {
    const double v = hi - (hi - lo) * double(y - top) / double(std::max(1, bottom - top));
    const Rgb c = scale.color(v);
    for (int k = 0; k < bar_w; ++k) paint(img, x + k, y, c);
  }
  for (int y = top - 1; y <= bottom + 1; ++y)
    for (int k : {-1, bar_w}) paint(img, x + k, y, 60);
  for (int k = -1; k <= bar_w; ++k) {
    paint(img, x + k, top - 1, 60);
    paint(img, x + k, bottom + 1, 60);
  }
  // With out-of-range boxes the ends are labelled there ("> +h", "< -h").
  std::vector<std::pair<double, std::string>> ticks = {{hi, scale.out_of_range ? "" : number_label(hi)},
                                                       {lo, scale.out_of_range ? "" : number_label(lo)}};
  if (scale.kind == ColorMapKind::Diverging) {
    ticks.emplace_back(0.0, "0");
    if (scale.tolerance > 0.0 && scale.tolerance < hi) {
      ticks.emplace_back(scale.tolerance, "+" + number_label(scale.tolerance));
      ticks.emplace_back(-scale.tolerance, number_label(-scale.tolerance));
    }
  } else {
    ticks.emplace_back(0.5 * (lo + hi), number_label(0.5 * (lo + hi)));
  }
  int last_y = -1000;
  std::sort(ticks.begin(), ticks.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  for (const auto& [v, label] : ticks) {
    const int y = row_of(v);
    for (int k = 0; k < 5; ++k) paint(img, x + bar_w + k, std::clamp(y, 0, img.height - 1), 60);
    if (label.empty() || y - last_y < font + 2) continue;  // tolerance labels close to zero: keep the tick, drop the text
    text.draw(img, x + bar_w + 8, y + font / 2 - 1, label, font, {30, 30, 30});
    last_y = y;
  }
  // Out-of-range boxes: over above the bar, under below it, each with its threshold.
  int head_y = top - font, band_y = bottom + 2 * font;
  if (scale.out_of_range) {
    const int box = font, gap = font / 2;
    const auto swatch = [&](int y0, const Rgb& c, const std::string& label) {
      for (int y = y0; y < y0 + box; ++y)
        for (int k = -1; k <= bar_w; ++k) {
          const bool edge = y == y0 || y == y0 + box - 1 || k == -1 || k == bar_w;
          paint(img, x + k, y, edge ? Rgb{60, 60, 60} : c);
        }
      text.draw(img, x + bar_w + 8, y0 + box - 2, label, font, {30, 30, 30});
    };
    swatch(top - 1 - gap - box, ColorScale::kOverRange, "> " + (hi > 0.0 ? std::string("+") : std::string()) + number_label(hi));
    swatch(bottom + 2 + gap, ColorScale::kUnderRange, "< " + number_label(lo));
    head_y -= box + gap;
    band_y += box + gap;
  }
  text.draw(img, std::max(0, x - font / 2), head_y, legend_head(field, scale), font, {20, 20, 20});
  const std::string band = legend_band(scale);
  if (!band.empty()) text.draw(img, std::max(0, x - font / 2), band_y, band, std::max(9, font - 2), {30, 110, 40});
}

// A bar of a round length (1, 2 or 5 times a power of ten) about a fifth of the plot wide.
void draw_scale_bar(Image& img, const Layout& lay, double pixels_per_unit, detail::TextPainter& text) {
  if (!(pixels_per_unit > 0.0)) return;
  const double target = 0.2 * lay.plot_w / pixels_per_unit;
  const double p = std::pow(10.0, std::floor(std::log10(target)));
  const double len = target >= 5 * p ? 5 * p : target >= 2 * p ? 2 * p : p;
  const int n = int(std::lround(len * pixels_per_unit));
  const int font = std::max(10, img.height / 52);
  const int x = lay.plot_x0 + font, y = img.height - font;
  for (int k = 0; k < n; ++k)
    for (int t = 0; t < 3; ++t) paint(img, x + k, y - t, 40);
  for (int t = 0; t < 8; ++t) {
    paint(img, x, y - t, 40);
    paint(img, std::min(img.width - 1, x + n - 1), y - t, 40);
  }
  text.draw(img, x + n + 6, y, number_label(len), font, {30, 30, 30});
}

}  // namespace

namespace detail {

SceneRenderer::SceneRenderer(const PointCloud& cloud, const std::vector<Triangle>& triangles, const RenderParams& params)
    : cloud(cloud), triangles(triangles), params(params), mesh(!triangles.empty()), n(cloud.size()), s(params.supersample) {
  if (cloud.empty()) throw InputError("render: nothing to draw: the cloud is empty");
  params.validate();
  for (const Triangle& t : triangles)
    for (int k = 0; k < 3; ++k)
      if (t[k] < 0 || std::size_t(t[k]) >= n)
        throw InputError(fmt::format("render: a face uses vertex {}, but there are {} vertices", t[k], n));
}

void SceneRenderer::select_field() {
  const std::string& name = params.field;
  if (name.empty()) return;
  if (name == "x" || name == "y" || name == "z") {
    const int a = name[0] - 'x';
    axis_values.resize(n);
    for (std::size_t i = 0; i < n; ++i) axis_values[i] = cloud.positions[i][a];
    field = &axis_values;
  } else if (const ScalarField* f = cloud.fields.find(name)) {
    field = &f->values;
  } else {
    std::string names = "x, y, z";
    for (const ScalarField& f2 : cloud.fields) names += ", " + f2.name;
    throw InputError(fmt::format("field: the data has no field \"{}\" (it has {})", name, names));
  }
  out.scale = params.scale ? *params.scale : default_color_scale(*field, name);
}

// A mesh's used vertices frame the view; a cloud's points all do.
void SceneRenderer::frame_box() {
  if (mesh) {
    used.assign(n, 0);
    for (const Triangle& t : triangles)
      for (int k = 0; k < 3; ++k) used[std::size_t(t[k])] = 1;
  }
  BoundingBox box;
  for (std::size_t i = 0; i < n; ++i) {
    if (mesh && !used[i]) continue;
    if (!cloud.positions[i].allFinite()) throw InputError(fmt::format("render: point {} is not finite", i));
    box.extend(cloud.positions[i]);
  }
  centre = box.center();
  diagonal = std::max(box.diagonal(), 1e-300);
}

// A legend column on the right when colouring by a field, wide enough for its longest text;
// a title row on top.
void SceneRenderer::lay_out() {
  text.emplace(params.font_file);
  if (!text->ok()) out.warnings.push_back(text->error());
  legend = field && params.legend;
  int legend_w = 0;
  if (legend) {
    const int font = legend_font(params.size.height);
    legend_w = std::max({110, params.size.width / 6, text->width(legend_head(params.field, out.scale), font) + 2 * font,
                         text->width(legend_band(out.scale), std::max(9, font - 2)) + 2 * font});
    legend_w = std::min(legend_w, params.size.width / 2);
  }
  title_h = params.title.empty() ? 0 : std::max(16, params.size.height / 22);
  layout.plot_x0 = 0;
  layout.plot_y0 = title_h;
  layout.plot_w = params.size.width - legend_w;
  layout.plot_h = params.size.height - title_h;
  layout.legend_x = layout.plot_w;
}

void SceneRenderer::choose_projection() {
  if (params.camera)
    aim_camera(*params.camera);
  else
    frame_view();
  if (params.camera && !projection.perspective) out.pixels_per_unit = projection.scale / s;
}

void SceneRenderer::aim_camera(const Camera& c) {
  Projection& proj = projection;
  if ((c.target - c.eye).norm() <= 0.0) throw key_error("camera", "eye and target coincide");
  proj.basis = basis_of(c.target - c.eye, c.up);
  proj.eye = c.eye - centre;
  proj.cx = 0.5 * s * layout.plot_w;
  proj.cy = s * layout.plot_y0 + 0.5 * s * layout.plot_h;
  if (c.fov_deg > 0.0) {
    if (c.fov_deg >= 179.0) throw key_error("camera", fmt::format("field of view {} degrees is not below 179", c.fov_deg));
    proj.perspective = true;
    proj.scale = 0.5 * s * layout.plot_h / std::tan(0.5 * c.fov_deg * M_PI / 180.0);
    proj.near = 1e-6 * diagonal;
  } else {
    if (!(c.ortho_height > 0.0)) throw key_error("camera", "ortho_height must be positive for an orthographic camera");
    proj.scale = s * layout.plot_h / c.ortho_height;
    proj.eye = Vector3d::Zero();
    // Centre the picture on the target.
    const Vector3d t = c.target - centre;
    proj.cx -= proj.scale * t.dot(proj.basis.right);
    proj.cy += proj.scale * t.dot(proj.basis.up);
  }
}

// Frames the extent of the data across the view.
void SceneRenderer::frame_view() {
  Projection& proj = projection;
  proj.basis = view_basis(params.view);
  double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300;
  for (std::size_t i = 0; i < n; ++i) {
    if (mesh && !used[i]) continue;
    const Vector3d q = cloud.positions[i] - centre;
    const double x = q.dot(proj.basis.right), y = q.dot(proj.basis.up);
    xmin = std::min(xmin, x);
    xmax = std::max(xmax, x);
    ymin = std::min(ymin, y);
    ymax = std::max(ymax, y);
  }
  const double ext_x = std::max(xmax - xmin, 1e-9 * diagonal), ext_y = std::max(ymax - ymin, 1e-9 * diagonal);
  const double fit = (1.0 - 2.0 * params.margin);
  const double px_per_unit = std::min(fit * layout.plot_w / ext_x, fit * layout.plot_h / ext_y);
  proj.scale = s * px_per_unit;
  proj.cx = s * (0.5 * layout.plot_w) - proj.scale * 0.5 * (xmin + xmax);
  proj.cy = s * (layout.plot_y0 + 0.5 * layout.plot_h) + proj.scale * 0.5 * (ymin + ymax);
  out.pixels_per_unit = px_per_unit;
}

void SceneRenderer::project_vertices() {
  screen.resize(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 65536), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) screen[i] = projection(cloud.positions[i] - centre);
  });
  scale = out.scale;
  colors = vertex_colors(cloud, params, mesh, scale, field);
  buf = Buffers(params.size.width * s, params.size.height * s);
  bands = (buf.h + kBandRows - 1) / kBandRows;
  lights = make_lights();
}

Eigen::Vector3f SceneRenderer::to_camera(const Vector3d& v) const {
  const Basis& b = projection.basis;
  return Eigen::Vector3f(float(v.dot(b.right)), float(v.dot(b.up)), float(-v.dot(b.forward)));
}

void SceneRenderer::compute_normals() {
  const std::size_t f = triangles.size();
  normals.assign(params.flat_shading ? f : n, Eigen::Vector3f::Zero());
  std::vector<Vector3d> face_normals(f);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, f, 65536), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t t = r.begin(); t != r.end(); ++t) {
      const Vector3d& a = cloud.positions[std::size_t(triangles[t][0])];
      face_normals[t] = (cloud.positions[std::size_t(triangles[t][1])] - a).cross(cloud.positions[std::size_t(triangles[t][2])] - a);
    }
  });
  if (params.flat_shading) {
    for (std::size_t t = 0; t < f; ++t) normals[t] = to_camera(face_normals[t]);
  } else {
    // Area-weighted vertex normals (the cross product's length is twice the area).
    std::vector<Vector3d> sum(n, Vector3d::Zero());
    for (std::size_t t = 0; t < f; ++t)
      for (int k = 0; k < 3; ++k) sum[std::size_t(triangles[t][k])] += face_normals[t];
    for (std::size_t i = 0; i < n; ++i) normals[i] = to_camera(sum[i]);
  }
}

// The sample rows each face spans, {1, 0} for a face not drawn.
std::vector<std::array<std::int32_t, 2>> SceneRenderer::triangle_rows() const {
  std::vector<std::array<std::int32_t, 2>> rows(triangles.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, triangles.size(), 65536), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t t = r.begin(); t != r.end(); ++t) {
      const Eigen::Vector3f& a = screen[std::size_t(triangles[t][0])];
      const Eigen::Vector3f& b = screen[std::size_t(triangles[t][1])];
      const Eigen::Vector3f& c = screen[std::size_t(triangles[t][2])];
      if (a.z() == kNoDepth || b.z() == kNoDepth || c.z() == kNoDepth) {
        rows[t] = {1, 0};  // behind the eye: not drawn (no clipping)
        continue;
      }
      const float lo = std::min({a.y(), b.y(), c.y()}), hi = std::max({a.y(), b.y(), c.y()});
      const float left = std::min({a.x(), b.x(), c.x()}), right = std::max({a.x(), b.x(), c.x()});
      if (hi < 0.f || lo >= float(buf.h) || right < 0.f || left >= float(buf.w)) {
        rows[t] = {1, 0};
        continue;
      }
      rows[t] = {std::max(0, int(std::floor(lo))), std::min(buf.h - 1, int(std::ceil(hi)))};
    }
  });
  return rows;
}

void SceneRenderer::raster_mesh() {
  const std::vector<std::array<std::int32_t, 2>> rows = triangle_rows();
  const Bins bins = bin_by_rows(triangles.size(), bands, rows);
  MeshInputs in{&triangles, &screen, &colors, &normals, params.flat_shading, projection.perspective, params.wireframe, 0.55f * float(s)};
  tbb::parallel_for(0, bands, [&](int band) { raster_triangles_band(in, bins, band, buf, lights); });
  for (const auto& r : rows) out.triangles_drawn += r[0] <= r[1] ? 1 : 0;
}

// From the projected density: the points spread over the framed area.
void SceneRenderer::size_splats() {
  float lo_x = 1e30f, hi_x = -1e30f, lo_y = 1e30f, hi_y = -1e30f;
  for (const Eigen::Vector3f& q : screen)
    if (q.z() != kNoDepth) {
      lo_x = std::min(lo_x, q.x());
      hi_x = std::max(hi_x, q.x());
      lo_y = std::min(lo_y, q.y());
      hi_y = std::max(hi_y, q.y());
    }
  const double area_px = std::max(1.0, double(hi_x - lo_x) * double(hi_y - lo_y)) / double(s * s);
  const double diameter_px = params.point_size_px > 0.0 ? params.point_size_px : std::clamp(3.0 * std::sqrt(area_px / double(n)), 1.5, 24.0);
  radius = float(0.5 * diameter_px * s);
}

void SceneRenderer::light_points() {
  light.clear();
  if (!cloud.has_normals()) return;
  light.resize(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 65536), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const Eigen::Vector3f nn = to_camera(cloud.normals[i]);
      light[i] = nn.squaredNorm() > 0.f ? 0.45f + 0.55f * std::abs(nn.normalized().dot(lights.key)) : 1.f;
    }
  });
}

// The sample rows each splat spans, {1, 0} for a splat not drawn.
std::vector<std::array<std::int32_t, 2>> SceneRenderer::splat_rows() const {
  std::vector<std::array<std::int32_t, 2>> rows(n);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 65536), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      const Eigen::Vector3f& q = screen[i];
      if (q.z() == kNoDepth || q.y() + radius < 0.f || q.y() - radius >= float(buf.h) || q.x() + radius < 0.f || q.x() - radius >= float(buf.w)) {
        rows[i] = {1, 0};
        continue;
      }
      rows[i] = {std::max(0, int(std::floor(q.y() - radius))), std::min(buf.h - 1, int(std::ceil(q.y() + radius)))};
    }
  });
  return rows;
}

void SceneRenderer::raster_points() {
  const std::vector<std::array<std::int32_t, 2>> rows = splat_rows();
  const Bins bins = bin_by_rows(n, bands, rows);
  PointInputs in{&screen, &colors, light.empty() ? nullptr : &light, radius};
  tbb::parallel_for(0, bands, [&](int band) { raster_points_band(in, bins, band, buf); });
  for (const auto& r : rows) out.points_drawn += r[0] <= r[1] ? 1 : 0;
}

void SceneRenderer::apply_eye_dome() {
  float zmin = kNoDepth, zmax = -kNoDepth;
  for (const Eigen::Vector3f& q : screen)
    if (q.z() != kNoDepth) {
      zmin = std::min(zmin, q.z());
      zmax = std::max(zmax, q.z());
    }
  // A splat's diameter in depth units (perspective: at the middle depth).
  const float ignore = float(2.0 * radius / projection.scale * (projection.perspective ? 0.5 * (zmin + zmax) : 1.0));
  eye_dome(buf, s, std::max(zmax - zmin, float(1e-6 * diagonal)), ignore);
}

// The mean of each pixel's samples, the background where none is covered.
void SceneRenderer::downsample() {
  const int width = params.size.width, height = params.size.height;
  image = Image(width, height);
  const float inv = 1.f / float(s * s);
  tbb::parallel_for(tbb::blocked_range<int>(0, height, 8), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y != rows.end(); ++y) {
      const Eigen::Vector3f bg = background(y, height);
      for (int x = 0; x < width; ++x) {
        Eigen::Vector3f sum = Eigen::Vector3f::Zero();
        for (int j = 0; j < s; ++j)
          for (int i = 0; i < s; ++i) {
            const std::size_t k = buf.index(x * s + i, y * s + j);
            sum += buf.depth[k] == kNoDepth ? bg : unpack(buf.color[k]);
          }
        sum *= inv;
        std::uint8_t* px = image.at(x, y);
        for (int c = 0; c < 3; ++c) px[c] = std::uint8_t(std::clamp(std::lround(sum[c]), 0l, 255l));
      }
    }
  });
}

void SceneRenderer::annotate() {
  if (legend) draw_legend(image, layout, scale, params.field, *text);
  if (!params.title.empty()) text->draw(image, 10, title_h - title_h / 4, params.title, std::max(12, title_h * 2 / 3), {20, 20, 20});
  if (out.pixels_per_unit > 0.0) draw_scale_bar(image, layout, out.pixels_per_unit, *text);
}

RenderResult SceneRenderer::result() && {
  out.image = std::move(image);
  return std::move(out);
}

}  // namespace detail

RenderResult render_scene(const PointCloud& cloud, const std::vector<Triangle>& triangles, const RenderParams& p) {
  detail::SceneRenderer r(cloud, triangles, p);
  r.select_field();
  r.frame_box();
  r.lay_out();
  r.choose_projection();
  r.project_vertices();
  if (r.mesh) {
    r.compute_normals();
    r.raster_mesh();
  } else {
    r.size_splats();
    r.light_points();
    r.raster_points();
    if (p.eye_dome) r.apply_eye_dome();
  }
  r.downsample();
  r.annotate();
  return std::move(r).result();
}

const ResultTable<RenderResult>& RenderResult::results(bool by_field) {
  static const std::vector<ResultTable<RenderResult>> tables = [] {
    using R = RenderResult;
    std::vector<ResultTable<R>> out(2);
    for (ResultTable<R>& t : out) {
      t.count("points_drawn", &R::points_drawn, "Points drawn").as_count();
      t.count("triangles_drawn", &R::triangles_drawn, "Triangles drawn").as_count();
    }
    ResultTable<R>& t = out[1];  // coloured by a field
    t.computed("scale_min", ResultType::Number, [](const R& r) { return ResultValue(r.scale.low()); }, "Value of the colour scale's low end");
    t.computed("scale_max", ResultType::Number, [](const R& r) { return ResultValue(r.scale.high()); }, "Value of the colour scale's high end");
    t.computed("scale_tolerance", ResultType::Number, [](const R& r) { return ResultValue(r.scale.tolerance); },
               "Diverging map: the green band's half width (0: none)");
    t.computed("colormap", ResultType::Text,
               [](const R& r) { return ResultValue(std::string(r.scale.kind == ColorMapKind::Diverging ? "diverging" : "sequential")); },
               "Colour map: sequential or diverging");
    return out;
  }();
  return tables[by_field ? 1 : 0];
}

}  // namespace pointsurf
