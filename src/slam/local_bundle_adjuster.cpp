#include "slam/local_bundle_adjuster.hpp"

#include <cmath>

#include "slam/reprojection_cost.hpp"

namespace builtscene::slam {
namespace {

class AbortCallback : public ceres::IterationCallback {
 public:
  explicit AbortCallback(const std::atomic<bool>* flag) : flag_(flag) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    if (flag_ && flag_->load()) {
      aborted = true;
      return ceres::SOLVER_TERMINATE_SUCCESSFULLY;
    }
    return ceres::SOLVER_CONTINUE;
  }
  bool aborted = false;

 private:
  const std::atomic<bool>* flag_;
};

double pixel_sq_error(const Intrinsics& K, const Observation& o, const Eigen::Vector3d& pc) {
  // Error in pixels (without the level information weight), for reporting; the disparity
  // residual of the depth-weighted form is left out (it is not a pixel error of the corner).
  Observation pixel = o;
  if (K.disparity_sigma > 0) pixel.u_right = -1;
  return reprojection_chi2(K, pixel, pc) / o.inv_sigma2;
}

}  // namespace

BundleAdjustmentResult solve_bundle_adjustment(const BundleAdjustmentProblem& pb, const BundleAdjustmentOptions& options,
                                               const std::atomic<bool>* abort) {
  BundleAdjustmentResult res;
  const std::size_t nc = pb.cameras.size(), np = pb.points.size(), nm = pb.measurements.size();
  res.poses.resize(nc);
  for (std::size_t c = 0; c < nc; ++c) res.poses[c] = pb.cameras[c].T_cw;
  res.points = pb.points;
  res.measurement_inlier.assign(nm, true);
  if (nm == 0 || nc == 0) return res;

  std::vector<double> poses(6 * nc), points(3 * np);
  for (std::size_t c = 0; c < nc; ++c) detail::pose_to_block(pb.cameras[c].T_cw, &poses[6 * c]);
  for (std::size_t p = 0; p < np; ++p)
    for (int k = 0; k < 3; ++k) points[3 * p + k] = pb.points[p][k];

  auto rms = [&](bool inliers_only) {
    double s = 0;
    std::size_t n = 0;
    for (std::size_t m = 0; m < nm; ++m) {
      if (inliers_only && !res.measurement_inlier[m]) continue;
      const auto& mm = pb.measurements[m];
      const SE3 T = detail::block_to_pose(&poses[6 * static_cast<std::size_t>(mm.camera)]);
      const Eigen::Vector3d pw(&points[3 * static_cast<std::size_t>(mm.point)]);
      const double e = pixel_sq_error(pb.K, mm.o, T * pw);
      if (!std::isfinite(e)) continue;
      s += e;
      ++n;
    }
    return n ? std::sqrt(s / static_cast<double>(n)) : 0.0;
  };
  res.initial_rms_px = rms(false);

  ceres::HuberLoss huber_mono(std::sqrt(kChi2Mono)), huber_stereo(std::sqrt(kChi2Stereo));
  AbortCallback callback(abort);
  int free_cameras = 0;
  for (const auto& c : pb.cameras) free_cameras += !c.fixed;

  for (int phase = 0; phase < 2; ++phase) {
    ceres::Problem::Options po;
    po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    ceres::Problem problem(po);
    const bool robust = phase == 0;
    std::vector<char> camera_used(nc, 0);
    for (std::size_t m = 0; m < nm; ++m) {
      if (!res.measurement_inlier[m]) continue;
      const auto& mm = pb.measurements[m];
      double* pose = &poses[6 * static_cast<std::size_t>(mm.camera)];
      double* point = &points[3 * static_cast<std::size_t>(mm.point)];
      const double sqrt_info = std::sqrt(mm.o.inv_sigma2);
      if (mm.o.stereo()) {
        problem.AddResidualBlock(new ceres::AutoDiffCostFunction<detail::PosePointCost<3>, 3, 6, 3>(
                                     new detail::PosePointCost<3>{pb.K, mm.o, sqrt_info}),
                                 robust ? &huber_stereo : nullptr, pose, point);
      } else {
        problem.AddResidualBlock(new ceres::AutoDiffCostFunction<detail::PosePointCost<2>, 2, 6, 3>(
                                     new detail::PosePointCost<2>{pb.K, mm.o, sqrt_info}),
                                 robust ? &huber_mono : nullptr, pose, point);
      }
      camera_used[static_cast<std::size_t>(mm.camera)] = 1;
    }
    for (std::size_t c = 0; c < nc; ++c)
      if (camera_used[c] && pb.cameras[c].fixed) problem.SetParameterBlockConstant(&poses[6 * c]);
    if (problem.NumResidualBlocks() == 0) break;

    ceres::Solver::Options so;
    so.linear_solver_type = free_cameras <= 60 ? ceres::DENSE_SCHUR : ceres::SPARSE_SCHUR;
    so.max_num_iterations = phase == 0 ? options.first_iterations : options.second_iterations;
    so.num_threads = 1;
    so.logging_type = ceres::SILENT;
    so.callbacks.push_back(&callback);
    so.update_state_every_iteration = false;
    ceres::Solver::Summary summary;
    ceres::Solve(so, &problem, &summary);
    res.solved = true;

    // Outlier classification after each phase.
    for (std::size_t m = 0; m < nm; ++m) {
      const auto& mm = pb.measurements[m];
      const SE3 T = detail::block_to_pose(&poses[6 * static_cast<std::size_t>(mm.camera)]);
      const Eigen::Vector3d pw(&points[3 * static_cast<std::size_t>(mm.point)]);
      const double chi2 = reprojection_chi2(pb.K, mm.o, T * pw);
      res.measurement_inlier[m] = chi2 <= (mm.o.stereo() ? kChi2Stereo : kChi2Mono);
    }
    if (callback.aborted) {
      res.aborted = true;
      break;
    }
  }
  for (std::size_t c = 0; c < nc; ++c)
    if (!pb.cameras[c].fixed) res.poses[c] = detail::block_to_pose(&poses[6 * c]);
  for (std::size_t p = 0; p < np; ++p) res.points[p] = Eigen::Vector3d(&points[3 * p]);
  res.final_rms_px = rms(true);
  return res;
}

}  // namespace builtscene::slam
