#include "slam/local_bundle_adjuster.hpp"

#include <cmath>

#include <Eigen/Cholesky>
#include <ceres/rotation.h>
#include <ceres/sphere_manifold.h>

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

// A measured relative pose T_ij between two pose blocks (angle-axis, translation of T_cw):
// residual U [t; w] of D = T_i T_j^-1 T_ij^-1 (a left increment of the measurement, as
// icp_with_motion_prior's information is), with U^T U the information.
struct RelativePoseInfoCost {
  Eigen::Quaterniond q_m;
  Eigen::Vector3d t_m;
  Eigen::Matrix<double, 6, 6> sqrt_info;
  template <typename T>
  bool operator()(const T* pi, const T* pj, T* r) const {
    T q[4], t[3];  // predicted T_ij = T_i * T_j^-1
    detail::relative_pose_of_blocks(pi, pj, q, t);
    const T qm_inv[4] = {T(q_m.w()), T(-q_m.x()), T(-q_m.y()), T(-q_m.z())};
    T qd[4];  // D = T_pred * T_m^-1: rotation q * qm^-1, translation t - qd * t_m
    ceres::QuaternionProduct(q, qm_inv, qd);
    const T tm[3] = {T(t_m.x()), T(t_m.y()), T(t_m.z())};
    T rt[3];
    ceres::UnitQuaternionRotatePoint(qd, tm, rt);
    if (qd[0] < T(0))
      for (auto& c : qd) c = -c;
    T e[6];
    for (int k = 0; k < 3; ++k) e[k] = t[k] - rt[k];
    ceres::QuaternionToAngleAxis(qd, e + 3);
    for (int a = 0; a < 6; ++a) {
      r[a] = T(0);
      for (int b = a; b < 6; ++b) r[a] += T(sqrt_info(a, b)) * e[b];
    }
    return true;
  }
};

// A plane measured in a camera's depth (n_m, d_m; camera coordinates) against the world plane
// (n, d) seen from the pose block (angle-axis, translation of T_cw): n_c = R n and
// d_c = d - n_c.t; residuals (n_c - n_m) / sigma_rad (3) and (d_c - d_m) / sigma_m.
struct PlaneCost {
  Eigen::Vector3d n_m;
  double d_m = 0, inv_sigma_rad = 200, inv_sigma_m = 100;
  template <typename T>
  bool operator()(const T* pose, const T* n, const T* d, T* r) const {
    T nc[3];
    ceres::AngleAxisRotatePoint(pose, n, nc);
    const T dc = d[0] - (nc[0] * pose[3] + nc[1] * pose[4] + nc[2] * pose[5]);
    for (int k = 0; k < 3; ++k) r[k] = (nc[k] - T(n_m[k])) * T(inv_sigma_rad);
    r[3] = (dc - T(d_m)) * T(inv_sigma_m);
    return true;
  }
};

// A pose block held near its start: (block - start) / sigma, rotation and translation apart.
struct HoldInPlaceCost {
  double start[6];
  double inv_sigma_rad = 50, inv_sigma_m = 20;
  template <typename T>
  bool operator()(const T* pose, T* r) const {
    for (int k = 0; k < 3; ++k) r[k] = (pose[k] - T(start[k])) * T(inv_sigma_rad);
    for (int k = 3; k < 6; ++k) r[k] = (pose[k] - T(start[k])) * T(inv_sigma_m);
    return true;
  }
};

}  // namespace

