// SPDX-License-Identifier: GPL-3.0-or-later
// The phases of render_scene (render/detail/scene_renderer.h), each run alone on a unit square
// seen from the front in a small picture, where the framing is known by construction: with a
// margin of 1/4, the square fills the middle half of the plot.
#include "render/detail/scene_renderer.h"

#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "pointsurf/core/error.h"

namespace pointsurf {
namespace {

using detail::Buffers;
using detail::kNoDepth;
using detail::SceneRenderer;

// The unit square in the xz plane (facing -y, towards the front view's eye), as two triangles.
PointCloud square() {
  PointCloud c;
  c.positions = {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}};
  return c;
}
const std::vector<Triangle> kSquareFaces = {Triangle(0, 1, 2), Triangle(0, 2, 3)};
const std::vector<Triangle> kNoFaces;

RenderParams front(int size, int supersample) {
  RenderParams p;
  p.size = {size, size};
  p.view = View::Front;
  p.supersample = supersample;
  p.margin = 0.25;
  p.legend = false;
  return p;
}

// Runs the phases up to and including project_vertices.
void project(SceneRenderer& r) {
  r.select_field();
  r.frame_box();
  r.lay_out();
  r.choose_projection();
  r.project_vertices();
}

std::size_t covered_samples(const Buffers& buf) {
  std::size_t k = 0;
  for (const float z : buf.depth) k += z != kNoDepth;
  return k;
}

TEST(SceneRendererPhases, SelectFieldTakesACoordinateOrANamedFieldOrNone) {
  PointCloud cloud = square();
  cloud.fields.add("height", 4).values = {5, 6, 7, 8};
  RenderParams p = front(16, 1);
  {
    SceneRenderer r(cloud, kNoFaces, p);
    r.select_field();
    EXPECT_EQ(r.field, nullptr);
  }
  p.field = "z";
  {
    SceneRenderer r(cloud, kNoFaces, p);
    r.select_field();
    ASSERT_NE(r.field, nullptr);
    EXPECT_EQ(*r.field, (std::vector<double>{0, 0, 1, 1}));
  }
  p.field = "height";
  {
    SceneRenderer r(cloud, kNoFaces, p);
    r.select_field();
    ASSERT_NE(r.field, nullptr);
    EXPECT_EQ(*r.field, (std::vector<double>{5, 6, 7, 8}));
  }
  p.field = "width";
  SceneRenderer r(cloud, kNoFaces, p);
  try {
    r.select_field();
    FAIL() << "an unknown field was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no field \"width\" (it has x, y, z, height)"), std::string::npos) << e.what();
  }
}

TEST(SceneRendererPhases, FrameBoxOfAMeshLeavesOutItsUnusedVertices) {
  PointCloud cloud = square();
  cloud.positions.emplace_back(std::nan(""), 100.0, 100.0);  // in no face: neither framed nor refused
  const std::vector<Triangle> faces = {Triangle(0, 1, 2)};
  const RenderParams p = front(16, 1);
  SceneRenderer r(cloud, faces, p);
  r.frame_box();
  EXPECT_EQ(r.used, (std::vector<char>{1, 1, 1, 0, 0}));
  EXPECT_EQ(r.centre, Vector3d(0.5, 0.0, 0.5));
  EXPECT_DOUBLE_EQ(r.diagonal, std::sqrt(2.0));
  // As a cloud, every point is framed: the non-finite one is refused.
  SceneRenderer points(cloud, kNoFaces, p);
  EXPECT_THROW(points.frame_box(), InputError);
}

