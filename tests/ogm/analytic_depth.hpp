#pragma once
// Exact depth images of axis-aligned boxes by ray casting: an independent ground truth for
// the virtual laser scan and the mapper (shares no code with the renderer in src/synth).
#include <limits>
#include <vector>

#include <opencv2/core.hpp>

#include "../common/kinect_camera.hpp"
#include "core/camera.hpp"
#include "core/se3.hpp"

namespace builtscene::testing {

struct Box {
  Eigen::Vector3d lo, hi;  // world (z up)
};

inline double ray_box(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Box& b) {
  double t0 = 0, t1 = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    if (std::abs(d[k]) < 1e-12) {
      if (o[k] < b.lo[k] || o[k] > b.hi[k]) return std::numeric_limits<double>::infinity();
      continue;
    }
    double a = (b.lo[k] - o[k]) / d[k], c = (b.hi[k] - o[k]) / d[k];
    if (a > c) std::swap(a, c);
    t0 = std::max(t0, a);
    t1 = std::min(t1, c);
    if (t0 > t1) return std::numeric_limits<double>::infinity();
  }
  return t0;
}

// Depth (z along the optical axis, metres) of camera T_wc looking at `boxes`.
inline cv::Mat render_depth(const PinholeCamera& cam, const SE3& T_wc, const std::vector<Box>& boxes) {
  cv::Mat depth(cam.height, cam.width, CV_32F, cv::Scalar(0));
  const Eigen::Matrix3d R = T_wc.rotation_matrix();
  const Eigen::Vector3d o = T_wc.translation();
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u) {
      const Eigen::Vector3d rc((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0);
      const Eigen::Vector3d d = R * rc;
      double best = std::numeric_limits<double>::infinity();
      for (const auto& b : boxes) best = std::min(best, ray_box(o, d, b));
      if (std::isfinite(best) && best < 20) depth.at<float>(v, u) = static_cast<float>(best);  // t is z for rc.z = 1
    }
  return depth;
}


// A camera at (x, y, height) looking horizontally along heading `yaw` (z-up world).
inline SE3 level_camera(double x, double y, double height, double yaw) {
  Eigen::Matrix3d R;  // columns: camera x (right), y (down), z (forward) in the world
  const Eigen::Vector3d fwd(std::cos(yaw), std::sin(yaw), 0), down(0, 0, -1);
  R.col(2) = fwd;
  R.col(1) = down;
  R.col(0) = down.cross(fwd);
  return SE3(R, Eigen::Vector3d(x, y, height));
}

}  // namespace builtscene::testing
