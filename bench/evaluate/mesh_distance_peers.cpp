// SPDX-License-Identifier: GPL-3.0-or-later
// mesh_distance_peers MESH.ply POINTS.ply TOOL OUT.bin
//   Unsigned point-to-mesh distances through another library's hierarchy, timed like
//   `mesh_distance_runner time ... unsigned` (hierarchy build plus queries, file reading
//   excluded), so pointsurf's hand-written TriangleBvh has a measured reason:
//     pointsurf  TriangleBvh::closest_near (what pointsurf evaluate runs)
//     cgal       CGAL 5.5 AABB_tree over Simple_cartesian<double> triangles,
//                closest_point_and_primitive (exact in double, single hierarchy)
//     embree     Embree 3 rtcPointQuery over a float32 triangle scene with a closest-point
//                callback that measures the double triangle (pointsurf's exact Ericson test);
//                the callback shrinks the float query radius only to the distance found
//                widened by 1e-6 relative plus 1e-6 of the extent, so the float boxes
//                (built from corners rounded to float) cull no triangle that could be closer
//   All tools: coordinates about the centre of the mesh's box, queries in pointsurf's Morton
//   order, parallel over TBB blocks of 1024 (the same work split as pointsurf).
//   Writes the N distances as float64 to OUT.bin and prints one JSON object.
// Exit codes: 0 ok, 1 usage or a tool not built in, 2 unreadable input.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#ifdef POINTSURF_BENCH_EMBREE
#include <embree3/rtcore.h>
#endif

#include "../bench_util.h"
#include "pointsurf/core/error.h"
#include "pointsurf/evaluate/triangle_bvh.h"
#include "pointsurf/io/io.h"
#include "pointsurf/spatial/kd_tree.h"

namespace {

using namespace pointsurf;

struct Timing {
  double build = 0.0;
};

// Queries in Morton order, blocks of 1024, `one(i)` answers point i.
template <class One>
void for_queries(const std::vector<std::uint32_t>& order, One&& one) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, order.size(), 1024), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t k = r.begin(); k != r.end(); ++k) one(static_cast<std::size_t>(order[k]));
  });
}

std::vector<double> run_pointsurf(const TriangleMesh& mesh, const std::vector<Vector3d>& points, const std::vector<std::uint32_t>& order,
                                  Timing& t) {
  const auto start = bench::Clock::now();
  const TriangleBvh bvh(mesh);
  t.build = bench::seconds_since(start);
  std::vector<double> d(points.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, order.size(), 1024), [&](const tbb::blocked_range<std::size_t>& r) {
    int previous = -1;
    for (std::size_t k = r.begin(); k != r.end(); ++k) {
      const std::size_t i = order[k];
      const ClosestPoint c = bvh.closest_near(points[i], previous);
      previous = c.triangle;
      d[i] = std::sqrt(c.squared_distance);
    }
  });
  return d;
}

std::vector<double> run_cgal(const TriangleMesh& mesh, const std::vector<Vector3d>& points, const std::vector<std::uint32_t>& order,
                             Timing& t, const Vector3d& origin) {
  using K = CGAL::Simple_cartesian<double>;
  using Triangles = std::vector<K::Triangle_3>;
  using Primitive = CGAL::AABB_triangle_primitive<K, Triangles::const_iterator>;
  using Tree = CGAL::AABB_tree<CGAL::AABB_traits<K, Primitive>>;
  const auto start = bench::Clock::now();
  Triangles triangles;
  triangles.reserve(mesh.triangles.size());
  auto at = [&](int v) {
    const Vector3d p = mesh.vertices.positions[static_cast<std::size_t>(v)] - origin;
    return K::Point_3(p.x(), p.y(), p.z());
  };
  for (const Triangle& f : mesh.triangles) triangles.emplace_back(at(f[0]), at(f[1]), at(f[2]));
  Tree tree(triangles.begin(), triangles.end());
  tree.accelerate_distance_queries();  // builds the hierarchy and the kd-tree of hints
  t.build = bench::seconds_since(start);
  std::vector<double> d(points.size());
  for_queries(order, [&](std::size_t i) {
    const Vector3d q = points[i] - origin;
    const K::Point_3 p(q.x(), q.y(), q.z());
    const auto hit = tree.closest_point_and_primitive(p);
    d[i] = std::sqrt(CGAL::squared_distance(p, hit.first));
  });
  return d;
}

#ifdef POINTSURF_BENCH_EMBREE
struct EmbreeQuery {
  const std::vector<Vector3d>* corners;  // 3 per triangle, double, about the origin
  Vector3d p;
  double best2 = std::numeric_limits<double>::infinity();
  double slack = 0.0;  // absolute widening of the float radius
};