TEST(SceneRendererPhases, LayoutMakesRoomForTitleAndLegend) {
  const PointCloud cloud = square();
  RenderParams p = front(16, 1);
  p.size = {200, 100};
  {
    SceneRenderer r(cloud, kNoFaces, p);
    r.select_field();
    r.lay_out();
    EXPECT_FALSE(r.legend);
    EXPECT_EQ(r.title_h, 0);
    EXPECT_EQ(r.layout.plot_y0, 0);
    EXPECT_EQ(r.layout.plot_w, 200);
    EXPECT_EQ(r.layout.plot_h, 100);
  }
  // A title row of max(16, 100 / 22) pixels; a legend column of at least 110 pixels, capped
  // at half the width.
  p.title = "T";
  p.field = "z";
  p.legend = true;
  SceneRenderer r(cloud, kNoFaces, p);
  r.select_field();
  r.lay_out();
  EXPECT_TRUE(r.legend);
  EXPECT_EQ(r.title_h, 16);
  EXPECT_EQ(r.layout.plot_y0, 16);
  EXPECT_EQ(r.layout.plot_h, 84);
  EXPECT_EQ(r.layout.plot_w, 100);
  EXPECT_EQ(r.layout.legend_x, 100);
}

TEST(SceneRendererPhases, AutoFramedViewFitsTheSquareInsideTheMargin) {
  const PointCloud cloud = square();
  const RenderParams p = front(16, 2);  // 32 x 32 samples
  SceneRenderer r(cloud, kSquareFaces, p);
  r.select_field();
  r.frame_box();
  r.lay_out();
  r.choose_projection();
  EXPECT_EQ(r.out.pixels_per_unit, 8.0);  // the middle half of 16 pixels
  EXPECT_EQ(r.projection.scale, 16.0);    // in samples
  EXPECT_EQ(r.projection(cloud.positions[0] - r.centre), Eigen::Vector3f(8, 24, 0));  // bottom left
  EXPECT_EQ(r.projection(cloud.positions[2] - r.centre), Eigen::Vector3f(24, 8, 0));  // top right
}

TEST(SceneRendererPhases, GivenOrthographicCameraCentresItsTarget) {
  const PointCloud cloud = square();
  RenderParams p = front(16, 1);
  p.camera = Camera{Vector3d(0.5, -10, 0.5), Vector3d(0.5, 0, 0.5), Vector3d::UnitZ(), 0.0, 2.0};
  SceneRenderer r(cloud, kNoFaces, p);
  r.frame_box();
  r.lay_out();
  r.choose_projection();
  EXPECT_EQ(r.out.pixels_per_unit, 8.0);  // 16 pixels show 2 units
  EXPECT_EQ(r.projection(Vector3d(0.5, 0, 0.5) - r.centre), Eigen::Vector3f(8, 8, 0));
  EXPECT_EQ(r.projection(cloud.positions[0] - r.centre), Eigen::Vector3f(4, 12, 0));
  // A camera whose eye is its target is refused.
  p.camera->eye = p.camera->target;
  SceneRenderer bad(cloud, kNoFaces, p);
  bad.frame_box();
  bad.lay_out();
  EXPECT_THROW(bad.choose_projection(), UsageError);
}

TEST(SceneRendererPhases, ProjectedVerticesAndPlainColours) {
  const PointCloud cloud = square();
  const RenderParams p = front(16, 2);
  SceneRenderer mesh(cloud, kSquareFaces, p);
  project(mesh);
  ASSERT_EQ(mesh.screen.size(), 4u);
  EXPECT_EQ(mesh.screen[1], Eigen::Vector3f(24, 24, 0));
  EXPECT_EQ(mesh.screen[3], Eigen::Vector3f(8, 8, 0));
  EXPECT_EQ(mesh.colors, std::vector<Eigen::Vector3f>(4, Eigen::Vector3f(190, 196, 206)));
  EXPECT_EQ(mesh.buf.w, 32);
  EXPECT_EQ(mesh.buf.h, 32);
  EXPECT_EQ(mesh.bands, 1);
  EXPECT_EQ(covered_samples(mesh.buf), 0u);
  SceneRenderer points(cloud, kNoFaces, p);
  project(points);
  EXPECT_EQ(points.colors, std::vector<Eigen::Vector3f>(4, Eigen::Vector3f(70, 110, 170)));
}

