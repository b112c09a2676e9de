#pragma once
// Known-truth configurations for the optimizer tests: points in front of cameras, exact
// projections, noise and outliers drawn from a seeded generator.
#include <random>
#include <vector>

#include "core/se3.hpp"
#include "core/so3.hpp"
#include "slam/observation.hpp"

namespace builtscene::slam::test {

inline Intrinsics kinect() { return {525.0, 525.0, 319.5, 239.5, 40.0}; }

inline Eigen::Vector2d project(const Intrinsics& K, const Eigen::Vector3d& pc) {
  return {K.fx * pc.x() / pc.z() + K.cx, K.fy * pc.y() / pc.z() + K.cy};
}

inline SE3 perturb(const SE3& T, double rot_rad, double trans_m, std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  const Eigen::Vector3d w = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized() * rot_rad;
  const Eigen::Vector3d t = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized() * trans_m;
  return SE3(so3_exp(w), t) * T;
}

inline double rotation_error_deg(const SE3& a, const SE3& b) {
  return so3_log(a.rotation() * b.rotation().inverse()).norm() * 180.0 / M_PI;
}

inline double translation_error(const SE3& a, const SE3& b) {
  // Compare camera centres.
  return (a.inverse().translation() - b.inverse().translation()).norm();
}

}  // namespace builtscene::slam::test
