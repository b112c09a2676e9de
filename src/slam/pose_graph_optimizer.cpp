#include "slam/pose_graph_optimizer.hpp"

#include <cmath>

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include "slam/reprojection_cost.hpp"

namespace builtscene::slam {
namespace {

// Pose blocks as in bundle adjustment (angle-axis, translation of T_cw): the rotations of a
// loop span every angle, and angle-axis is only singular at 2 pi.
struct RelativePoseCost {
  Eigen::Quaterniond q_m;  // measured rotation of T_ij
  Eigen::Vector3d t_m;
  double sqrt_w;
  template <typename T>
  bool operator()(const T* pi, const T* pj, T* r) const {
    T q[4], t[3];  // predicted T_ij = T_i * T_j^-1
    detail::relative_pose_of_blocks(pi, pj, q, t);
    // Error T_m^-1 * T_pred, expressed in the measurement's frame.
    const T qm_inv[4] = {T(q_m.w()), T(-q_m.x()), T(-q_m.y()), T(-q_m.z())};
    T qe[4];
    ceres::QuaternionProduct(qm_inv, q, qe);
    const T dt[3] = {t[0] - T(t_m.x()), t[1] - T(t_m.y()), t[2] - T(t_m.z())};
    T te[3];
    ceres::UnitQuaternionRotatePoint(qm_inv, dt, te);
    // q and -q are the same rotation: take the short way round.
    if (qe[0] < T(0))
      for (auto& c : qe) c = -c;
    T aa[3];
    ceres::QuaternionToAngleAxis(qe, aa);
    for (int k = 0; k < 3; ++k) {
      r[k] = T(sqrt_w) * te[k];
      r[3 + k] = T(sqrt_w) * aa[k];
    }
    return true;
  }
};

}  // namespace

PoseGraphResult optimize_pose_graph(const PoseGraph& graph, const PoseGraphOptions& options) {
  PoseGraphResult res;
  const std::size_t n = graph.nodes.size();
  res.poses.resize(n);
  for (std::size_t i = 0; i < n; ++i) res.poses[i] = graph.nodes[i].T_cw;
  std::vector<double> blocks(6 * n);
  for (std::size_t i = 0; i < n; ++i) detail::pose_to_block(graph.nodes[i].T_cw, &blocks[6 * i]);

  ceres::Problem problem;
  std::vector<char> used(n, 0);
  for (const auto& e : graph.edges) {
    if (e.i < 0 || e.j < 0 || static_cast<std::size_t>(e.i) >= n || static_cast<std::size_t>(e.j) >= n || e.i == e.j ||
        !(e.weight > 0))
      continue;
    auto* cost = new ceres::AutoDiffCostFunction<RelativePoseCost, 6, 6, 6>(
        new RelativePoseCost{e.T_ij.rotation(), e.T_ij.translation(), std::sqrt(e.weight)});
    problem.AddResidualBlock(cost, nullptr, &blocks[6 * static_cast<std::size_t>(e.i)],
                             &blocks[6 * static_cast<std::size_t>(e.j)]);
    used[static_cast<std::size_t>(e.i)] = used[static_cast<std::size_t>(e.j)] = 1;
  }
  if (problem.NumResidualBlocks() == 0) return res;
  bool any_fixed = false;
  for (std::size_t i = 0; i < n; ++i)
    if (used[i] && graph.nodes[i].fixed) {
      problem.SetParameterBlockConstant(&blocks[6 * i]);
      any_fixed = true;
    }
  if (!any_fixed)
    for (std::size_t i = 0; i < n; ++i)
      if (used[i]) {
        problem.SetParameterBlockConstant(&blocks[6 * i]);
        break;
      }
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  so.max_num_iterations = options.iterations;
  so.num_threads = 1;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  res.initial_cost = summary.initial_cost;
  res.final_cost = summary.final_cost;
  res.solved = summary.IsSolutionUsable();
  if (!res.solved) return res;
  for (std::size_t i = 0; i < n; ++i)
    if (used[i] && !graph.nodes[i].fixed) res.poses[i] = detail::block_to_pose(&blocks[6 * i]);
  return res;
}

}  // namespace builtscene::slam
