// SPDX-License-Identifier: GPL-3.0-or-later
#include "pointsurf/register/pose_graph.h"

#include <cmath>
#include <random>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "pointsurf/core/error.h"
#include "pointsurf/spatial/kd_tree.h"
#include "support/files.h"

namespace pointsurf {
namespace {

RigidTransform rotation_about_z(double degrees, const Eigen::Vector3d& t) {
  return RigidTransform(Eigen::AngleAxisd(degrees * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix(), t);
}

// A small random motion: rotation of about `degrees` about a random axis, translation of about `shift`.
RigidTransform noise(std::mt19937_64& rng, double degrees, double shift) {
  std::normal_distribution<double> g(0.0, 1.0);
  const Eigen::Vector3d axis = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
  return RigidTransform(Eigen::AngleAxisd(degrees * g(rng) * M_PI / 180.0, axis).toRotationMatrix(),
                        shift * Eigen::Vector3d(g(rng), g(rng), g(rng)));
}

// Points on a unit box around `center`: what each scan sees of the object.
PointCloud box_points(const Eigen::Vector3d& center) {
  PointCloud c;
  for (int i = 0; i <= 10; ++i)
    for (int j = 0; j <= 10; ++j) {
      const double u = i / 10.0 - 0.5, v = j / 10.0 - 0.5;
      for (int s : {-1, 1}) {
        c.positions.push_back(center + Eigen::Vector3d(0.5 * s, u, v));
        c.positions.push_back(center + Eigen::Vector3d(u, 0.5 * s, v));
        c.positions.push_back(center + Eigen::Vector3d(u, v, 0.5 * s));
      }
    }
  return c;
}

Matrix6d box_information(const Eigen::Vector3d& center) {
  const PointCloud c = box_points(center);
  const KdTree tree(c.positions);
  return information_from_pairs(c, tree, RigidTransform(), 1e-3, center);
}

struct Loop {
  std::vector<RigidTransform> truth;
  std::vector<PoseGraphEdge> edges;  // 0->1, 1->2, ..., (n-1)->0 closing the loop
  std::vector<RigidTransform> chain;  // poses composed along the odometry edges
  std::vector<Eigen::Vector3d> object;  // the object's centre in each scan's frame
};

// n scans around an object at `center`, each turned by 360/n degrees; every edge measured with
// noise.
Loop make_loop(std::size_t n, std::uint64_t seed, const Eigen::Vector3d& center = Eigen::Vector3d::Zero()) {
  std::mt19937_64 rng(seed);
  Loop loop;
  for (std::size_t k = 0; k < n; ++k) {
    const RigidTransform about = rotation_about_z(360.0 * double(k) / double(n), Eigen::Vector3d(0.3 * double(k), 0.1 * double(k), 0.0));
    // About the object's centre, so that far from the origin the motion stays small there.
    loop.truth.push_back(RigidTransform::about(center, about.rotation(), about.translation()));
    loop.object.push_back(loop.truth.back().inverse().apply(center));
  }
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t j = (k + 1) % n;
    PoseGraphEdge e;
    e.source = k;
    e.target = j;
    const RigidTransform exact = loop.truth[j].inverse() * loop.truth[k];
    const RigidTransform n0 = noise(rng, 0.5, 0.01);
    // Noise about the object's centre in the target's frame, where the information is too.
    e.transform = RigidTransform::about(loop.object[j], n0.rotation(), n0.translation()) * exact;
    e.information = box_information(loop.object[j]);
    e.uncertain = j == 0;
    loop.edges.push_back(e);
  }
  loop.chain.push_back(RigidTransform());
  // Edge k -> k+1 says P_{k+1} T = P_k, so P_{k+1} = P_k T^-1.
  for (std::size_t k = 0; k + 1 < n; ++k) loop.chain.push_back(loop.chain[k] * loop.edges[k].transform.inverse());
  return loop;
}

// Summed distance between where the poses and the truth put the object's centre.
double total_error(const std::vector<RigidTransform>& poses, const Loop& loop) {
  double sum = 0.0;
  for (std::size_t k = 0; k < poses.size(); ++k) sum += RigidTransform::translation_error(poses[k], loop.truth[k], loop.object[k]);
  return sum;
}

// RMS displacement of the box's points (around `at`, in the edge's target frame) by the misfit
// of `edge` under `poses`.
double closing_rms(const std::vector<RigidTransform>& poses, const PoseGraphEdge& edge, const Eigen::Vector3d& at) {
  const RigidTransform misfit = poses[edge.target].inverse() * poses[edge.source] * edge.transform.inverse();
  const PointCloud c = box_points(at);
  double sum = 0.0;
  for (const Eigen::Vector3d& p : c.positions) sum += (misfit.apply(p) - p).squaredNorm();
  return std::sqrt(sum / double(c.size()));
}

TEST(PoseGraph, ExactEdgesGiveExactPosesFromAPerturbedStart) {
  Loop loop = make_loop(4, 1);
  // Replace the measurements by exact ones.
  for (PoseGraphEdge& e : loop.edges) e.transform = loop.truth[e.target].inverse() * loop.truth[e.source];
  std::mt19937_64 rng(3);
  std::vector<RigidTransform> start = loop.truth;
  for (std::size_t k = 1; k < start.size(); ++k) start[k] = noise(rng, 5.0, 0.2) * start[k];
  const PoseGraphResult r = optimize_pose_graph(start, loop.edges);
  EXPECT_TRUE(r.converged);
  EXPECT_GT(r.initial_cost, 1.0);
  EXPECT_LT(r.cost, 1e-16);
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_LT(RigidTransform::rotation_error_degrees(r.poses[k], loop.truth[k]), 1e-6) << k;
    EXPECT_LT(RigidTransform::translation_error(r.poses[k], loop.truth[k], Eigen::Vector3d::Zero()), 1e-8) << k;
  }
}

TEST(PoseGraph, LoopClosureBeatsTheChain) {
  // Over several seeds, the refined poses are nearer the truth than the chain of odometry
  // edges, and the loop's misfit is spread over its edges.
  double chain_error = 0.0, graph_error = 0.0;
  std::size_t better = 0;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    const Loop loop = make_loop(5, seed);
    const PoseGraphResult r = optimize_pose_graph(loop.chain, loop.edges);
    EXPECT_TRUE(r.converged);
    EXPECT_LT(r.cost, r.initial_cost);
    const double c = total_error(loop.chain, loop);
    const double g = total_error(r.poses, loop);
    chain_error += c;
    graph_error += g;
    better += g < c;
    // The loop closes: the closing edge's misfit falls well below its misfit under the chain.
    const double chain_closing = closing_rms(loop.chain, loop.edges.back(), loop.object[0]);
    const double closing = closing_rms(r.poses, loop.edges.back(), loop.object[0]);
    EXPECT_NEAR(r.edge_rms.back(), closing, 0.05 * closing + 1e-12) << seed;
    EXPECT_LT(closing, 0.6 * chain_closing) << seed;
  }
  EXPECT_GE(better, 8u);
  EXPECT_LT(graph_error, 0.8 * chain_error);  // 0.70 measured; the variances predict about 0.65
}

