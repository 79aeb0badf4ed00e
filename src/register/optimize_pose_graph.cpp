// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/register/pose_graph.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include "pointsurf/core/error.h"
#include "pointsurf/spatial/kd_tree.h"

namespace pointsurf {
namespace {

using Vector6d = Eigen::Matrix<double, 6, 1>;

// A pose in the graph's centred frame: x -> R x + t with x relative to the centre.
struct Pose {
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  Pose inverse() const { return {r.transpose(), -(r.transpose() * t)}; }
  friend Pose operator*(const Pose& a, const Pose& b) { return {a.r * b.r, a.r * b.t + a.t}; }
};

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

// The same motion as `t` in the frame whose origin is `c`: x_c -> T(x_c + c) - c. Evaluated
// through apply(c), which keeps the digits of a transform built about a nearby centre.
Pose centred(const RigidTransform& t, const Eigen::Vector3d& c) { return {t.rotation(), t.apply(c) - c}; }

RigidTransform world(const Pose& p, const Eigen::Vector3d& c) {
  return RigidTransform::about(c, RigidTransform::nearest_rotation(p.r), p.t);
}

// Rotation vector and translation of a motion near the identity: E x ~ x + w x x + t.
Vector6d residual_of(const Pose& e) {
  const Eigen::AngleAxisd aa(e.r);
  Vector6d r;
  r.head<3>() = aa.angle() * aa.axis();
  r.tail<3>() = e.t;
  return r;
}

// Left update x -> exp(d) x, d = (rotation vector, translation).
Pose exp_left(const Vector6d& d, const Pose& p) {
  const Eigen::Vector3d w = d.head<3>();
  const double angle = w.norm();
  Pose step;
  if (angle > 0.0) step.r = Eigen::AngleAxisd(angle, w / angle).toRotationMatrix();
  step.t = d.tail<3>();
  return step * p;
}

// Adjoint of T = (R, p) on (rotation vector, translation): T exp(x) T^-1 = exp(Ad_T x).
Matrix6d adjoint(const Pose& t) {
  Matrix6d a = Matrix6d::Zero();
  a.topLeftCorner<3, 3>() = t.r;
  a.bottomRightCorner<3, 3>() = t.r;
  a.bottomLeftCorner<3, 3>() = skew(t.t) * t.r;
  return a;
}

struct Edge {
  std::size_t i, j;
  Pose inverse_measured;  // T_ij^-1, centred
  Matrix6d information;
};

// E = P_j^-1 P_i T_ij^-1: the identity when the poses agree with the edge.
Vector6d edge_residual(const Edge& e, const std::vector<Pose>& poses) {
  return residual_of(poses[e.j].inverse() * poses[e.i] * e.inverse_measured);
}

double total_cost(const std::vector<Edge>& edges, const std::vector<char>& active, const std::vector<Pose>& poses) {
  double cost = 0.0;
  for (std::size_t k = 0; k < edges.size(); ++k) {
    if (!active[k]) continue;
    const Vector6d r = edge_residual(edges[k], poses);
    cost += r.dot(edges[k].information * r);
  }
  return cost;
}

// Scans reachable from `fixed` through active edges.
std::vector<char> reachable(std::size_t n, const std::vector<Edge>& edges, const std::vector<char>& active, std::size_t fixed) {
  std::vector<char> seen(n, 0);
  std::vector<std::size_t> stack = {fixed};
  seen[fixed] = 1;
  while (!stack.empty()) {
    const std::size_t v = stack.back();
    stack.pop_back();
    for (std::size_t k = 0; k < edges.size(); ++k) {
      if (!active[k] || (edges[k].i != v && edges[k].j != v)) continue;
      const std::size_t w = edges[k].i == v ? edges[k].j : edges[k].i;
      if (!seen[w]) {
        seen[w] = 1;
        stack.push_back(w);
      }
    }
  }
  return seen;
}

struct SolveOutcome {
  std::size_t iterations = 0;
  bool converged = false;
};

// Gauss-Newton with a halving line search; every loop bounded.
SolveOutcome solve(std::vector<Pose>& poses, const std::vector<Edge>& edges, const std::vector<char>& active, const PoseGraphParams& params) {
  const std::size_t n = poses.size();
  // Unknowns: 6 per scan except the fixed one.
  std::vector<std::ptrdiff_t> column(n, -1);
  std::ptrdiff_t unknowns = 0;
  for (std::size_t v = 0; v < n; ++v)
    if (v != params.fixed) column[v] = 6 * (unknowns++);
  SolveOutcome out;
  if (unknowns == 0) {
    out.converged = true;
    return out;
  }
  double cost = total_cost(edges, active, poses);
  for (std::size_t it = 0; it < params.max_iterations; ++it) {
    ++out.iterations;
    Eigen::MatrixXd h = Eigen::MatrixXd::Zero(6 * unknowns, 6 * unknowns);
    Eigen::VectorXd b = Eigen::VectorXd::Zero(6 * unknowns);
    for (std::size_t k = 0; k < edges.size(); ++k) {
      if (!active[k]) continue;
      const Edge& e = edges[k];
      const Vector6d r = edge_residual(e, poses);
      // d r / d(delta_i) = Ad(P_j^-1), d r / d(delta_j) = -Ad(P_j^-1), to first order (the
      // residuals are small near the answer).
      const Matrix6d a = adjoint(poses[e.j].inverse());
      const Matrix6d at_l = a.transpose() * e.information;
      const Matrix6d block = at_l * a;
      const Vector6d g = at_l * r;
      const std::ptrdiff_t ci = column[e.i], cj = column[e.j];
      if (ci >= 0) {
        h.block<6, 6>(ci, ci) += block;
        b.segment<6>(ci) += g;
      }
      if (cj >= 0) {
        h.block<6, 6>(cj, cj) += block;
        b.segment<6>(cj) -= g;
      }
      if (ci >= 0 && cj >= 0) {
        h.block<6, 6>(ci, cj) -= block;
        h.block<6, 6>(cj, ci) -= block;
      }
    }
    // A whisker of damping keeps a direction no edge constrains (a plane's in-plane motion)
    // from making the system singular; it does not move the answer measurably.
    const double scale = std::max(h.diagonal().maxCoeff(), 1e-300);
    h.diagonal().array() += 1e-12 * scale;
    const Eigen::VectorXd delta = h.ldlt().solve(-b);
    if (!delta.allFinite()) break;
    double step = 1.0;
    bool improved = false;
    std::vector<Pose> trial(n);
    for (int halving = 0; halving < 20 && !improved; ++halving, step *= 0.5) {
      for (std::size_t v = 0; v < n; ++v)
        trial[v] = column[v] < 0 ? poses[v] : exp_left(step * Vector6d(delta.segment<6>(column[v])), poses[v]);
      const double c = total_cost(edges, active, trial);
      if (c <= cost) {
        improved = true;
        const double drop = cost - c;
        poses.swap(trial);
        cost = c;
        if (drop <= params.tolerance * std::max(c + drop, 1e-300)) {
          out.converged = true;
          return out;
        }
      }
    }
    if (!improved) {  // no step lowers the cost: at the minimum to round-off
      out.converged = true;
      return out;
    }
  }
  return out;
}

}  // namespace

const FieldTable<PoseGraphParams>& PoseGraphParams::fields() {
  static const FieldTable<PoseGraphParams> table = [] {
    using P = PoseGraphParams;
    FieldTable<P> t;
    t.integer("fixed", &P::fixed, "The scan whose pose is kept").internal();
    t.integer("max_iterations", &P::max_iterations, "Gauss-Newton iterations at most, per solve").at_least(1).internal();
    t.number("tolerance", &P::tolerance, "Converged when an iteration lowers the cost by less than this share of it").non_negative().internal();
    t.number("prune_distance", &P::prune_distance, "Drop an uncertain edge whose RMS point displacement exceeds this; 0 keeps all")
        .unit("cloud units")
        .non_negative()
        .internal();
    t.vector3("center", &P::center, "Origin of the frame of the residuals and information").unit("cloud units").internal();
    return t;
  }();
  return table;
}

void PoseGraphParams::validate() const {
  fields().validate(*this, "pose graph");
  if (!center.allFinite()) throw UsageError("pose graph: the centre is not finite");
}

PoseGraphResult optimize_pose_graph(const std::vector<RigidTransform>& initial_poses, const std::vector<PoseGraphEdge>& edges,
                                    const PoseGraphParams& params) {
  params.validate();
  const std::size_t n = initial_poses.size();
  if (n == 0) throw UsageError("pose graph: no scan");
  if (params.fixed >= n) throw UsageError(fmt::format("pose graph: fixed scan {} of {} scans", params.fixed, n));
  const Eigen::Vector3d& c = params.center;
  std::vector<Pose> poses;
  for (const RigidTransform& p : initial_poses) poses.push_back(centred(p, c));
  std::vector<Edge> graph;
  for (std::size_t k = 0; k < edges.size(); ++k) {
    const PoseGraphEdge& e = edges[k];
    if (e.source >= n || e.target >= n || e.source == e.target)
      throw UsageError(fmt::format("pose graph: edge {} joins scans {} and {} of {}", k, e.source, e.target, n));
    if (!e.information.allFinite()) throw UsageError(fmt::format("pose graph: edge {} has a non-finite information matrix", k));
    graph.push_back({e.source, e.target, centred(e.transform, c).inverse(), e.information});
  }
  std::vector<char> active(graph.size(), 1);
  const std::vector<char> seen = reachable(n, graph, active, params.fixed);
  for (std::size_t v = 0; v < n; ++v)
    if (!seen[v]) throw UsageError(fmt::format("pose graph: scan {} is not connected to scan {} by any edge", v, params.fixed));

  PoseGraphResult result;
  result.initial_cost = total_cost(graph, active, poses);
  SolveOutcome outcome = solve(poses, graph, active, params);
  result.iterations = outcome.iterations;
  auto edge_rms = [&](std::size_t k) {
    const Vector6d r = edge_residual(graph[k], poses);
    const double pairs = std::max(graph[k].information.bottomRightCorner<3, 3>().trace() / 3.0, 1e-300);
    return std::sqrt(std::max(r.dot(graph[k].information * r), 0.0) / pairs);
  };
  if (params.prune_distance > 0.0) {
    // Drop the worst uncertain edge at a time while one is beyond the distance, and solve again.
    for (std::size_t round = 0; round < graph.size(); ++round) {
      std::size_t worst = graph.size();
      double worst_rms = params.prune_distance;
      for (std::size_t k = 0; k < graph.size(); ++k) {
        if (!active[k] || !edges[k].uncertain) continue;
        const double rms = edge_rms(k);
        if (rms <= worst_rms) continue;
        active[k] = 0;
        const std::vector<char> reach = reachable(n, graph, active, params.fixed);
        const bool still_connected = std::all_of(reach.begin(), reach.end(), [](char s) { return s != 0; });
        active[k] = 1;
        if (still_connected) {
          worst = k;
          worst_rms = rms;
        }
      }
      if (worst == graph.size()) break;
      active[worst] = 0;
      result.pruned.push_back(worst);
      outcome = solve(poses, graph, active, params);
      result.iterations += outcome.iterations;
    }
  }
  result.converged = outcome.converged;
  result.cost = total_cost(graph, active, poses);
  for (std::size_t k = 0; k < graph.size(); ++k) result.edge_rms.push_back(edge_rms(k));
  for (std::size_t v = 0; v < n; ++v) result.poses.push_back(v == params.fixed ? initial_poses[v] : world(poses[v], c));
  return result;
}

Matrix6d information_from_pairs(const PointCloud& source, const KdTree& target_tree, const RigidTransform& transform, double max_distance,
                                const Eigen::Vector3d& center) {
  if (!(max_distance > 0.0)) throw UsageError(fmt::format("information_from_pairs: max_distance must be > 0, got {}", max_distance));
  const double squared = max_distance * max_distance;
  using Range = tbb::blocked_range<std::size_t>;
  return tbb::parallel_reduce(
      Range(0, source.size(), 1024), Matrix6d(Matrix6d::Zero()),
      [&](const Range& range, Matrix6d sum) {
        std::vector<Neighbor> nearest;
        for (std::size_t i = range.begin(); i != range.end(); ++i) {
          const Eigen::Vector3d q = transform.apply(source.positions[i]);
          target_tree.knn(q, 1, nearest);
          if (nearest.empty() || nearest.front().squared_distance > squared) continue;
          const Eigen::Vector3d x = q - center;
          Eigen::Matrix<double, 3, 6> j;
          j.leftCols<3>() = -skew(x);
          j.rightCols<3>().setIdentity();
          sum.noalias() += j.transpose() * j;
        }
        return sum;
      },
      [](const Matrix6d& a, const Matrix6d& b) -> Matrix6d { return a + b; });
}

const ResultTable<PoseGraphResult>& PoseGraphResult::results() {
  static const ResultTable<PoseGraphResult> table = [] {
    using G = PoseGraphResult;
    ResultTable<G> t;
    t.number("cost_before", &G::initial_cost, "Cost of the pose graph before the refinement").with_unit("squared cloud units");
    t.number("cost", &G::cost, "Cost after it").with_unit("squared cloud units").lower_is_better();
    t.computed("iterations", ResultType::Integer, [](const G& g) { return ResultValue(std::int64_t(g.iterations)); }, "Gauss-Newton iterations");
    t.flag("converged", &G::converged, "The refinement converged").higher_is_better();
    return t;
  }();
  return table;
}

}  // namespace pointsurf
