#include "core/se3.hpp"

#include <cmath>

#include "core/so3.hpp"

namespace builtscene {

Eigen::Matrix3d so3_left_jacobian(const Eigen::Vector3d& omega) {
  const double theta = omega.norm();
  const Eigen::Matrix3d W = skew(omega);
  if (theta < 1e-5) return Eigen::Matrix3d::Identity() + 0.5 * W + W * W / 6.0;
  const double t2 = theta * theta;
  return Eigen::Matrix3d::Identity() + (1.0 - std::cos(theta)) / t2 * W + (theta - std::sin(theta)) / (t2 * theta) * W * W;
}

SE3 SE3::exp(const Eigen::Matrix<double, 6, 1>& xi) {
  const Eigen::Vector3d rho = xi.head<3>();
  const Eigen::Vector3d omega = xi.tail<3>();
  return SE3(so3_exp(omega), so3_left_jacobian(omega) * rho);
}

Eigen::Matrix<double, 6, 1> SE3::log() const {
  const Eigen::Vector3d omega = so3_log(q_);
  Eigen::Matrix<double, 6, 1> xi;
  xi.head<3>() = so3_left_jacobian(omega).inverse() * t_;
  xi.tail<3>() = omega;
  return xi;
}

Eigen::Matrix4d SE3::matrix() const {
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.topLeftCorner<3, 3>() = q_.toRotationMatrix();
  T.topRightCorner<3, 1>() = t_;
  return T;
}

SE3 SE3::inverse() const {
  const Eigen::Quaterniond qi = q_.conjugate();
  return SE3(qi, -(qi * t_));
}

SE3 SE3::interpolate(const SE3& a, const SE3& b, double s) {
  return a * SE3::exp(s * (a.inverse() * b).log());
}

}  // namespace builtscene