TEST(PoseGraph, WrongLoopClosureIsPruned) {
  Loop loop = make_loop(4, 2);
  loop.edges.back().transform = rotation_about_z(30.0, Eigen::Vector3d(0.5, 0.0, 0.0)) * loop.edges.back().transform;
  PoseGraphParams p;
  p.prune_distance = 0.05;
  const PoseGraphResult r = optimize_pose_graph(loop.chain, loop.edges, p);
  ASSERT_EQ(r.pruned.size(), 1u);
  EXPECT_EQ(r.pruned.front(), 3u);
  for (std::size_t k = 0; k < 4; ++k) EXPECT_LT(RigidTransform::rotation_error_degrees(r.poses[k], loop.truth[k]), 2.0) << k;
  // Without pruning the bad edge drags the poses.
  const PoseGraphResult kept = optimize_pose_graph(loop.chain, loop.edges);
  EXPECT_GT(RigidTransform::rotation_error_degrees(kept.poses[3], loop.truth[3]), 3.0);
}

TEST(PoseGraph, SameAnswerOneMillionMetresAway) {
  const Eigen::Vector3d far(1.0e6, -2.0e6, 3.0e5);
  const Loop near_loop = make_loop(4, 5);
  const Loop far_loop = make_loop(4, 5, far);
  PoseGraphParams p;
  p.center = far;
  const PoseGraphResult a = optimize_pose_graph(near_loop.chain, near_loop.edges);
  const PoseGraphResult b = optimize_pose_graph(far_loop.chain, far_loop.edges, p);
  for (std::size_t k = 0; k < 4; ++k) {
    const double ea = RigidTransform::translation_error(a.poses[k], near_loop.truth[k], near_loop.object[k]);
    const double eb = RigidTransform::translation_error(b.poses[k], far_loop.truth[k], far_loop.object[k]);
    EXPECT_NEAR(ea, eb, 1e-7) << k;
    const double ra = RigidTransform::rotation_error_degrees(a.poses[k], near_loop.truth[k]);
    const double rb = RigidTransform::rotation_error_degrees(b.poses[k], far_loop.truth[k]);
    EXPECT_NEAR(ra, rb, 1e-6) << k;
  }
}

