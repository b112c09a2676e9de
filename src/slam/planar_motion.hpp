#pragma once
// Planar motion of a ground robot (optional): the camera is fixed on a robot that drives on a
// flat floor, so its height above the floor and its tilt (pitch and roll against the floor)
// never change; only the position on the floor and the heading do. In the map's world (the
// first camera's frame) that is: every camera's centre c lies in the plane through the
// origin with normal n, and every camera's rotation R_cw keeps n (R_cw n = n), where n is
// the floor's up direction in camera coordinates (the same in every camera).
//
// Soft: a term of standard deviation sigma_m on the height and sigma_rad on the tilt, in
// tracking's pose optimization (as a PosePrior) and in local and global bundle adjustment
// (PlanarMotionCost), so the floor's bumps and the robot's wobble still fit.
#include <Eigen/Core>
#include <ceres/rotation.h>

#include "core/se3.hpp"
#include "slam/pose_optimizer.hpp"

namespace builtscene::slam {

struct PlanarMotion {
  bool enabled = false;
  Eigen::Vector3d up_c{0.0, -1.0, 0.0};  // floor normal (up) in camera coordinates, unit
  double sigma_m = 0.01;
  double sigma_rad = 0.005;
  // A camera pitched down by `pitch_deg` (x right, y down, z forward), no roll.
  static PlanarMotion from_pitch(double pitch_deg);
};

// The constraint around T_cw as a pose prior: its target is T_cw moved onto the plane
// (height removed along n, tilt removed by the smallest rotation), its square-root
// information holds the three constrained directions only (heading and position on the
// floor are free).
PosePrior planar_prior(const PlanarMotion& pm, const SE3& T_cw);

// Ceres cost on one pose block (angle-axis, translation of T_cw): 4 residuals, the height
// n.c / sigma_m with c = -R^T t (so n.c = -(R n).t) and the tilt (R n - n) / sigma_rad.
struct PlanarMotionCost {
  Eigen::Vector3d n;
  double inv_sigma_m = 100, inv_sigma_rad = 200;
  template <typename T>
  bool operator()(const T* pose, T* r) const {
    const T nn[3] = {T(n.x()), T(n.y()), T(n.z())};
    T Rn[3];
    ceres::AngleAxisRotatePoint(pose, nn, Rn);
    r[0] = -(Rn[0] * pose[3] + Rn[1] * pose[4] + Rn[2] * pose[5]) * T(inv_sigma_m);
    for (int k = 0; k < 3; ++k) r[1 + k] = (Rn[k] - nn[k]) * T(inv_sigma_rad);
    return true;
  }
};

}  // namespace builtscene::slam
