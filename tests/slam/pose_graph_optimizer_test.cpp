// Pose-graph optimization against known answers: a ring of camera poses whose exact relative
// poses are given is recovered from a drifted start; a chain with biased odometry closed by
// one exact loop edge spreads the loop's error evenly, as the least-squares closed form says.
#include <gtest/gtest.h>

#include <random>

#include "core/so3.hpp"
#include "slam/pose_graph_optimizer.hpp"
#include "synthetic_scene.hpp"

namespace builtscene::slam {
namespace {

// Cameras on a circle of radius 3 m looking along it, bobbing up and down (T_cw).
std::vector<SE3> ring(int n) {
  std::vector<SE3> out;
  for (int i = 0; i < n; ++i) {
    const double a = 2 * M_PI * i / n;
    const Eigen::Vector3d c(3 * std::cos(a), 0.2 * std::sin(3 * a), 3 * std::sin(a));
    const Eigen::Quaterniond q(Eigen::AngleAxisd(-a, Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(0.1 * std::sin(2 * a), Eigen::Vector3d::UnitX()));
    out.push_back(SE3(q, c).inverse());
  }
  return out;
}

TEST(PoseGraphOptimizer, RingWithExactEdgesIsRecoveredFromADriftedStart) {
  const int n = 30;
  const auto truth = ring(n);
  PoseGraph g;
  std::mt19937 rng(3);
  for (int i = 0; i < n; ++i) {
    // Drift growing along the ring, up to ~9 deg and 0.6 m at the end.
    SE3 start = i == 0 ? truth[0] : test::perturb(truth[static_cast<std::size_t>(i)], 0.005 * i, 0.02 * i, rng);
    g.nodes.push_back({start, i == 0});
  }
  for (int i = 0; i + 1 < n; ++i)
    g.edges.push_back({i, i + 1, truth[static_cast<std::size_t>(i)] * truth[static_cast<std::size_t>(i + 1)].inverse()});
  g.edges.push_back({n - 1, 0, truth[static_cast<std::size_t>(n - 1)] * truth[0].inverse()});
  const auto r = optimize_pose_graph(g, {50});
  ASSERT_TRUE(r.solved);
  EXPECT_LT(r.final_cost, 1e-12);
  for (int i = 0; i < n; ++i) {
    EXPECT_LT(test::translation_error(r.poses[static_cast<std::size_t>(i)], truth[static_cast<std::size_t>(i)]), 1e-6) << i;
    EXPECT_LT(test::rotation_error_deg(r.poses[static_cast<std::size_t>(i)], truth[static_cast<std::size_t>(i)]), 1e-5) << i;
  }
}

// Cameras on a line (no rotation), odometry says each step is 1 + b m, one exact loop edge
// from the last camera to the first. Least squares over the cycle gives every edge the same
// residual, (n - 1) b / n, so camera k ends at k (1 + b / n): closed form.
TEST(PoseGraphOptimizer, BiasedChainClosedByALoopMatchesTheClosedForm) {
  const int n = 10;
  const double b = 0.05;
  auto T = [](double x) { return SE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(-x, 0, 0)); };  // camera at (x,0,0)
  PoseGraph g;
  for (int i = 0; i < n; ++i) g.nodes.push_back({T(i * (1 + b)), i == 0});  // dead reckoning
  for (int i = 0; i + 1 < n; ++i) g.edges.push_back({i, i + 1, T(i * (1 + b)) * T((i + 1) * (1 + b)).inverse()});
  g.edges.push_back({n - 1, 0, T(n - 1) * T(0).inverse()});
  const auto r = optimize_pose_graph(g);
  ASSERT_TRUE(r.solved);
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d c = r.poses[static_cast<std::size_t>(k)].inverse().translation();
    EXPECT_NEAR(c.x(), k * (1 + b / n), 1e-6) << k;
    EXPECT_NEAR(c.y(), 0, 1e-9);
    EXPECT_NEAR(c.z(), 0, 1e-9);
  }
}

// The same line, but only edge m is wrong (by b) and it weighs w, the others 1 (the loop
// closer weighs a depth-odometry edge so). Least squares gives each edge a residual in
// inverse proportion to its weight, summing to b: r = (b / S) / weight with S = (n - 1) + 1 / w
// over the n - 1 unit edges (chain and loop) and the weak one. Camera k ends at k - (b / S)
// times the number of unit chain edges before it, minus the weak edge's share past m.
TEST(PoseGraphOptimizer, AWeakEdgeTakesTheLoopErrorInInverseProportionToItsWeight) {
  const int n = 10, m = 4;
  const double b = 0.3, w = 0.1;
  auto T = [](double x) { return SE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(-x, 0, 0)); };
  std::vector<double> dead{0};
  for (int i = 0; i + 1 < n; ++i) dead.push_back(dead.back() + 1 + (i == m ? b : 0));
  PoseGraph g;
  for (int i = 0; i < n; ++i) g.nodes.push_back({T(dead[static_cast<std::size_t>(i)]), i == 0});
  for (int i = 0; i + 1 < n; ++i)
    g.edges.push_back({i, i + 1, T(dead[static_cast<std::size_t>(i)]) * T(dead[static_cast<std::size_t>(i + 1)]).inverse(), i == m ? w : 1.0});
  g.edges.push_back({n - 1, 0, T(n - 1) * T(0).inverse()});
  const auto r = optimize_pose_graph(g, {50});
  ASSERT_TRUE(r.solved);
  const double S = (n - 1) + 1 / w, unit = b / S, weak = b / S / w;
  double expect = 0;
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d c = r.poses[static_cast<std::size_t>(k)].inverse().translation();
    EXPECT_NEAR(c.x(), expect, 1e-6) << k;
    expect += 1 + (k == m ? b - weak : -unit);
  }
  // With w = 0.1 the weak edge takes 10 / 19 of the error, each unit edge 1 / 19.
  EXPECT_NEAR(weak / b, 10.0 / 19.0, 1e-12);
}

