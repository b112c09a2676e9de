#include "core/so3.hpp"

#include <cmath>

namespace builtscene {

Eigen::Matrix3d skew(const Eigen::Vector3d& w) {
  Eigen::Matrix3d m;
  m << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return m;
}

Eigen::Quaterniond so3_exp(const Eigen::Vector3d& omega) {
  const double theta = omega.norm();
  const double half = 0.5 * theta;
  double imag_factor, real;
  if (theta < 1e-8) {
    const double t2 = theta * theta;
    imag_factor = 0.5 - t2 / 48.0;
    real = 1.0 - t2 / 8.0;
  } else {
    imag_factor = std::sin(half) / theta;
    real = std::cos(half);
  }
  return Eigen::Quaterniond(real, imag_factor * omega.x(), imag_factor * omega.y(), imag_factor * omega.z());
}

Eigen::Vector3d so3_log(const Eigen::Quaterniond& q_in) {
  Eigen::Quaterniond q = q_in.normalized();
  if (q.w() < 0) q.coeffs() = -q.coeffs();  // angle in [0, pi]
  const Eigen::Vector3d v = q.vec();
  const double n = v.norm();
  if (n < 1e-10) return 2.0 * v / q.w();  // first order; q.w() ~ 1 here
  // atan2 is accurate over the whole range, unlike acos near 0 or asin near pi.
  const double theta = 2.0 * std::atan2(n, q.w());
  return theta / n * v;
}

}  // namespace builtscene