TEST(SceneRendererPhases, NormalsPerFaceOrAreaWeightedPerVertexFaceTheViewer) {
  const PointCloud cloud = square();
  RenderParams p = front(16, 1);
  // Each face's cross product is twice its area (1/2) long and points at the viewer: camera +z.
  p.flat_shading = true;
  SceneRenderer flat(cloud, kSquareFaces, p);
  project(flat);
  flat.compute_normals();
  EXPECT_EQ(flat.normals, std::vector<Eigen::Vector3f>(2, Eigen::Vector3f(0, 0, 1)));
  p.flat_shading = false;
  SceneRenderer smooth(cloud, kSquareFaces, p);
  project(smooth);
  smooth.compute_normals();
  // Vertices 0 and 2 are in both faces.
  EXPECT_EQ(smooth.normals, (std::vector<Eigen::Vector3f>{{0, 0, 2}, {0, 0, 1}, {0, 0, 2}, {0, 0, 1}}));
}

TEST(SceneRendererPhases, RasterizedSquareCoversTheMiddleHalfOfThePlot) {
  const PointCloud cloud = square();
  const RenderParams p = front(16, 1);
  SceneRenderer r(cloud, kSquareFaces, p);
  project(r);
  r.compute_normals();
  r.raster_mesh();
  EXPECT_EQ(r.out.triangles_drawn, 2u);
  // Corners at samples 4 and 12: the sample centres 4.5 .. 11.5 each way, at depth 0.
  EXPECT_EQ(covered_samples(r.buf), 64u);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) {
      const bool inside = x >= 4 && x < 12 && y >= 4 && y < 12;
      EXPECT_EQ(r.buf.depth[r.buf.index(x, y)], inside ? 0.f : kNoDepth) << x << ", " << y;
    }
}

TEST(SceneRendererPhases, SplatSizeGivenOrFromTheProjectedDensity) {
  const PointCloud cloud = square();
  RenderParams p = front(16, 2);
  p.point_size_px = 4.0;
  {
    SceneRenderer r(cloud, kNoFaces, p);
    project(r);
    r.size_splats();
    EXPECT_EQ(r.radius, 4.f);  // 2 pixels of 2 samples
  }
  // The corners span 8 x 8 pixels: 16 square pixels a point, a diameter of 3 x 4 pixels.
  p.point_size_px = 0.0;
  SceneRenderer r(cloud, kNoFaces, p);
  project(r);
  r.size_splats();
  EXPECT_EQ(r.radius, 12.f);
}

TEST(SceneRendererPhases, PointsFacingTheViewerAreLitByTheKeyLight) {
  PointCloud cloud = square();
  const RenderParams p = front(16, 1);
  {
    SceneRenderer r(cloud, kNoFaces, p);
    project(r);
    r.light_points();
    EXPECT_TRUE(r.light.empty());  // no normals: the splats keep their colour
  }
  cloud.normals = {{0, -1, 0}, {0, 1, 0}, {0, 0, 0}, {0, -1, 0}};
  SceneRenderer r(cloud, kNoFaces, p);
  project(r);
  r.light_points();
  const float facing = 0.45f + 0.55f * r.lights.key.z();
  EXPECT_EQ(r.light, (std::vector<float>{facing, facing, 1.f, facing}));  // two-sided; no normal: unlit
}

TEST(SceneRendererPhases, SplatsAreDiscsOfTheirRadius) {
  const PointCloud cloud = square();
  RenderParams p = front(16, 1);
  p.point_size_px = 4.0;
  SceneRenderer r(cloud, kNoFaces, p);
  project(r);
  r.size_splats();
  r.light_points();
  r.raster_points();
  EXPECT_EQ(r.out.points_drawn, 4u);
  // Around each corner (4 or 12, 4 or 12), the sample centres within 2: 4 at offsets
  // (+-0.5, +-0.5) and 8 at (+-0.5, +-1.5) or (+-1.5, +-0.5).
  EXPECT_EQ(covered_samples(r.buf), 48u);
  const std::uint32_t plain = detail::pack(Eigen::Vector3f(70, 110, 170));
  for (const auto& [x, y] : {std::pair(4, 4), std::pair(12, 4), std::pair(4, 12), std::pair(12, 12)}) {
    EXPECT_EQ(r.buf.color[r.buf.index(x, y)], plain);
    EXPECT_EQ(r.buf.color[r.buf.index(x - 2, y - 1)], plain);
    EXPECT_EQ(r.buf.depth[r.buf.index(x + 1, y + 1)], kNoDepth);  // (1.5, 1.5) is 2.12 away
  }
}

