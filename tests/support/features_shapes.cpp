// SPDX-License-Identifier: GPL-3.0-or-later
// Self-contained (no gtest, no other support file), so bench/features can compile it in too.
#include "features_shapes.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <random>
#include <utility>

#include <Eigen/Geometry>


namespace pointsurf::test {
namespace {

using Rng = std::mt19937_64;
using Sample = std::pair<Vector3d, Vector3d>;  // position, outward normal

struct Segment {
  Vector3d a, b;
};
struct Circle {  // horizontal circle
  Vector3d center;
  double radius;
};

double distance_to_segment(const Vector3d& q, const Segment& s) {
  const Vector3d d = s.b - s.a;
  const double t = std::clamp((q - s.a).dot(d) / d.squaredNorm(), 0.0, 1.0);
  return (q - (s.a + t * d)).norm();
}

double distance_to_circle(const Vector3d& q, const Circle& c) {
  const double rho = std::hypot(q.x() - c.center.x(), q.y() - c.center.y());
  return std::hypot(rho - c.radius, q.z() - c.center.z());
}

// A surface piece: its area and an area-uniform sampler.
struct Piece {
  double area;
  std::function<Sample(Rng&)> sample;
};

Piece triangle(const Vector3d& a, const Vector3d& b, const Vector3d& c, const Vector3d& normal) {
  return {0.5 * (b - a).cross(c - a).norm(), [=](Rng& rng) {
            std::uniform_real_distribution<double> u(0.0, 1.0);
            double s = u(rng), t = u(rng);
            if (s + t > 1.0) s = 1.0 - s, t = 1.0 - t;
            return Sample{a + s * (b - a) + t * (c - a), normal};
          }};
}

Piece parallelogram(const Vector3d& o, const Vector3d& e1, const Vector3d& e2, const Vector3d& normal) {
  return {e1.cross(e2).norm(), [=](Rng& rng) {
            std::uniform_real_distribution<double> u(0.0, 1.0);
            const double s = u(rng);
            const double t = u(rng);
            return Sample{o + s * e1 + t * e2, normal};
          }};
}

FeatureShape sample_pieces(const std::vector<Piece>& pieces, const std::vector<Segment>& segments, const std::vector<Circle>& circles,
                           const std::vector<Vector3d>& corners, std::size_t n, std::uint64_t seed) {
  std::vector<double> areas;
  for (const Piece& p : pieces) areas.push_back(p.area);
  std::discrete_distribution<std::size_t> pick(areas.begin(), areas.end());
  Rng rng(seed);
  FeatureShape shape;
  shape.cloud.positions.reserve(n);
  shape.cloud.normals.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const auto [p, normal] = pieces[pick(rng)].sample(rng);
    double edge = std::numeric_limits<double>::infinity(), corner = edge;
    for (const Segment& s : segments) edge = std::min(edge, distance_to_segment(p, s));
    for (const Circle& c : circles) edge = std::min(edge, distance_to_circle(p, c));
    for (const Vector3d& c : corners) corner = std::min(corner, (p - c).norm());
    shape.cloud.positions.push_back(p);
    shape.cloud.normals.push_back(normal);
    shape.edge_distance.push_back(edge);
    shape.corner_distance.push_back(corner);
  }
  return shape;
}

}  // namespace

FeatureShape sample_cube_features(std::size_t n, double half, std::uint64_t seed) {
  FeatureShape shape;
  Rng rng(seed);
  std::uniform_real_distribution<double> u(-half, half);
  std::uniform_int_distribution<int> face(0, 5);
  for (std::size_t i = 0; i < n; ++i) {
    const int f = face(rng);
    const int axis = f / 2;
    const double sign = (f % 2 == 0) ? 1.0 : -1.0;
    const double a = u(rng);
    const double b = u(rng);
    Vector3d p, normal = Vector3d::Zero();
    p[axis] = sign * half;
    p[(axis + 1) % 3] = a;
    p[(axis + 2) % 3] = b;
    normal[axis] = sign;
    shape.cloud.positions.push_back(p);
    shape.cloud.normals.push_back(normal);
  }
  for (std::size_t i = 0; i < shape.cloud.size(); ++i) {
    const Vector3d& p = shape.cloud.positions[i];
    const Vector3d& normal = shape.cloud.normals[i];
    double edge = std::numeric_limits<double>::infinity();
    Vector3d to_corner = Vector3d::Zero();
    for (int a = 0; a < 3; ++a) {
      if (normal[a] != 0.0) continue;  // the two in-face axes
      edge = std::min(edge, half - std::abs(p[a]));
      to_corner[a] = half - std::abs(p[a]);
    }
    shape.edge_distance.push_back(edge);
    shape.corner_distance.push_back(to_corner.norm());
  }
  return shape;
}

