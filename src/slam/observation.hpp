#pragma once
// One measurement of a 3D point in a camera, as both optimizers use it: the undistorted pixel,
// optionally the virtual right coordinate (RGB-D keypoints with depth), and the information
// 1 / sigma^2 of the keypoint's pyramid level.
#include <Eigen/Core>

namespace builtscene::slam {

struct Intrinsics {
  double fx = 0, fy = 0, cx = 0, cy = 0, bf = 0;
  // > 0: the third residual of a stereo observation is the disparity bf / z against the
  // reading's (u - u_right), weighted by 1 / disparity_sigma^2 whatever the keypoint's level:
  // a depth reading's error does not grow with the pyramid level the corner was found on, and
  // it is independent of the corner's pixel error (which the u_right form counts twice).
  // 0: ORB-SLAM's u_right residual with the level's sigma.
  double disparity_sigma = 0;
};

struct Observation {
  Eigen::Vector2d uv = Eigen::Vector2d::Zero();
  double u_right = -1;  // < 0: monocular measurement (2 residuals), else stereo (3)
  double inv_sigma2 = 1;
  bool stereo() const { return u_right >= 0; }
};

// A stereo observation's disparity residual in pixels, without weight: the disparity p_c
// predicts (bf / z) minus the reading's (u - u_right). p_c must be in front of the camera.
inline double disparity_residual(const Intrinsics& K, const Observation& o, const Eigen::Vector3d& p_c) {
  return K.bf * (1.0 / p_c.z()) - (o.uv.x() - o.u_right);
}

// ORB-SLAM's chi-square thresholds at 95 %: 2 and 3 degrees of freedom.
constexpr double kChi2Mono = 5.991;
constexpr double kChi2Stereo = 7.815;

// Squared, information-weighted reprojection error of p_c (camera frame); infinity when the
// point is not in front of the camera.
double reprojection_chi2(const Intrinsics& K, const Observation& o, const Eigen::Vector3d& p_c);

}  // namespace builtscene::slam
