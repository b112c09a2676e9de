#include "slam/pose_optimizer.hpp"

#include <cmath>
#include <limits>

#include "slam/frame.hpp"
#include "slam/map_point.hpp"
#include "slam/reprojection_cost.hpp"

namespace builtscene::slam {

double reprojection_chi2(const Intrinsics& K, const Observation& o, const Eigen::Vector3d& p_c) {
  if (!(p_c.z() > 1e-6)) return std::numeric_limits<double>::infinity();
  const double inv_z = 1.0 / p_c.z();
  const double u = K.fx * p_c.x() * inv_z + K.cx, v = K.fy * p_c.y() * inv_z + K.cy;
  double e = (u - o.uv.x()) * (u - o.uv.x()) + (v - o.uv.y()) * (v - o.uv.y());
  if (o.stereo() && K.disparity_sigma > 0) {
    const double ed = disparity_residual(K, o, p_c) / K.disparity_sigma;
    return e * o.inv_sigma2 + ed * ed;
  }
  if (o.stereo()) {
    const double ur = u - K.bf * inv_z;
    e += (ur - o.u_right) * (ur - o.u_right);
  }
  return e * o.inv_sigma2;
}

Intrinsics intrinsics_of(const FrameContext& ctx) {
  return {ctx.camera.fx, ctx.camera.fy, ctx.camera.cx, ctx.camera.cy, ctx.bf, ctx.disparity_sigma};
}

namespace {
Intrinsics with_disparity_sigma(Intrinsics K, double sigma) {
  if (K.disparity_sigma > 0 && sigma > 0) K.disparity_sigma = sigma;  // ORB-SLAM's form stays
  return K;
}
}  // namespace

Intrinsics global_ba_intrinsics_of(const FrameContext& ctx) {
  return with_disparity_sigma(intrinsics_of(ctx), ctx.global_ba_disparity_sigma);
}

Intrinsics local_ba_intrinsics_of(const FrameContext& ctx) {
  return with_disparity_sigma(intrinsics_of(ctx), ctx.local_ba_disparity_sigma);
}

namespace {

// r = S [log(R R0^T); t - R R0^T t0]: the pose relative to the prior, S its square-root
// information (diag(1/sigma_rad x3, 1/sigma_m x3) for the motion prior).
struct PosePriorCost {
  Eigen::Quaterniond q0;
  Eigen::Vector3d t0;
  Eigen::Matrix<double, 6, 6> S;
  template <typename T>
  bool operator()(const T* pose, T* r) const {
    T q[4], q0_inv[4] = {T(q0.w()), T(-q0.x()), T(-q0.y()), T(-q0.z())}, dq[4];
    ceres::AngleAxisToQuaternion(pose, q);
    ceres::QuaternionProduct(q, q0_inv, dq);
    T aa[3];
    ceres::QuaternionToAngleAxis(dq, aa);
    const T t0_[3] = {T(t0.x()), T(t0.y()), T(t0.z())};
    T rt0[3];
    ceres::UnitQuaternionRotatePoint(dq, t0_, rt0);
    T e[6];
    for (int i = 0; i < 3; ++i) {
      e[i] = aa[i];
      e[3 + i] = pose[3 + i] - rt0[i];
    }
    for (int i = 0; i < 6; ++i) {
      r[i] = T(0);
      for (int j = 0; j < 6; ++j) r[i] += T(S(i, j)) * e[j];
    }
    return true;
  }
};

}  // namespace

PoseOptimizationResult optimize_pose(const SE3& T_cw_initial, const std::vector<Eigen::Vector3d>& points_w,
                                     const std::vector<Observation>& obs, const Intrinsics& K,
                                     const PoseOptimizerOptions& options) {
  PoseOptimizationResult result;
  result.T_cw = T_cw_initial;
  const std::size_t n = obs.size();
  result.inlier.assign(n, true);
  result.inliers = static_cast<int>(n);
  if (static_cast<int>(n) < options.min_inliers) return result;
  result.ok = true;

  std::vector<PosePrior> priors = options.priors;
  if (options.prior_T_cw) {
    Eigen::Matrix<double, 6, 1> d;
    d << Eigen::Vector3d::Constant(1.0 / options.prior_sigma_rad), Eigen::Vector3d::Constant(1.0 / options.prior_sigma_m);
    priors.push_back({*options.prior_T_cw, d.asDiagonal()});
  }

  double pose[6];
  detail::pose_to_block(T_cw_initial, pose);
  ceres::HuberLoss huber_mono(std::sqrt(kChi2Mono)), huber_stereo(std::sqrt(kChi2Stereo));
  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type = ceres::DENSE_QR;
  solver_options.max_num_iterations = options.iterations;
  solver_options.num_threads = 1;
  solver_options.logging_type = ceres::SILENT;
  solver_options.minimizer_progress_to_stdout = false;

  for (int round = 0; round < options.rounds; ++round) {
    ceres::Problem problem(problem_options);
    const bool robust = round < 2;
    int used = 0;
    for (std::size_t i = 0; i < n; ++i) {
      if (!result.inlier[i]) continue;
      const double sqrt_info = std::sqrt(obs[i].inv_sigma2);
      if (obs[i].stereo()) {
        auto* cost = new ceres::AutoDiffCostFunction<detail::PoseOnlyCost<3>, 3, 6>(
            new detail::PoseOnlyCost<3>{points_w[i], K, obs[i], sqrt_info});
        problem.AddResidualBlock(cost, robust ? &huber_stereo : nullptr, pose);
      } else {
        auto* cost = new ceres::AutoDiffCostFunction<detail::PoseOnlyCost<2>, 2, 6>(
            new detail::PoseOnlyCost<2>{points_w[i], K, obs[i], sqrt_info});
        problem.AddResidualBlock(cost, robust ? &huber_mono : nullptr, pose);
      }
      ++used;
    }
    if (used < options.min_inliers) break;
    for (const auto& P : priors) {
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PosePriorCost, 6, 6>(new PosePriorCost{
                                   Eigen::Quaterniond(P.T_cw.rotation()), P.T_cw.translation(), P.sqrt_information}),
                               nullptr, pose);
    }
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options, &problem, &summary);

    // Re-classify every match, including earlier outliers, at the new pose.
    const SE3 T = detail::block_to_pose(pose);
    int inliers = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const double chi2 = reprojection_chi2(K, obs[i], T * points_w[i]);
      result.inlier[i] = chi2 <= (obs[i].stereo() ? kChi2Stereo : kChi2Mono);
      inliers += result.inlier[i];
    }
    result.inliers = inliers;
    if (inliers < options.min_inliers) break;
  }
  result.T_cw = detail::block_to_pose(pose);
  return result;
}

int optimize_frame_pose(Frame& frame, const PoseOptimizerOptions& options) {
  std::vector<Eigen::Vector3d> pts;
  std::vector<Observation> obs;
  std::vector<std::size_t> index;
  const auto& f = *frame.f;
  for (std::size_t i = 0; i < frame.points.size(); ++i) {
    const auto& p = frame.points[i];
    if (!p) continue;
    pts.push_back(p->position);
    obs.push_back(f.observation(i));  // a frame's far readings are never disparity measurements
    index.push_back(i);
  }
  const auto r = optimize_pose(frame.T_cw, pts, obs, intrinsics_of(*f.ctx), options);
  if (!r.ok) return 0;
  frame.set_pose(r.T_cw);
  for (std::size_t k = 0; k < index.size(); ++k) frame.outlier[index[k]] = !r.inlier[k];
  return r.inliers;
}

}  // namespace builtscene::slam
