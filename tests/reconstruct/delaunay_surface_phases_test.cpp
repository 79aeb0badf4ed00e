// SPDX-License-Identifier: GPL-3.0-or-later
// The phases of extract_delaunay_surface (reconstruct/detail/delaunay_surface.h), each run alone
// on hand-made samples and poles: a regular tetrahedron, two of them, a fin on one, a flat grid
// with a sliver on its rim.
#include "reconstruct/detail/delaunay_surface.h"

#include <algorithm>
#include <array>
#include <numeric>
#include <set>
#include <utility>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

namespace pointsurf::detail {
namespace {

using Tris = std::vector<std::array<int, 3>>;

// Samples `pts` (already about their origin) with spacing 1, no pole vectors (zero), every pole
// finite and no sample on the hull.
DelaunaySetup make_setup(const std::vector<Vector3d>& pts) {
  DelaunaySetup s;
  s.p = pts;
  s.spacing = 1.0;
  const std::size_t n = pts.size();
  s.cells.representative.resize(n);
  std::iota(s.cells.representative.begin(), s.cells.representative.end(), 0);
  s.poles.axis.assign(n, Vector3d::Zero());
  s.poles.hull_normal.assign(n, Vector3d::Zero());
  s.poles.on_hull.assign(n, 0);
  s.poles.finite_pole.assign(n, 1);
  return s;
}

PointCloud cloud_of(const std::vector<Vector3d>& pts) {
  PointCloud c;
  c.positions = pts;
  return c;
}

// A regular tetrahedron about the origin (its centroid), shifted by `shift`.
std::vector<Vector3d> tetrahedron(const Vector3d& shift = Vector3d::Zero()) {
  return {Vector3d(1, 1, 1) + shift, Vector3d(1, -1, -1) + shift, Vector3d(-1, 1, -1) + shift, Vector3d(-1, -1, 1) + shift};
}

Tris tetrahedron_faces(int first = 0) {
  const int a = first, b = first + 1, c = first + 2, d = first + 3;
  return {{a, b, c}, {a, b, d}, {a, c, d}, {b, c, d}};
}

DelaunaySurfaceParams params_with(DelaunayBoundary boundary, double sharp_deg = 360.0) {
  DelaunaySurfaceParams p;
  p.boundary = boundary;
  p.sharp_edge_angle_deg = sharp_deg;
  p.max_boundary_edge_in_spacings = 0.0;
  return p;
}

Vector3d face_normal(const std::vector<Vector3d>& p, const Triangle& t) {
  return (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]);
}

// Runs the phases up to and including the walk.
void walk(DelaunayExtraction& x) {
  x.index_edges();
  x.prune_sharp_edges();
  x.split_pieces();
  x.walk_pieces();
}

TEST(DelaunayExtractionPhases, NormalFilterDropsStrayAndDegenerateTriangles) {
  // Pole vectors along z: the triangle in the xy plane passes, the one in the xz plane strays by
  // 90 degrees, the one on the x axis is degenerate.
  const std::vector<Vector3d> pts{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {2, 0, 0}};
  DelaunaySetup setup = make_setup(pts);
  setup.poles.axis.assign(pts.size(), Vector3d::UnitZ());
  const PointCloud cloud = cloud_of(pts);
  DelaunaySurfaceParams params = params_with(DelaunayBoundary::Auto);
  params.normal_filter_angle_deg = 30.0;
  DelaunaySurfaceStats stats;
  DelaunayExtraction x(cloud, setup, {{0, 1, 3}, {0, 1, 2}, {0, 1, 4}, {1, 2, 4}}, params, stats);
  x.filter_by_normals();
  EXPECT_EQ(x.candidates, (Tris{{0, 1, 2}, {1, 2, 4}}));
  EXPECT_EQ(stats.candidate_triangles, 4u);
  EXPECT_EQ(stats.normal_filtered, 2u);
}

TEST(DelaunayExtractionPhases, IndexEdgesOfATetrahedronGivesSixEdgesOfTwoTriangles) {
  const std::vector<Vector3d> pts = tetrahedron();
  const DelaunaySetup setup = make_setup(pts);
  const PointCloud cloud = cloud_of(pts);
  const DelaunaySurfaceParams params = params_with(DelaunayBoundary::Closed);
  DelaunaySurfaceStats stats;
  DelaunayExtraction x(cloud, setup, tetrahedron_faces(), params, stats);
  x.index_edges();
  ASSERT_EQ(x.cx.tris, tetrahedron_faces());
  ASSERT_EQ(x.cx.edge_verts.size(), 6u);
  for (std::size_t e = 0; e < 6; ++e) EXPECT_EQ(x.cx.edge_start[e + 1] - x.cx.edge_start[e], 2u);
  for (std::size_t t = 0; t < 4; ++t)
    for (int k = 0; k < 3; ++k) {
      const int a = x.cx.tris[t][k], b = x.cx.tris[t][(k + 1) % 3];
      EXPECT_EQ(x.cx.edge_verts[x.cx.tri_edges[t][k]], (std::array<int, 2>{std::min(a, b), std::max(a, b)}));
    }
  EXPECT_EQ(x.alive, std::vector<char>(4, 1));
}

TEST(DelaunayExtractionPhases, PruningRemovesAFinOnAClosedPieceOnly) {
  // A tetrahedron with a fin (triangle 4) on its edge 0-1: two rim edges. The angular gap test
  // is off (360 degrees), so only the rim decides.
  std::vector<Vector3d> pts = tetrahedron();
  pts.emplace_back(3, 0, 0);
  const DelaunaySetup setup = make_setup(pts);
  const PointCloud cloud = cloud_of(pts);
  Tris tris = tetrahedron_faces();
  tris.push_back({0, 1, 4});
  for (const auto& [boundary, pruned, closed, open] :
       {std::array<std::size_t, 4>{std::size_t(DelaunayBoundary::Closed), 1, 0, 0},
        std::array<std::size_t, 4>{std::size_t(DelaunayBoundary::Open), 0, 0, 0},
        std::array<std::size_t, 4>{std::size_t(DelaunayBoundary::Auto), 1, 1, 0}}) {
    const DelaunaySurfaceParams params = params_with(DelaunayBoundary(boundary));
    DelaunaySurfaceStats stats;
    DelaunayExtraction x(cloud, setup, tris, params, stats);
    x.index_edges();
    x.prune_sharp_edges();
    EXPECT_EQ(stats.pruned, pruned) << boundary;
    EXPECT_EQ(x.alive, (std::vector<char>{1, 1, 1, 1, char(pruned == 1 ? 0 : 1)})) << boundary;
    EXPECT_EQ(stats.closed_pieces, closed) << boundary;  // counted here under Auto only
    EXPECT_EQ(stats.open_pieces, open) << boundary;
  }
}

TEST(DelaunayExtractionPhases, PruningRemovesTheTrianglesAtAnEdgeSharperThanTheGap) {
  // At each edge of a regular tetrahedron the two faces leave a gap of 360 - 70.5 degrees.
  const std::vector<Vector3d> pts = tetrahedron();
  const DelaunaySetup setup = make_setup(pts);
  const PointCloud cloud = cloud_of(pts);
  for (const auto& [sharp_deg, pruned] : {std::pair{280.0, std::size_t{4}}, std::pair{300.0, std::size_t{0}}}) {
    const DelaunaySurfaceParams params = params_with(DelaunayBoundary::Open, sharp_deg);
    DelaunaySurfaceStats stats;
    DelaunayExtraction x(cloud, setup, tetrahedron_faces(), params, stats);
    x.index_edges();
    x.prune_sharp_edges();
    EXPECT_EQ(stats.pruned, pruned) << sharp_deg;
  }
}

TEST(DelaunayExtractionPhases, SplitPiecesOfTwoTetrahedra) {
  std::vector<Vector3d> pts = tetrahedron();
  for (const Vector3d& q : tetrahedron(Vector3d(10, 0, 0))) pts.push_back(q);
  const DelaunaySetup setup = make_setup(pts);
  const PointCloud cloud = cloud_of(pts);
  // Interleaved, so that the pieces' lists differ from the input order.
  const Tris second = tetrahedron_faces(4);
  Tris tris;
  for (std::size_t t = 0; t < 4; ++t) {
    tris.push_back(tetrahedron_faces()[t]);
    tris.push_back(second[t]);
  }
  const DelaunaySurfaceParams params = params_with(DelaunayBoundary::Closed);
  DelaunaySurfaceStats stats;
  DelaunayExtraction x(cloud, setup, tris, params, stats);
  x.index_edges();
  x.alive[7] = 0;  // one face of the second tetrahedron gone
  x.split_pieces();
  EXPECT_EQ(x.piece_count, 2);
  EXPECT_EQ(x.piece_start, (std::vector<std::size_t>{0, 4, 7}));
  EXPECT_EQ(x.piece_tris, (std::vector<int>{0, 2, 4, 6, 1, 3, 5}));
  EXPECT_EQ(stats.closed_pieces, 2u);
}

TEST(DelaunayExtractionPhases, WalkOrientsEveryFaceOfATetrahedronOutwards) {
  const std::vector<Vector3d> pts = tetrahedron();
  const DelaunaySetup setup = make_setup(pts);
  const PointCloud cloud = cloud_of(pts);
  const DelaunaySurfaceParams params = params_with(DelaunayBoundary::Closed);
  DelaunaySurfaceStats stats;
  DelaunayExtraction x(cloud, setup, tetrahedron_faces(), params, stats);
  walk(x);
  ASSERT_EQ(x.out_tris.size(), 4u);
  EXPECT_EQ(stats.walk_dropped, 0u);
  std::set<std::pair<int, int>> directed;
  for (const Triangle& t : x.out_tris) {
    // The centroid is the origin: an outward face's normal points away from it.
    EXPECT_GT(face_normal(pts, t).dot(pts[t[0]] + pts[t[1]] + pts[t[2]]), 0.0);
    for (int k = 0; k < 3; ++k) directed.insert({t[k], t[(k + 1) % 3]});
  }
  EXPECT_EQ(directed.size(), 12u);  // each edge once each way
  std::vector<int> src = x.out_src;
  std::sort(src.begin(), src.end());
  EXPECT_EQ(src, (std::vector<int>{0, 1, 2, 3}));
  EXPECT_EQ(x.out_piece, (std::vector<int>(4, 0)));
  for (const auto& used : x.edge_used) EXPECT_TRUE(used[0] >= 0 && used[1] >= 0);
}

TEST(DelaunayExtractionPhases, RimPeelingRemovesALongSliverAtTheBorderOnly) {
  // A 3 x 3 grid of unit spacing in the xy plane, two triangles per cell (edges 1 and sqrt 2),
  // and a sliver from its edge (2, 0)-(2, 1) to the point (5, 1): two boundary edges of length
  // 3 and more, with the end (5, 1) on the border. A limit of 2 spacings peels the sliver only.
  std::vector<Vector3d> pts;
  for (int y = 0; y < 3; ++y)
    for (int x = 0; x < 3; ++x) pts.emplace_back(x, y, 0);
  pts.emplace_back(5, 1, 0);
  const DelaunaySetup setup = make_setup(pts);
  PointCloud cloud = cloud_of(pts);
  cloud.normals.assign(pts.size(), Vector3d::UnitZ());
  Tris tris;
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 2; ++x) {
      const int a = 3 * y + x;
      tris.push_back({a, a + 1, a + 4});
      tris.push_back({a, a + 3, a + 4});
    }
  tris.push_back({2, 5, 9});
  DelaunaySurfaceParams params = params_with(DelaunayBoundary::Open);
  params.max_boundary_edge_in_spacings = 2.0;
  DelaunaySurfaceStats stats;
  DelaunayExtraction x(cloud, setup, tris, params, stats);
  walk(x);
  ASSERT_EQ(x.out_tris.size(), 9u);
  x.peel_rim();
  EXPECT_EQ(stats.rim_peeled, 1u);
  ASSERT_EQ(x.out_tris.size(), 8u);
  EXPECT_EQ(x.out_src.size(), 8u);
  EXPECT_EQ(std::count(x.out_src.begin(), x.out_src.end(), 8), 0);
  // The grid's edge to the sliver is a boundary edge now.
  const int shared = x.cx.tri_edges[8][0];  // (2, 5)
  EXPECT_GE(x.edge_used[shared][0], 0);
  EXPECT_EQ(x.edge_used[shared][1], -1);
}