TEST(SceneRendererPhases, EyeDomeDarkensEverySampleOfSmallSplatsAndNothingElse) {
  const PointCloud cloud = square();
  RenderParams p = front(16, 1);
  p.point_size_px = 4.0;
  SceneRenderer r(cloud, kNoFaces, p);
  project(r);
  r.size_splats();
  r.light_points();
  r.raster_points();
  const std::vector<std::uint32_t> before = r.buf.color;
  r.apply_eye_dome();
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) {
      const std::size_t i = r.buf.index(x, y);
      if (r.buf.depth[i] == kNoDepth) {
        EXPECT_EQ(r.buf.color[i], before[i]);
        continue;
      }
      // Every sample of a 4-pixel disc has an empty neighbour: each is darker in each channel.
      const Eigen::Vector3f was = detail::unpack(before[i]), now = detail::unpack(r.buf.color[i]);
      for (int c = 0; c < 3; ++c) EXPECT_LT(now[c], was[c]) << x << ", " << y;
    }
}

TEST(SceneRendererPhases, DownsampleAveragesSamplesOverTheBackground) {
  const PointCloud cloud = square();
  const RenderParams p = front(8, 2);
  SceneRenderer r(cloud, kNoFaces, p);
  r.buf = Buffers(16, 16);
  for (int k = 0; k < 4; ++k) {  // pixel (0, 0): all four samples; pixel (1, 0): the left two
    r.buf.depth[r.buf.index(k % 2, k / 2)] = 0.f;
    r.buf.color[r.buf.index(k % 2, k / 2)] = detail::pack(Eigen::Vector3f(100, 50, 0));
  }
  for (int y = 0; y < 2; ++y) {
    r.buf.depth[r.buf.index(2, y)] = 0.f;
    r.buf.color[r.buf.index(2, y)] = detail::pack(Eigen::Vector3f(0, 0, 0));
  }
  r.downsample();
  ASSERT_EQ(r.image.width, 8);
  const auto rgb = [&](int x, int y) { return std::vector<int>(r.image.at(x, y), r.image.at(x, y) + 3); };
  EXPECT_EQ(rgb(0, 0), (std::vector<int>{100, 50, 0}));
  EXPECT_EQ(rgb(1, 0), (std::vector<int>{128, 128, 128}));  // half of the top row's white, rounded
  EXPECT_EQ(rgb(2, 0), (std::vector<int>{255, 255, 255}));
  EXPECT_EQ(rgb(5, 7), (std::vector<int>{222, 226, 234}));  // the bottom row's grey
}

TEST(SceneRendererPhases, ScaleBarOfARoundLengthAtTheBottomLeft) {
  const PointCloud cloud = square();
  const RenderParams p = front(100, 1);
  SceneRenderer r(cloud, kNoFaces, p);
  r.lay_out();
  r.image = Image(100, 100);
  r.out.pixels_per_unit = 10.0;  // a fifth of the plot is 2 units: a bar of 2 units, 20 pixels
  r.annotate();
  // From x = 10 (the font size) to 29, three pixels high above y = 90.
  for (int x = 10; x < 30; ++x)
    for (int y = 88; y <= 90; ++y) EXPECT_EQ(r.image.at(x, y)[0], 40) << x << ", " << y;
  EXPECT_EQ(r.image.at(30, 90)[0], 255);
  EXPECT_EQ(r.image.at(9, 90)[0], 255);
  EXPECT_EQ(r.image.at(20, 87)[0], 255);
}

}  // namespace
}  // namespace pointsurf