TEST(PoseGraph, InformationGivesTheSquaredDisplacement) {
  const PointCloud c = box_points(Eigen::Vector3d(2.0, 1.0, -1.0));
  const Eigen::Vector3d center(2.0, 1.0, -1.0);
  const KdTree tree(c.positions);
  const Matrix6d info = information_from_pairs(c, tree, RigidTransform(), 1e-6, center);
  Eigen::Matrix<double, 6, 1> xi;
  xi << 1e-4, -2e-4, 3e-4, 1e-3, 0.0, -2e-3;
  double direct = 0.0;
  for (const Eigen::Vector3d& p : c.positions) direct += (xi.head<3>().cross(p - center) + xi.tail<3>()).squaredNorm();
  EXPECT_NEAR(xi.dot(info * xi), direct, 1e-12 * direct + 1e-18);
  const double pairs = info.bottomRightCorner<3, 3>().trace() / 3.0;
  EXPECT_NEAR(pairs, double(c.size()), 1e-9);
  // Pairs farther than max_distance count for nothing.
  const Matrix6d none = information_from_pairs(c, tree, RigidTransform(Eigen::Matrix3d::Identity(), Eigen::Vector3d(10, 0, 0)), 1.0, center);
  EXPECT_EQ(none.norm(), 0.0);
}

TEST(PoseGraph, BadGraphsAreRefused) {
  const Loop loop = make_loop(3, 1);
  std::vector<PoseGraphEdge> first_only = {loop.edges.front()};
  test::expect_error<UsageError>([&] { optimize_pose_graph(loop.chain, first_only); }, "scan 2 is not connected to scan 0");
  std::vector<PoseGraphEdge> bad = loop.edges;
  bad[1].target = 7;
  test::expect_error<UsageError>([&] { optimize_pose_graph(loop.chain, bad); }, "edge 1 joins scans 1 and 7 of 3");
  PoseGraphParams p;
  p.fixed = 3;
  test::expect_error<UsageError>([&] { optimize_pose_graph(loop.chain, loop.edges, p); }, "fixed scan 3 of 3 scans");
  test::expect_error<UsageError>([&] { optimize_pose_graph({}, {}); }, "no scan");
  const PointCloud c = box_points(Eigen::Vector3d::Zero());
  const KdTree tree(c.positions);
  test::expect_error<UsageError>([&] { information_from_pairs(c, tree, RigidTransform(), 0.0, Eigen::Vector3d::Zero()); }, "max_distance must be > 0");
}

}  // namespace
}  // namespace pointsurf