TEST(DelaunayExtractionPhases, OrientationFlipsAnInwardClosedPieceBySignedVolume) {
  const std::vector<Vector3d> pts = tetrahedron();
  const DelaunaySetup setup = make_setup(pts);
  const PointCloud cloud = cloud_of(pts);  // no normals: a closed piece goes by its volume
  const DelaunaySurfaceParams params = params_with(DelaunayBoundary::Closed);
  DelaunaySurfaceStats stats;
  DelaunayExtraction x(cloud, setup, tetrahedron_faces(), params, stats);
  walk(x);
  for (Triangle& t : x.out_tris) std::swap(t[1], t[2]);  // all inwards
  x.orient_pieces();
  EXPECT_EQ(stats.flipped_pieces, 1u);
  for (const Triangle& t : x.out_tris) EXPECT_GT(face_normal(pts, t).dot(pts[t[0]] + pts[t[1]] + pts[t[2]]), 0.0);
}

TEST(DelaunayExtractionPhases, OrientationFollowsTheCloudsNormals) {
  const std::vector<Vector3d> pts = tetrahedron();
  const DelaunaySetup setup = make_setup(pts);
  PointCloud cloud = cloud_of(pts);
  for (const Vector3d& q : pts) cloud.normals.push_back(-q.normalized());  // inward normals
  const DelaunaySurfaceParams params = params_with(DelaunayBoundary::Closed);
  DelaunaySurfaceStats stats;
  DelaunayExtraction x(cloud, setup, tetrahedron_faces(), params, stats);
  walk(x);  // outward
  x.orient_pieces();
  EXPECT_EQ(stats.flipped_pieces, 1u);
  for (const Triangle& t : x.out_tris) EXPECT_LT(face_normal(pts, t).dot(pts[t[0]] + pts[t[1]] + pts[t[2]]), 0.0);
}