// A ring driven with a rotation and translation bias per step (drift), then one exact loop
// edge: the optimized ring is much closer to the truth than dead reckoning.
TEST(PoseGraphOptimizer, DriftedRingWithOneLoopEdgeComesBackToTheTruth) {
  const int n = 40;
  const auto truth = ring(n);
  const SE3 bias(so3_exp(Eigen::Vector3d(0.002, 0.008, -0.001)), Eigen::Vector3d(0.01, -0.005, 0.02));
  PoseGraph g;
  std::vector<SE3> dead{truth[0]};
  for (int i = 0; i + 1 < n; ++i) {
    const SE3 meas = truth[static_cast<std::size_t>(i + 1)] * truth[static_cast<std::size_t>(i)].inverse();  // T_{i+1,i}
    dead.push_back(bias * meas * dead.back());
    g.edges.push_back({i + 1, i, bias * meas});
  }
  for (int i = 0; i < n; ++i) g.nodes.push_back({dead[static_cast<std::size_t>(i)], i == 0});
  g.edges.push_back({n - 1, 0, truth[static_cast<std::size_t>(n - 1)] * truth[0].inverse()});
  const auto r = optimize_pose_graph(g);
  ASSERT_TRUE(r.solved);
  double before = 0, after = 0;
  for (int i = 0; i < n; ++i) {
    before = std::max(before, test::translation_error(dead[static_cast<std::size_t>(i)], truth[static_cast<std::size_t>(i)]));
    after = std::max(after, test::translation_error(r.poses[static_cast<std::size_t>(i)], truth[static_cast<std::size_t>(i)]));
  }
  std::printf("max position error: dead reckoning %.3f m, after the loop %.3f m\n", before, after);
  EXPECT_GT(before, 0.5);
  EXPECT_LT(after, 0.35 * before);
  // The loop edge itself is nearly satisfied: last camera back next to its true place.
  EXPECT_LT(test::translation_error(r.poses.back(), truth.back()), 0.25 * before);
  EXPECT_EQ(r.poses[0].translation(), truth[0].translation());  // the fixed node does not move
}

TEST(PoseGraphOptimizer, BadEdgesAndEmptyGraphsAreHarmless) {
  PoseGraph g;
  EXPECT_FALSE(optimize_pose_graph(g).solved);
  g.nodes.push_back({SE3(), false});
  g.nodes.push_back({SE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(1, 2, 3)), false});
  g.edges.push_back({0, 5, SE3()});   // out of range
  g.edges.push_back({1, 1, SE3()});   // self
  g.edges.push_back({0, 1, SE3(), 0}); // zero weight
  const auto r = optimize_pose_graph(g);
  EXPECT_FALSE(r.solved);
  ASSERT_EQ(r.poses.size(), 2u);
  EXPECT_EQ(r.poses[1].translation(), Eigen::Vector3d(1, 2, 3));
}

}  // namespace
}  // namespace builtscene::slam
