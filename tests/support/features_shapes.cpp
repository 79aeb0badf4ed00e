// SPDX-License-Identifier: GPL-3.0-or-later
// Self-contained (no gtest, no other support file), so bench/features can compile it in too.
#include "features_shapes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <random>
#include <map>
#include <optional>
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

SharpEdges::SharpEdges(const TriangleMesh& mesh, double sharp_deg) {
  const auto& v = mesh.vertices.positions;
  std::vector<Vector3d> face_normals;
  double area = 0.0;
  for (const Triangle& t : mesh.triangles) {
    const Vector3d c = (v[t[1]] - v[t[0]]).cross(v[t[2]] - v[t[0]]);
    area += 0.5 * c.norm();
    face_normals.push_back(c.norm() > 0.0 ? Vector3d(c.normalized()) : Vector3d::Zero());
  }
  std::map<std::array<double, 3>, int> first_at;
  std::vector<int> weld(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) weld[i] = first_at.try_emplace({v[i].x(), v[i].y(), v[i].z()}, int(i)).first->second;
  std::map<std::pair<int, int>, std::vector<std::size_t>> edge_faces;
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f)
    for (int e = 0; e < 3; ++e) {
      const int a = weld[mesh.triangles[f][e]], b = weld[mesh.triangles[f][(e + 1) % 3]];
      if (a != b) edge_faces[{std::min(a, b), std::max(a, b)}].push_back(f);
    }
  const double cos_sharp = std::cos(sharp_deg * std::numbers::pi / 180.0);
  std::map<int, int> degree;
  for (const auto& [edge, faces] : edge_faces) {
    if (faces.size() != 2) continue;
    const Vector3d &na = face_normals[faces[0]], &nb = face_normals[faces[1]];
    if (na.squaredNorm() == 0.0 || nb.squaredNorm() == 0.0 || na.dot(nb) > cos_sharp + 1e-12) continue;
    segments_.push_back({v[edge.first], v[edge.second]});
    turn_deg_.push_back(std::acos(std::clamp(na.dot(nb), -1.0, 1.0)) * 180.0 / std::numbers::pi);
    ++degree[edge.first];
    ++degree[edge.second];
  }
  for (const auto& [vertex, count] : degree)
    if (count >= 3) corners_.push_back(v[vertex]);
  // Points laid along the segments every step (about the spacing of 100k samples): the nearest
  // segment is among those with a laid point within (nearest laid distance + step).
  step_ = std::max(1e-12, std::sqrt(area / 1e5));
  for (std::size_t e = 0; e < segments_.size(); ++e) {
    const auto& [a, b] = segments_[e];
    const int steps = std::max(1, int(std::ceil((b - a).norm() / step_)));
    for (int k = 0; k <= steps; ++k) {
      laid_.push_back(a + (b - a) * (double(k) / steps));
      laid_segment_.push_back(std::uint32_t(e));
    }
  }
  if (!laid_.empty()) laid_tree_ = std::make_shared<const KdTree>(laid_);
}

double SharpEdges::distance(const Vector3d& p, double* turn_deg) const {
  double best = std::numeric_limits<double>::infinity(), turn = 0.0;
  if (laid_tree_) {
    std::vector<Neighbor> nb;
    laid_tree_->knn(p, 1, nb);
    laid_tree_->radius(p, std::sqrt(nb[0].squared_distance) + step_, nb);
    for (const Neighbor& q : nb) {
      const std::uint32_t e = laid_segment_[q.index];
      if (const double d = distance_to_segment(p, {segments_[e][0], segments_[e][1]}); d < best) best = d, turn = turn_deg_[e];
    }
  }
  if (turn_deg != nullptr) *turn_deg = turn;
  return best;
}

FeatureShape sample_mesh_features(const TriangleMesh& mesh, std::size_t n, double sharp_deg, std::uint64_t seed) {
  const auto& v = mesh.vertices.positions;
  std::vector<double> areas;
  std::vector<Vector3d> face_normals;
  for (const Triangle& t : mesh.triangles) {
    const Vector3d c = (v[t[1]] - v[t[0]]).cross(v[t[2]] - v[t[0]]);
    areas.push_back(0.5 * c.norm());
    face_normals.push_back(c.norm() > 0.0 ? Vector3d(c.normalized()) : Vector3d::Zero());
  }
  FeatureShape shape;
  std::discrete_distribution<std::size_t> pick(areas.begin(), areas.end());
  Rng rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t f = pick(rng);
    double a = u(rng), b = u(rng);
    if (a + b > 1.0) a = 1.0 - a, b = 1.0 - b;
    const Triangle& t = mesh.triangles[f];
    shape.cloud.positions.push_back(v[t[0]] + a * (v[t[1]] - v[t[0]]) + b * (v[t[2]] - v[t[0]]));
    shape.cloud.normals.push_back(face_normals[f]);
  }
  const SharpEdges sharp(mesh, sharp_deg);
  std::optional<KdTree> corner_tree;
  if (!sharp.corners().empty()) corner_tree.emplace(sharp.corners());
  std::vector<Neighbor> nb;
  for (const Vector3d& p : shape.cloud.positions) {
    double turn = 0.0;
    shape.edge_distance.push_back(sharp.distance(p, &turn));
    shape.edge_turn_deg.push_back(turn);
    double corner = std::numeric_limits<double>::infinity();
    if (corner_tree) {
      corner_tree->knn(p, 1, nb);
      corner = std::sqrt(nb[0].squared_distance);
    }
    shape.corner_distance.push_back(corner);
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