TEST(DelaunayExtractionPhases, MeshNormalsAreThePoleVectorsSignedByTheFaces) {
  const std::vector<Vector3d> pts = tetrahedron();
  DelaunaySetup setup = make_setup(pts);
  for (std::size_t i = 0; i < pts.size(); ++i) setup.poles.axis[i] = -pts[i].normalized();  // inward
  setup.poles.finite_pole[3] = 0;  // a hull sample: takes its faces' mean normal
  setup.poles.axis[3] = Vector3d::UnitX();
  const PointCloud cloud = cloud_of(pts);
  const DelaunaySurfaceParams params = params_with(DelaunayBoundary::Closed);
  DelaunaySurfaceStats stats;
  DelaunayExtraction x(cloud, setup, tetrahedron_faces(), params, stats);
  walk(x);
  x.orient_pieces();
  x.build_mesh();
  const TriangleMesh& mesh = x.reconstruction.mesh;
  ASSERT_EQ(mesh.triangles.size(), 4u);
  ASSERT_EQ(mesh.vertices.normals.size(), 4u);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(mesh.vertices.normals[i], pts[i].normalized()) << i;
  // The three faces at a vertex of a regular tetrahedron sum to the direction of the vertex.
  EXPECT_NEAR((mesh.vertices.normals[3] - pts[3].normalized()).norm(), 0.0, 1e-12);
  EXPECT_EQ(x.reconstruction.mean_spacing, 1.0);
}

TEST(DelaunayExtractionPhases, SmallHoleFillingClosesAMissingFace) {
  const std::vector<Vector3d> pts = tetrahedron();
  const DelaunaySetup setup = make_setup(pts);
  PointCloud cloud = cloud_of(pts);
  for (const Vector3d& q : pts) cloud.normals.push_back(q.normalized());
  DelaunaySurfaceParams params = params_with(DelaunayBoundary::Open);
  params.max_hole_perimeter_in_spacings = 100.0;
  DelaunaySurfaceStats stats;
  Tris three = tetrahedron_faces();
  three.pop_back();
  DelaunayExtraction x(cloud, setup, three, params, stats);
  walk(x);
  x.build_mesh();
  ASSERT_EQ(x.reconstruction.mesh.triangles.size(), 3u);
  x.fill_small_holes();
  EXPECT_EQ(stats.holes_filled, 1u);
  EXPECT_EQ(stats.fill_triangles, 1u);
  EXPECT_EQ(x.reconstruction.mesh.triangles.size(), 4u);
  EXPECT_TRUE(x.reconstruction.topology.watertight());
  EXPECT_EQ(x.reconstruction.unused_points, 0u);
}

}  // namespace
}  // namespace pointsurf::detail
