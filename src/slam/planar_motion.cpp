#include "slam/planar_motion.hpp"

#include <cmath>

#include <Eigen/Geometry>

#include "slam/reprojection_cost.hpp"

namespace builtscene::slam {

PlanarMotion PlanarMotion::from_pitch(double pitch_deg) {
  PlanarMotion pm;
  pm.enabled = true;
  const double p = pitch_deg * M_PI / 180.0;
  pm.up_c = Eigen::Vector3d(0.0, -std::cos(p), -std::sin(p));
  return pm;
}

namespace {

// The constraint's residuals at a pose: PlanarMotionCost itself, on doubles.
Eigen::Vector4d planar_residual(const PlanarMotion& pm, const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  double block[6];
  detail::pose_to_block(SE3(R, t), block);
  Eigen::Vector4d r;
  PlanarMotionCost{pm.up_c, 1.0 / pm.sigma_m, 1.0 / pm.sigma_rad}(block, r.data());
  return r;
}

Eigen::Matrix3d exp_so3(const Eigen::Vector3d& w) {
  const double a = w.norm();
  if (a < 1e-15) return Eigen::Matrix3d::Identity();
  return Eigen::AngleAxisd(a, w / a).toRotationMatrix();
}

}  // namespace

PosePrior planar_prior(const PlanarMotion& pm, const SE3& T_cw) {
  const Eigen::Vector3d& n = pm.up_c;
  const Eigen::Matrix3d R = T_cw.rotation_matrix();
  // Target: tilt removed by the smallest rotation taking R n to n, the centre moved into the plane.
  const Eigen::Matrix3d R0 = Eigen::Quaterniond::FromTwoVectors(R * n, n).toRotationMatrix() * R;
  Eigen::Vector3d c = -R.transpose() * T_cw.translation();
  c -= n * n.dot(c);
  const Eigen::Vector3d t0 = -R0 * c;
  // The pose optimizer's prior residual is S [log(R R0^T); t - R R0^T t0]: perturb in those
  // coordinates and differentiate the constraint numerically.
  Eigen::Matrix<double, 4, 6> J;
  const double h = 1e-6;
  for (int k = 0; k < 6; ++k) {
    Eigen::Matrix<double, 6, 1> e = Eigen::Matrix<double, 6, 1>::Zero();
    e[k] = h;
    auto at = [&](const Eigen::Matrix<double, 6, 1>& d) {
      const Eigen::Matrix3d Rd = exp_so3(d.head<3>()) * R0;
      return planar_residual(pm, Rd, Rd * R0.transpose() * t0 + d.tail<3>());
    };
    J.col(k) = (at(e) - at(-e)) / (2 * h);
  }
  Eigen::Matrix<double, 6, 6> S = Eigen::Matrix<double, 6, 6>::Zero();
  S.topRows<4>() = J;
  return PosePrior{SE3(Eigen::Quaterniond(R0), t0), S};
}

}  // namespace builtscene::slam
