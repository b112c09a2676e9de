#pragma once
// Depth images ray-cast from infinite planes (closed form: the depth of a plane along each
// pixel's ray), for the ICP and depth-odometry tests: Kinect-like intrinsics, 640 x 480.
#include <cmath>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "core/se3.hpp"

namespace builtscene::slam::test {

constexpr double kFx = 525, kFy = 525, kCx = 319.5, kCy = 239.5;

struct Plane {
  Eigen::Vector3d n;  // unit normal, world
  double d;           // n . x = d on the plane
};

// Depth (CV_32F metres) of the nearest plane in front of a camera at T_cw (world -> camera; z
// forward, y down); 0 where nothing is hit or beyond max_depth (0: no limit). incidence, when
// given, receives |cos| between each pixel's ray and the plane it hit.
inline cv::Mat render_planes(const std::vector<Plane>& planes, const SE3& T_cw, double max_depth = 0,
                             cv::Mat* incidence = nullptr) {
  const SE3 T_wc = T_cw.inverse();
  const Eigen::Matrix3d R_wc = T_wc.rotation_matrix();
  cv::Mat depth(480, 640, CV_32F, cv::Scalar(0));
  if (incidence) *incidence = cv::Mat(480, 640, CV_32F, cv::Scalar(0));
  for (int v = 0; v < depth.rows; ++v)
    for (int u = 0; u < depth.cols; ++u) {
      const Eigen::Vector3d ray_c((u - kCx) / kFx, (v - kCy) / kFy, 1.0);  // z = 1: the scale is depth
      const Eigen::Vector3d ray_w = R_wc * ray_c;
      double best = 0, cos = 0;
      for (const auto& p : planes) {
        const double denom = p.n.dot(ray_w);
        if (std::abs(denom) < 1e-9) continue;
        const double z = (p.d - p.n.dot(T_wc.translation())) / denom;
        if (z > 0.3 && (best == 0 || z < best)) best = z, cos = std::abs(denom) / ray_w.norm();
      }
      if (max_depth > 0 && best > max_depth) best = 0;
      depth.at<float>(v, u) = static_cast<float>(best);
      if (incidence) incidence->at<float>(v, u) = static_cast<float>(cos);
    }
  return depth;
}

}  // namespace builtscene::slam::test