bool embree_closest(RTCPointQueryFunctionArguments* args) {
  auto* q = static_cast<EmbreeQuery*>(args->userPtr);
  const std::size_t t = args->primID;
  const std::vector<Vector3d>& c = *q->corners;
  const ClosestPoint r = closest_point_on_triangle(q->p, c[3 * t], c[3 * t + 1], c[3 * t + 2]);
  if (r.squared_distance < q->best2) {
    q->best2 = r.squared_distance;
    const float radius = static_cast<float>(std::sqrt(r.squared_distance) * (1.0 + 1e-6) + q->slack);
    if (radius < args->query->radius) {
      args->query->radius = radius;
      return true;
    }
  }
  return false;
}

std::vector<double> run_embree(const TriangleMesh& mesh, const std::vector<Vector3d>& points, const std::vector<std::uint32_t>& order,
                               Timing& t, const Vector3d& origin, double extent) {
  const auto start = bench::Clock::now();
  RTCDevice device = rtcNewDevice(nullptr);
  RTCScene scene = rtcNewScene(device);
  RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  const std::size_t nv = mesh.vertices.positions.size(), nf = mesh.triangles.size();
  auto* v = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), nv));
  for (std::size_t i = 0; i < nv; ++i) {
    const Vector3d p = mesh.vertices.positions[i] - origin;
    for (int k = 0; k < 3; ++k) v[3 * i + std::size_t(k)] = static_cast<float>(p[k]);
  }
  auto* f = static_cast<unsigned*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), nf));
  for (std::size_t i = 0; i < nf; ++i)
    for (int k = 0; k < 3; ++k) f[3 * i + std::size_t(k)] = static_cast<unsigned>(mesh.triangles[i][k]);
  rtcCommitGeometry(geometry);
  rtcAttachGeometry(scene, geometry);
  rtcReleaseGeometry(geometry);
  rtcCommitScene(scene);
  std::vector<Vector3d> corners(3 * nf);
  tbb::parallel_for(std::size_t(0), nf, [&](std::size_t i) {
    for (int k = 0; k < 3; ++k) corners[3 * i + std::size_t(k)] = mesh.vertices.positions[std::size_t(mesh.triangles[i][k])] - origin;
  });
  t.build = bench::seconds_since(start);
  std::vector<double> d(points.size());
  for_queries(order, [&](std::size_t i) {
    EmbreeQuery q{&corners, points[i] - origin};
    q.slack = 1e-6 * extent;
    RTCPointQuery query;
    query.x = static_cast<float>(q.p.x());
    query.y = static_cast<float>(q.p.y());
    query.z = static_cast<float>(q.p.z());
    query.radius = std::numeric_limits<float>::infinity();
    query.time = 0.0f;
    RTCPointQueryContext context;
    rtcInitPointQueryContext(&context);
    rtcPointQuery(scene, &query, &context, embree_closest, &q);
    d[i] = std::sqrt(q.best2);
  });
  rtcReleaseScene(scene);
  rtcReleaseDevice(device);
  return d;
}
#endif

}  // namespace

int main(int argc, char** argv) {
  try {
    if (argc != 5) {
      fmt::print(stderr, "usage: mesh_distance_peers MESH POINTS pointsurf|cgal|embree OUT.bin\n");
      return 1;
    }
    const TriangleMesh mesh = read_mesh(argv[1]).mesh;
    const std::vector<Vector3d> points = read_point_cloud(argv[2]).cloud.positions;
    const std::string tool = argv[3];
    const BoundingBox box = bounding_box(mesh.vertices.positions);
    const Vector3d origin = box.center();
    const double rss_before = bench::peak_rss_mb(), cpu_before = bench::cpu_seconds();
    const auto start = bench::Clock::now();
    const std::vector<std::uint32_t> order = morton_order(points);
    Timing timing;
    std::vector<double> d;
    if (tool == "pointsurf") d = run_pointsurf(mesh, points, order, timing);
    else if (tool == "cgal") d = run_cgal(mesh, points, order, timing, origin);
#ifdef POINTSURF_BENCH_EMBREE
    else if (tool == "embree") d = run_embree(mesh, points, order, timing, origin, box.diagonal());
#endif
    else {
      fmt::print(stderr, "mesh_distance_peers: unknown or not built-in tool {}\n", tool);
      return 1;
    }
    const double seconds = bench::seconds_since(start), cpu = bench::cpu_seconds() - cpu_before;
    std::ofstream(argv[4], std::ios::binary).write(reinterpret_cast<const char*>(d.data()), std::streamsize(d.size() * sizeof(double)));
    fmt::print("{{\"mode\": \"{}\", \"seconds\": {:.4f}, \"build_seconds\": {:.4f}, \"cpu_seconds\": {:.4f}, \"peak_rss_mb\": {:.1f}, "
               "\"rss_before_mb\": {:.1f}, \"points\": {}, \"triangles\": {}}}\n",
               tool, seconds, timing.build, cpu, bench::peak_rss_mb(), rss_before, points.size(), mesh.triangles.size());
    return 0;
  } catch (const pointsurf::Error& e) {
    fmt::print(stderr, "mesh_distance_peers: {}\n", e.what());
    return e.exit_code();
  } catch (const std::exception& e) {
    fmt::print(stderr, "mesh_distance_peers: {}\n", e.what());
    return 2;
  }
}
