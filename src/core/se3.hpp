#pragma once
// Rigid transforms (rotation as a unit quaternion, translation). By convention a pose T_wc
// maps camera coordinates to world coordinates: p_w = T_wc * p_c.
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace builtscene {

class SE3 {
 public:
  SE3() : q_(Eigen::Quaterniond::Identity()), t_(Eigen::Vector3d::Zero()) {}
  SE3(const Eigen::Quaterniond& q, const Eigen::Vector3d& t) : q_(q.normalized()), t_(t) {}
  SE3(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) : q_(Eigen::Quaterniond(R).normalized()), t_(t) {}
  explicit SE3(const Eigen::Matrix4d& T) : SE3(Eigen::Matrix3d(T.topLeftCorner<3, 3>()), T.topRightCorner<3, 1>()) {}

  // Tangent vector (rho, omega): translation part first, then rotation.
  static SE3 exp(const Eigen::Matrix<double, 6, 1>& xi);
  Eigen::Matrix<double, 6, 1> log() const;

  const Eigen::Quaterniond& rotation() const { return q_; }
  Eigen::Matrix3d rotation_matrix() const { return q_.toRotationMatrix(); }
  const Eigen::Vector3d& translation() const { return t_; }
  Eigen::Matrix4d matrix() const;

  SE3 inverse() const;
  SE3 operator*(const SE3& o) const { return SE3(q_ * o.q_, t_ + q_ * o.t_); }
  Eigen::Vector3d operator*(const Eigen::Vector3d& p) const { return q_ * p + t_; }

  // Geodesic interpolation on the group (constant twist): a at s=0, b at s=1.
  static SE3 interpolate(const SE3& a, const SE3& b, double s);

 private:
  Eigen::Quaterniond q_;
  Eigen::Vector3d t_;
};

// Left Jacobian V of SO(3) used by exp/log of SE(3): t = V(omega) * rho.
Eigen::Matrix3d so3_left_jacobian(const Eigen::Vector3d& omega);

}  // namespace builtscene
