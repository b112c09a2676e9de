// Planar motion terms against closed-form poses: a camera turned about the floor normal and
// moved along the floor breaks nothing; a raised or tilted one is charged its height and tilt
// over their standard deviations, by the tracking prior and the bundle-adjustment cost alike.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "slam/planar_motion.hpp"
#include "slam/reprojection_cost.hpp"

namespace builtscene::slam {
namespace {

// The prior's residual at a pose, as pose_optimizer.cpp computes it.
Eigen::Matrix<double, 6, 1> prior_residual(const PosePrior& p, const SE3& T) {
  const Eigen::Matrix3d R = T.rotation_matrix(), R0 = p.T_cw.rotation_matrix();
  const Eigen::AngleAxisd aa(R * R0.transpose());
  Eigen::Matrix<double, 6, 1> e;
  e << aa.angle() * aa.axis(), T.translation() - R * R0.transpose() * p.T_cw.translation();
  return p.sqrt_information * e;
}

Eigen::Vector4d cost_residual(const PlanarMotion& pm, const SE3& T) {
  double block[6];
  detail::pose_to_block(T, block);
  Eigen::Vector4d r;
  PlanarMotionCost{pm.up_c, 1 / pm.sigma_m, 1 / pm.sigma_rad}(block, r.data());
  return r;
}

// Camera-to-world pose: heading `yaw` about the floor normal, at `ground` on the floor plane,
// raised by `height` and tilted by `tilt` about the camera's x axis.
SE3 camera(const PlanarMotion& pm, double yaw, const Eigen::Vector3d& ground, double height, double tilt) {
  const Eigen::Matrix3d R_wc =
      Eigen::AngleAxisd(yaw, pm.up_c).toRotationMatrix() * Eigen::AngleAxisd(tilt, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const Eigen::Vector3d c = ground - pm.up_c * pm.up_c.dot(ground) + pm.up_c * height;
  return SE3(R_wc, c).inverse();
}

TEST(PlanarMotion, MotionOnTheFloorCostsNothing) {
  const auto pm = PlanarMotion::from_pitch(5.0);
  EXPECT_NEAR(pm.up_c.norm(), 1.0, 1e-12);
  for (double yaw : {0.0, 0.7, -2.5}) {
    const SE3 T = camera(pm, yaw, Eigen::Vector3d(3.0, -0.4, 7.5), 0.0, 0.0);
    const auto prior = planar_prior(pm, T);
    EXPECT_LT((prior.T_cw.translation() - T.translation()).norm(), 1e-9);
    EXPECT_LT(prior_residual(prior, T).norm(), 1e-6);
    EXPECT_LT(cost_residual(pm, T).norm(), 1e-9);
  }
}

TEST(PlanarMotion, HeightAndTiltAreChargedOverTheirSigmas) {
  auto pm = PlanarMotion::from_pitch(5.0);
  pm.sigma_m = 0.01;
  pm.sigma_rad = 0.005;
  const double height = 0.04, tilt = 0.01;  // 4 sigma and 2 sigma
  const SE3 raised = camera(pm, 1.1, Eigen::Vector3d(-2.0, 0.3, 4.0), height, 0.0);
  const SE3 tilted = camera(pm, 1.1, Eigen::Vector3d(-2.0, 0.3, 4.0), 0.0, tilt);
  EXPECT_NEAR(cost_residual(pm, raised).norm(), height / pm.sigma_m, 1e-6);
  EXPECT_NEAR(prior_residual(planar_prior(pm, raised), raised).norm(), height / pm.sigma_m, 1e-4);
  // A tilt by angle a moves the normal by 2 sin(a / 2) (chord), ~a for small angles; the
  // prior's linearized form charges the angle itself.
  EXPECT_NEAR(cost_residual(pm, tilted).norm(), 2 * std::sin(tilt / 2) / pm.sigma_rad, 1e-6);
  EXPECT_NEAR(prior_residual(planar_prior(pm, tilted), tilted).norm(), tilt / pm.sigma_rad, 1e-3);
  // The prior's target is on the plane and keeps the heading and the position on the floor.
  const auto p = planar_prior(pm, raised);
  EXPECT_LT(cost_residual(pm, p.T_cw).norm(), 1e-9);
  const Eigen::Vector3d c = raised.inverse().translation(), c0 = p.T_cw.inverse().translation();
  EXPECT_NEAR((c - c0).norm(), height, 1e-9);
}

}  // namespace
}  // namespace builtscene::slam
