#pragma once
// Ceres cost functors of the reprojection error (internal to pose_optimizer.cpp and
// local_bundle_adjuster.cpp). A pose block is 6 doubles: angle-axis rotation then translation
// of T_cw (world -> camera).
#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include "core/se3.hpp"
#include "slam/observation.hpp"

namespace builtscene::slam::detail {

template <int kResiduals, typename T>
inline bool project_residuals(const T* pose, const T* pw, const Intrinsics& K, const Observation& o, double sqrt_info,
                              T* r) {
  T pc[3];
  ceres::AngleAxisRotatePoint(pose, pw, pc);
  pc[0] += pose[3];
  pc[1] += pose[4];
  pc[2] += pose[5];
  const T inv_z = T(1.0) / pc[2];
  const T u = T(K.fx) * pc[0] * inv_z + T(K.cx);
  const T v = T(K.fy) * pc[1] * inv_z + T(K.cy);
  r[0] = T(sqrt_info) * (u - T(o.uv.x()));
  r[1] = T(sqrt_info) * (v - T(o.uv.y()));
  if constexpr (kResiduals == 3) {
    if (K.disparity_sigma > 0)
      r[2] = T(1.0 / K.disparity_sigma) * (T(K.bf) * inv_z - T(o.uv.x() - o.u_right));
    else
      r[2] = T(sqrt_info) * (u - T(K.bf) * inv_z - T(o.u_right));
  }
  return true;
}

// The 3D point is a constant: motion-only optimization.
template <int kResiduals>
struct PoseOnlyCost {
  Eigen::Vector3d pw;
  Intrinsics K;
  Observation o;
  double sqrt_info;
  template <typename T>
  bool operator()(const T* pose, T* r) const {
    const T p[3] = {T(pw.x()), T(pw.y()), T(pw.z())};
    return project_residuals<kResiduals>(pose, p, K, o, sqrt_info, r);
  }
};

// Pose and point both free: bundle adjustment.
template <int kResiduals>
struct PosePointCost {
  Intrinsics K;
  Observation o;
  double sqrt_info;
  template <typename T>
  bool operator()(const T* pose, const T* point, T* r) const {
    return project_residuals<kResiduals>(pose, point, K, o, sqrt_info, r);
  }
};

// The relative pose T_ij = T_i * T_j^-1 of two pose blocks (angle-axis, translation of T_cw):
// rotation q (w, x, y, z) and translation t.
template <typename T>
void relative_pose_of_blocks(const T* pi, const T* pj, T* q, T* t) {
  T qi[4], qj[4];
  ceres::AngleAxisToQuaternion(pi, qi);
  ceres::AngleAxisToQuaternion(pj, qj);
  const T qj_inv[4] = {qj[0], -qj[1], -qj[2], -qj[3]};
  ceres::QuaternionProduct(qi, qj_inv, q);
  T tj[3];
  ceres::UnitQuaternionRotatePoint(q, pj + 3, tj);
  for (int k = 0; k < 3; ++k) t[k] = pi[3 + k] - tj[k];
}

inline void pose_to_block(const SE3& T, double* block) {
  const Eigen::AngleAxisd aa(T.rotation());
  const Eigen::Vector3d w = aa.angle() * aa.axis();
  for (int i = 0; i < 3; ++i) {
    block[i] = w[i];
    block[3 + i] = T.translation()[i];
  }
}

inline SE3 block_to_pose(const double* block) {
  const Eigen::Vector3d w(block[0], block[1], block[2]);
  const double angle = w.norm();
  const Eigen::Quaterniond q =
      angle < 1e-12 ? Eigen::Quaterniond::Identity() : Eigen::Quaterniond(Eigen::AngleAxisd(angle, w / angle));
  return SE3(q, Eigen::Vector3d(block[3], block[4], block[5]));
}

}  // namespace builtscene::slam::detail
