#pragma once
// Rotation helpers on Eigen: skew matrix, exponential and logarithm of SO(3).
#include <Eigen/Core>
#include <Eigen/Geometry>

namespace builtscene {

Eigen::Matrix3d skew(const Eigen::Vector3d& w);

// Rodrigues' formula; exact to machine precision also for tiny angles (Taylor branch).
Eigen::Quaterniond so3_exp(const Eigen::Vector3d& omega);

// Axis-angle vector with angle in [0, pi]; stable near 0 and near pi.
Eigen::Vector3d so3_log(const Eigen::Quaterniond& q);

}  // namespace builtscene
