#pragma once
// Similarity transforms: p' = s * R * p + t. Used for scaled alignment (Umeyama with scale)
// and wherever a map's scale is not fixed.
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "core/se3.hpp"

namespace builtscene {

class Sim3 {
 public:
  Sim3() : q_(Eigen::Quaterniond::Identity()), t_(Eigen::Vector3d::Zero()), s_(1.0) {}
  Sim3(const Eigen::Quaterniond& q, const Eigen::Vector3d& t, double s) : q_(q.normalized()), t_(t), s_(s) {}
  explicit Sim3(const SE3& T) : q_(T.rotation()), t_(T.translation()), s_(1.0) {}

  // Tangent vector (rho, omega, sigma) with scale = e^sigma.
  static Sim3 exp(const Eigen::Matrix<double, 7, 1>& xi);
  Eigen::Matrix<double, 7, 1> log() const;

  const Eigen::Quaterniond& rotation() const { return q_; }
  const Eigen::Vector3d& translation() const { return t_; }
  double scale() const { return s_; }
  Eigen::Matrix4d matrix() const;

  Sim3 inverse() const;
  Sim3 operator*(const Sim3& o) const { return Sim3(q_ * o.q_, t_ + s_ * (q_ * o.t_), s_ * o.s_); }
  Eigen::Vector3d operator*(const Eigen::Vector3d& p) const { return s_ * (q_ * p) + t_; }

  // Applied to a pose: rotation composed, camera centre mapped, scale leaves the pose rigid.
  SE3 transform_pose(const SE3& T) const { return SE3(q_ * T.rotation(), *this * T.translation()); }

  static Sim3 interpolate(const Sim3& a, const Sim3& b, double s);

 private:
  Eigen::Quaterniond q_;
  Eigen::Vector3d t_;
  double s_;
};

// The matrix W(sigma, omega) = integral_0^1 e^(sigma tau) exp(tau [omega]x) d tau,
// with t = W * rho in Sim3::exp.
Eigen::Matrix3d sim3_translation_jacobian(double sigma, const Eigen::Vector3d& omega);

}  // namespace builtscene
