#include "core/sim3.hpp"

#include <cmath>

#include "core/so3.hpp"

namespace builtscene {

// W = A I + (S/theta) [w] + ((A - C)/theta^2) [w]^2 with
//   A = int e^(s tau), S = int e^(s tau) sin(theta tau), C = int e^(s tau) cos(theta tau)  over [0,1].
// Small sigma and small theta use the limits of the same integrals (series in sigma).
Eigen::Matrix3d sim3_translation_jacobian(double sigma, const Eigen::Vector3d& omega) {
  const double theta = omega.norm();
  const Eigen::Matrix3d W = skew(omega);
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  const double es = std::exp(sigma);
  const bool small_sigma = std::abs(sigma) < 1e-6;
  const double A = small_sigma ? 1.0 + sigma / 2.0 + sigma * sigma / 6.0 : (es - 1.0) / sigma;
  double b, c;  // coefficients of [w] and [w]^2
  if (theta < 1e-6) {
    // b -> int tau e^(s tau), c -> int tau^2/2 e^(s tau)
    if (small_sigma) {
      b = 0.5 + sigma / 3.0 + sigma * sigma / 8.0;
      c = 1.0 / 6.0 + sigma / 8.0 + sigma * sigma / 20.0;
    } else {
      const double s2 = sigma * sigma;
      b = (es * (sigma - 1.0) + 1.0) / s2;
      c = 0.5 * (es * (s2 - 2.0 * sigma + 2.0) - 2.0) / (s2 * sigma);
    }
  } else {
    const double st = std::sin(theta), ct = std::cos(theta);
    const double d = sigma * sigma + theta * theta;
    const double S = (es * (sigma * st - theta * ct) + theta) / d;
    const double C = (es * (sigma * ct + theta * st) - sigma) / d;
    b = S / theta;
    c = (A - C) / (theta * theta);
  }
  return A * I + b * W + c * W * W;
}

Sim3 Sim3::exp(const Eigen::Matrix<double, 7, 1>& xi) {
  const Eigen::Vector3d rho = xi.head<3>();
  const Eigen::Vector3d omega = xi.segment<3>(3);
  const double sigma = xi(6);
  return Sim3(so3_exp(omega), sim3_translation_jacobian(sigma, omega) * rho, std::exp(sigma));
}

Eigen::Matrix<double, 7, 1> Sim3::log() const {
  Eigen::Matrix<double, 7, 1> xi;
  const Eigen::Vector3d omega = so3_log(q_);
  const double sigma = std::log(s_);
  xi.head<3>() = sim3_translation_jacobian(sigma, omega).inverse() * t_;
  xi.segment<3>(3) = omega;
  xi(6) = sigma;
  return xi;
}

Eigen::Matrix4d Sim3::matrix() const {
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.topLeftCorner<3, 3>() = s_ * q_.toRotationMatrix();
  T.topRightCorner<3, 1>() = t_;
  return T;
}

Sim3 Sim3::inverse() const {
  const Eigen::Quaterniond qi = q_.conjugate();
  return Sim3(qi, -(qi * t_) / s_, 1.0 / s_);
}

Sim3 Sim3::interpolate(const Sim3& a, const Sim3& b, double s) {
  return a * Sim3::exp(s * (a.inverse() * b).log());
}

}  // namespace builtscene