BundleAdjustmentResult solve_bundle_adjustment(const BundleAdjustmentProblem& pb, const BundleAdjustmentOptions& options,
                                               const std::atomic<bool>* abort) {
  BundleAdjustmentResult res;
  const std::size_t nc = pb.cameras.size(), np = pb.points.size(), nm = pb.measurements.size();
  res.poses.resize(nc);
  for (std::size_t c = 0; c < nc; ++c) res.poses[c] = pb.cameras[c].T_cw;
  res.points = pb.points;
  res.planes = pb.planes;
  res.measurement_inlier.assign(nm, true);
  if (nm == 0 || nc == 0) return res;
  const std::size_t nplanes = pb.planes.size();
  std::vector<double> plane_n(3 * nplanes), plane_d(nplanes);
  for (std::size_t j = 0; j < nplanes; ++j) {
    const Eigen::Vector3d n = pb.planes[j].n.normalized();
    for (int k = 0; k < 3; ++k) plane_n[3 * j + k] = n[k];
    plane_d[j] = pb.planes[j].d;
  }

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
  ceres::HuberLoss huber_plane(3.0);  // a plane joined to the wrong landmark pulls no harder than 3 sigma
  ceres::SphereManifold<3> unit_normal;
  AbortCallback callback(abort);
  int free_cameras = 0;
  for (const auto& c : pb.cameras) free_cameras += !c.fixed;

  for (int phase = 0; phase < 2; ++phase) {
    ceres::Problem::Options po;
    po.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    po.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
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
    for (const auto& rp : pb.relative_poses) {
      const auto i = static_cast<std::size_t>(rp.i), j = static_cast<std::size_t>(rp.j);
      if (i >= nc || j >= nc || i == j || (pb.cameras[i].fixed && pb.cameras[j].fixed)) continue;
      const Eigen::LLT<Eigen::Matrix<double, 6, 6>> llt(rp.information);
      if (llt.info() != Eigen::Success) continue;
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<RelativePoseInfoCost, 6, 6, 6>(new RelativePoseInfoCost{
                                   Eigen::Quaterniond(rp.T_ij.rotation_matrix()), rp.T_ij.translation(), llt.matrixU()}),
                               nullptr, &poses[6 * i], &poses[6 * j]);
      camera_used[i] = camera_used[j] = 1;
    }
    for (const auto& held : pb.held_in_place) {
      const auto c = static_cast<std::size_t>(held.camera);
      if (c >= nc || pb.cameras[c].fixed) continue;
      const double spread = std::sqrt(static_cast<double>(std::max(held.group, 1)));
      auto* cost = new HoldInPlaceCost{{}, 1.0 / (spread * pb.hold_sigma_rad), 1.0 / (spread * pb.hold_sigma_m)};
      detail::pose_to_block(pb.cameras[c].T_cw, cost->start);
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<HoldInPlaceCost, 6, 6>(cost), nullptr, &poses[6 * c]);
      camera_used[c] = 1;
    }
    // A free camera that nothing else holds (its points all rejected) gets no plane term: the
    // planes alone leave it free to slide along them (a singular system).
    std::vector<char> plane_used(nplanes, 0);
    for (const auto& pm : pb.plane_measurements) {
      const auto c = static_cast<std::size_t>(pm.camera), j = static_cast<std::size_t>(pm.plane);
      if (c >= nc || j >= nplanes || (!camera_used[c] && !pb.cameras[c].fixed)) continue;
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PlaneCost, 4, 6, 3, 1>(new PlaneCost{
                                   pm.m.n_c, pm.m.d_c, 1.0 / pb.plane_sigma_rad, 1.0 / pb.plane_sigma_m}),
                               &huber_plane, &poses[6 * c], &plane_n[3 * j], &plane_d[j]);
      camera_used[c] = 1;  // (fixed anchors: set constant below)
      if (!plane_used[j]) problem.SetManifold(&plane_n[3 * j], &unit_normal);
      plane_used[j] = 1;
    }
    if (pb.planar.enabled)
      for (std::size_t c = 0; c < nc; ++c)
        if (camera_used[c] && !pb.cameras[c].fixed)
          problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PlanarMotionCost, 4, 6>(new PlanarMotionCost{
                                       pb.planar.up_c, 1.0 / pb.planar.sigma_m, 1.0 / pb.planar.sigma_rad}),
                                   nullptr, &poses[6 * c]);
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
  for (std::size_t j = 0; j < nplanes; ++j) res.planes[j] = {Eigen::Vector3d(&plane_n[3 * j]).normalized(), plane_d[j]};
  res.final_rms_px = rms(true);
  return res;
}

}  // namespace builtscene::slam
