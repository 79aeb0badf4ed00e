// SPDX-License-Identifier: GPL-3.0-or-later
// Pictures with answers known by construction: a sphere's silhouette area, a plane seen
// edge-on, the legend's extremes, depth order, and the same picture after a 1e6 m shift.
#include "pointsurf/render/render_scene.h"

#include <cmath>
#include <cstdlib>

#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "support/files.h"
#include "support/mesh_shapes.h"
#include "support/shapes.h"

namespace pointsurf {
namespace {

using Rgb = std::array<std::uint8_t, 3>;

PointCloud coloured(const std::vector<Vector3d>& positions, const Vector3f& rgb) {
  PointCloud c;
  c.positions = positions;
  c.colors.assign(positions.size(), rgb);
  return c;
}

// Pixels whose green channel differs from the background of their row (the pixel at x = 0,
// left empty by the margin) by more than half of a red object's contrast.
std::size_t object_pixels(const Image& img, int x0 = 0, int y0 = 0, int x1 = -1, int y1 = -1) {
  if (x1 < 0) x1 = img.width;
  if (y1 < 0) y1 = img.height;
  std::size_t n = 0;
  for (int y = std::max(0, y0); y < std::min(img.height, y1); ++y)
    for (int x = std::max(0, x0); x < std::min(img.width, x1); ++x)
      if (std::abs(int(img.at(x, y)[1]) - int(img.at(0, y)[1])) > 100) ++n;
  return n;
}

RenderParams plain(View view) {
  RenderParams p;
  p.size = {400, 300};
  p.view = view;
  return p;
}

TEST(RenderScene, SphereSilhouetteHasTheAreaOfItsDisc) {
  const TriangleMesh sphere = test::icosphere_mesh(5, 2.0);
  const PointCloud c = coloured(sphere.vertices.positions, Vector3f(1, 0, 0));
  for (View v : {View::Front, View::Side, View::Top, View::Iso}) {
    const RenderResult r = render_scene(c, sphere.triangles, plain(v));
    EXPECT_TRUE(r.warnings.empty());
    EXPECT_EQ(r.triangles_drawn, sphere.triangles.size());
    const double radius_px = 2.0 * r.pixels_per_unit;
    // Framed: the disc fills the plot's height less the margins.
    EXPECT_NEAR(2.0 * radius_px, 300.0 * (1.0 - 2.0 * RenderParams{}.margin), 1.0) << view_names().name(v);
    const double expected = M_PI * radius_px * radius_px;
    const double measured = double(object_pixels(r.image, 200 - int(radius_px) - 4, 150 - int(radius_px) - 4, 200 + int(radius_px) + 4,
                                                 150 + int(radius_px) + 4));
    EXPECT_NEAR(measured / expected, 1.0, 0.02) << view_names().name(v);
  }
}

TEST(RenderScene, SplattedSphereCoversItsDisc) {
  const PointCloud c = coloured(test::sample_sphere(40000, 1.0).positions, Vector3f(1, 0, 0));
  const RenderResult r = render_scene(c, {}, plain(View::Front));
  EXPECT_EQ(r.points_drawn, c.size());
  const double radius_px = r.pixels_per_unit;
  const double ratio = double(object_pixels(r.image, 0, 0, 400, 300 - 30)) / (M_PI * radius_px * radius_px);
  EXPECT_GT(ratio, 0.95);
  EXPECT_LT(ratio, 1.15);  // splats reach past the silhouette by their radius
}

TEST(RenderScene, PlaneSeenEdgeOnDrawsNothingAndSeenFromAboveFillsItsSquare) {
  const TriangleMesh plane = test::grid_mesh(20, 1.0);
  const PointCloud c = coloured(plane.vertices.positions, Vector3f(1, 0, 0));
  // The front view looks along y, within the plane z = 0: every triangle has zero area.
  const RenderResult edge = render_scene(c, plane.triangles, plain(View::Front));
  EXPECT_EQ(object_pixels(edge.image, 0, 0, 400, 300 - 30), 0u);
  const RenderResult top = render_scene(c, plane.triangles, plain(View::Top));
  const double side_px = 2.0 * top.pixels_per_unit;
  EXPECT_NEAR(double(object_pixels(top.image)) / (side_px * side_px), 1.0, 0.02);
}

TEST(RenderScene, NearTriangleHidesFarOneWhateverTheirOrder) {
  PointCloud c;
  // Two squares parallel to the xz-plane: red at y = -1 (nearer the front camera), blue at y = +1.
  for (double y : {-1.0, 1.0})
    for (auto [x, z] : {std::pair{-1.0, -1.0}, {1.0, -1.0}, {1.0, 1.0}, {-1.0, 1.0}}) {
      c.positions.emplace_back(x, y, z);
      c.colors.push_back(y < 0 ? Vector3f(1, 0, 0) : Vector3f(0, 0, 1));
    }
  std::vector<Triangle> tris = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
  auto centre = [](const RenderResult& r) {
    const std::uint8_t* p = r.image.at(r.image.width / 2, r.image.height / 2);
    return Rgb{p[0], p[1], p[2]};
  };
  for (int order = 0; order < 2; ++order) {
    const Rgb front = centre(render_scene(c, tris, plain(View::Front)));
    EXPECT_GT(front[0], 2 * front[2]) << "order " << order;
    RenderParams persp = plain(View::Front);
    persp.camera = Camera{Vector3d(0.3, -8, 0.2), Vector3d::Zero(), Vector3d::UnitZ(), 30.0};
    const Rgb near_red = centre(render_scene(c, tris, persp));
    EXPECT_GT(near_red[0], 2 * near_red[2]) << "order " << order;
    persp.camera->eye = Vector3d(0.3, 8, 0.2);  // from behind: blue is nearer
    const Rgb near_blue = centre(render_scene(c, tris, persp));
    EXPECT_GT(near_blue[2], 2 * near_blue[0]) << "order " << order;
    std::swap(tris[0], tris[2]);
    std::swap(tris[1], tris[3]);
  }
}

TEST(RenderScene, LegendShowsTheFieldsExtremesTopToBottom) {
  PointCloud c = test::sample_plane(500, 1.0);
  ScalarField& f = c.fields.add("height", c.size());
  for (std::size_t i = 0; i < c.size(); ++i) f.values[i] = -2.0 + 7.0 * double(i) / double(c.size() - 1);
  RenderParams p = plain(View::Top);
  p.field = "height";
  const RenderResult r = render_scene(c, {}, p);
  EXPECT_DOUBLE_EQ(r.scale.min, -2.0);
  EXPECT_DOUBLE_EQ(r.scale.max, 5.0);
  auto rows_of = [&](const Rgb& colour) {
    std::vector<int> rows;
    for (int y = 0; y < r.image.height; ++y)
      for (int x = r.image.width * 3 / 4; x < r.image.width; ++x)
        if (Rgb{r.image.at(x, y)[0], r.image.at(x, y)[1], r.image.at(x, y)[2]} == colour) rows.push_back(y);
    return rows;
  };
  const std::vector<int> top = rows_of(r.scale.color(5.0)), bottom = rows_of(r.scale.color(-2.0));
  ASSERT_FALSE(top.empty());
  ASSERT_FALSE(bottom.empty());
  EXPECT_LT(*std::max_element(top.begin(), top.end()), *std::min_element(bottom.begin(), bottom.end()));

  // A deviation: diverging, symmetric, the tolerance band in green on the bar.
  c.fields.add("deviation", c.size()).values = f.values;
  p.field = "deviation";
  ColorScale s = default_color_scale(f.values, "deviation");
  s.tolerance = 1.0;
  p.scale = s;
  const RenderResult d = render_scene(c, {}, p);
  EXPECT_DOUBLE_EQ(d.scale.min, -5.0);
  EXPECT_DOUBLE_EQ(d.scale.max, 5.0);
  std::size_t green = 0;
  for (int y = 0; y < d.image.height; ++y)
    for (int x = d.image.width * 3 / 4; x < d.image.width; ++x)
      if (Rgb{d.image.at(x, y)[0], d.image.at(x, y)[1], d.image.at(x, y)[2]} == Rgb{64, 176, 72}) ++green;
  EXPECT_GT(green, 50u);
}

TEST(RenderScene, ShiftOfAMillionMetresGivesTheSamePicture) {
  const TriangleMesh sphere = test::icosphere_mesh(4, 1.5);
  PointCloud a = coloured(sphere.vertices.positions, Vector3f(0.8f, 0.5f, 0.2f));
  PointCloud b = a;
  for (Vector3d& p : b.positions) p += Vector3d(1e6, -2e6, 3e6);
  for (bool mesh : {true, false}) {
    const std::vector<Triangle> tris = mesh ? sphere.triangles : std::vector<Triangle>{};
    const Image ia = render_scene(a, tris, plain(View::Iso)).image, ib = render_scene(b, tris, plain(View::Iso)).image;
    std::size_t differ = 0;
    for (std::size_t i = 0; i < ia.rgb.size(); ++i) differ += std::abs(int(ia.rgb[i]) - int(ib.rgb[i])) > 2;
    EXPECT_LE(differ, ia.rgb.size() / 1000) << (mesh ? "mesh" : "points");
  }
}

TEST(RenderScene, SamePictureOnEveryRun) {
  const TriangleMesh sphere = test::icosphere_mesh(3);
  PointCloud c;
  c.positions = sphere.vertices.positions;
  RenderParams p = plain(View::Iso);
  p.wireframe = true;
  EXPECT_EQ(render_scene(c, sphere.triangles, p).image.rgb, render_scene(c, sphere.triangles, p).image.rgb);
  p.flat_shading = true;
  EXPECT_EQ(render_scene(c, sphere.triangles, p).image.rgb, render_scene(c, sphere.triangles, p).image.rgb);
}

TEST(RenderScene, BadInputIsRefusedWithAReason) {
  PointCloud c = test::sample_sphere(100);
  c.fields.add("intensity", c.size());
  test::expect_error<InputError>([] { render_scene(PointCloud{}, {}); }, "the cloud is empty");
  RenderParams p;
  p.field = "curvature";
  test::expect_error<InputError>([&] { render_scene(c, {}, p); }, "no field \"curvature\" (it has x, y, z, intensity)");
  p = {};
  p.size.width = 4;
  test::expect_error<UsageError>([&] { render_scene(c, {}, p); }, "size: 4x768");
  p = {};
  p.supersample = 5;
  test::expect_error<UsageError>([&] { render_scene(c, {}, p); }, "render_scene: supersample must be in [1, 4], got 5");
  test::expect_error<InputError>([&] { render_scene(c, {Triangle(0, 1, 100)}); }, "vertex 100, but there are 100 vertices");
  p = {};
  p.camera = Camera{Vector3d(0, 0, 5), Vector3d::Zero(), Vector3d::UnitZ(), 40.0};
  test::expect_error<UsageError>([&] { render_scene(c, {}, p); }, "parallel to the viewing direction");
  c.positions[3].x() = std::nan("");
  test::expect_error<InputError>([&] { render_scene(c, {}); }, "point 3 is not finite");
  EXPECT_EQ(view_names().value("top"), View::Top);
  EXPECT_EQ(view_names().names(), (std::vector<std::string>{"front", "side", "top", "iso"}));
  EXPECT_EQ(parse_picture_size("320x200"), (PictureSize{320, 200}));
  EXPECT_EQ(picture_size_text(PictureSize{}), "1024x768");
  test::expect_error<UsageError>([] { parse_picture_size("300"); }, "size: \"300\" is not WIDTHxHEIGHT");
  test::expect_error<UsageError>([] { parse_picture_size("4x768"); }, "size: 4x768 is outside 8x8 .. 16384x16384");
}

}  // namespace
}  // namespace pointsurf