FeatureShape sample_cad_part(std::size_t n, std::uint64_t seed) {
  const Vector3d ex = Vector3d::UnitX(), ey = Vector3d::UnitY(), ez = Vector3d::UnitZ();
  const double x0 = -2.0, x1 = 2.0, y0 = -1.5, y1 = 1.5, h = 0.5;  // plate
  const double c = 0.25;                                            // chamfer width and height
  const double xs = 1.0, hs = 0.9;                                  // step block x >= xs, top at hs
  const Vector3d cyl(-0.5, 0.0, h);                                 // cylinder foot centre
  const double r = 0.5, hc = 0.6;                                   // its radius and height
  const double w = y1 - y0;
  const Vector3d chamfer_normal = Vector3d(-1.0, 0.0, 1.0).normalized();

  std::vector<Piece> pieces;
  pieces.push_back(parallelogram({x0, y0, 0.0}, (x1 - x0) * ex, w * ey, -ez));                      // bottom
  pieces.push_back(parallelogram({x0, y0, 0.0}, w * ey, c * ez, -ex));                              // left
  pieces.push_back(parallelogram({x0, y0, c}, w * ey, Vector3d(c, 0.0, h - c), chamfer_normal));   // chamfer
  pieces.push_back(parallelogram({x1, y0, 0.0}, w * ey, hs * ez, ex));                              // right
  pieces.push_back(parallelogram({xs, y0, hs}, (x1 - xs) * ex, w * ey, ez));                        // step top
  pieces.push_back(parallelogram({xs, y0, h}, w * ey, (hs - h) * ez, -ex));                         // step wall
  for (const double y : {y0, y1}) {                                                                 // front, back
    const Vector3d normal = y == y0 ? Vector3d(-ey) : ey;
    const Vector3d a(x0, y, 0.0), b(x1, y, 0.0), cc(x1, y, h), d(x0 + c, y, h), e(x0, y, c);
    pieces.push_back(triangle(a, b, cc, normal));
    pieces.push_back(triangle(a, cc, d, normal));
    pieces.push_back(triangle(a, d, e, normal));
    pieces.push_back(parallelogram({xs, y, h}, (x1 - xs) * ex, (hs - h) * ez, normal));
  }
  // Plate top between chamfer and step, minus the cylinder's foot (rejection sampling).
  const double top_area = (xs - x0 - c) * w - std::numbers::pi * r * r;
  pieces.push_back({top_area, [=](Rng& rng) {
                      std::uniform_real_distribution<double> ux(x0 + c, xs), uy(y0, y1);
                      for (;;) {
                        const double x = ux(rng);
                        const double y = uy(rng);
                        if (std::hypot(x - cyl.x(), y - cyl.y()) >= r) return Sample{{x, y, h}, ez};
                      }
                    }});
  pieces.push_back({2.0 * std::numbers::pi * r * hc, [=](Rng& rng) {
                      std::uniform_real_distribution<double> ua(0.0, 2.0 * std::numbers::pi), uz(0.0, hc);
                      const double a = ua(rng);
                      const double z = uz(rng);
                      const Vector3d radial(std::cos(a), std::sin(a), 0.0);
                      return Sample{cyl + r * radial + z * ez, radial};
                    }});
  pieces.push_back({std::numbers::pi * r * r, [=](Rng& rng) {
                      std::uniform_real_distribution<double> ua(0.0, 2.0 * std::numbers::pi), u(0.0, 1.0);
                      const double a = ua(rng);
                      const double rho = r * std::sqrt(u(rng));
                      return Sample{cyl + Vector3d(rho * std::cos(a), rho * std::sin(a), hc), ez};
                    }});

  std::vector<Segment> segments = {
      {{x0, y0, 0.0}, {x1, y0, 0.0}}, {{x0, y1, 0.0}, {x1, y1, 0.0}},   // bottom, along x
      {{x0, y0, 0.0}, {x0, y1, 0.0}}, {{x1, y0, 0.0}, {x1, y1, 0.0}},   // bottom, along y
      {{x0, y0, c}, {x0, y1, c}},     {{x0 + c, y0, h}, {x0 + c, y1, h}}, // chamfer's two edges
      {{xs, y0, h}, {xs, y1, h}},                                       // step foot (concave)
      {{xs, y0, hs}, {xs, y1, hs}},   {{x1, y0, hs}, {x1, y1, hs}},     // step top
  };
  for (const double y : {y0, y1}) {
    segments.push_back({{x0, y, 0.0}, {x0, y, c}});         // left vertical
    segments.push_back({{x0, y, c}, {x0 + c, y, h}});       // chamfer side
    segments.push_back({{x0 + c, y, h}, {xs, y, h}});       // plate top side
    segments.push_back({{xs, y, h}, {xs, y, hs}});          // step wall side
    segments.push_back({{xs, y, hs}, {x1, y, hs}});         // step top side
    segments.push_back({{x1, y, 0.0}, {x1, y, hs}});        // right vertical
  }
  const std::vector<Circle> circles = {{cyl, r}, {cyl + hc * ez, r}};
  std::vector<Vector3d> corners;
  for (const double y : {y0, y1})
    for (const Vector3d& v : {Vector3d(x0, y, 0.0), Vector3d(x1, y, 0.0), Vector3d(x0, y, c), Vector3d(x0 + c, y, h),
                              Vector3d(xs, y, h), Vector3d(xs, y, hs), Vector3d(x1, y, hs)})
      corners.push_back(v);
  return sample_pieces(pieces, segments, circles, corners, n, seed);
}

void add_feature_noise(FeatureShape& shape, double sigma, std::uint64_t seed) {
  Rng rng(seed);
  std::normal_distribution<double> g(0.0, sigma);
  for (Vector3d& p : shape.cloud.positions) {
    const double dx = g(rng), dy = g(rng), dz = g(rng);
    p += Vector3d(dx, dy, dz);
  }
}

FeatureScore score_features(const std::vector<double>& labels, const std::vector<double>& edge_distance, double truth,
                            double tolerance) {
  FeatureScore s;
  std::size_t correct = 0, found = 0;
  for (std::size_t i = 0; i < labels.size(); ++i) {
    const bool labelled = labels[i] != 0.0;
    s.labelled += labelled;
    correct += labelled && edge_distance[i] <= tolerance;
    if (edge_distance[i] <= truth) {
      ++s.truth;
      found += labelled;
    }
  }
  s.precision = s.labelled == 0 ? 0.0 : double(correct) / double(s.labelled);
  s.recall = s.truth == 0 ? 0.0 : double(found) / double(s.truth);
  return s;
}

}  // namespace pointsurf::test
