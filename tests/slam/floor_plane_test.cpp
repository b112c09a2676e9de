#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <Eigen/Geometry>

#include "../common/kinect_camera.hpp"
#include "slam/floor_plane.hpp"

namespace builtscene::slam {
namespace {

using builtscene::testing::kinect_camera;

// A camera `h` above a floor, pitched down and rolled; a wall 3 m ahead (along the floor)
// closes the view. Depth by ray casting, with Gaussian noise of `sigma` metres.
cv::Mat floor_and_wall(const PinholeCamera& cam, const Eigen::Vector3d& up_c, double h, double sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma);
  // The wall: normal along the camera's forward direction projected onto the floor.
  Eigen::Vector3d fwd = Eigen::Vector3d::UnitZ() - up_c * up_c.z();
  fwd.normalize();
  cv::Mat depth(cam.height, cam.width, CV_32F, cv::Scalar(0));
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u) {
      const Eigen::Vector3d ray((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0);
      double s = 1e9;
      if (ray.dot(up_c) < 0) s = std::min(s, h / -ray.dot(up_c));      // floor: up.p = -h
      if (ray.dot(fwd) > 0) s = std::min(s, 3.0 / ray.dot(fwd));       // wall: fwd.p = 3
      if (s < 1e8) depth.at<float>(v, u) = static_cast<float>(s + noise(rng));  // ray.z = 1: s is the depth
    }
  return depth;
}

double angle_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180 / M_PI;
}

TEST(FloorPlane, RecoversATiltedFloorUnderNoiseBesideAWall) {
  const PinholeCamera cam = kinect_camera();
  // Pitched 5.3 degrees down, rolled 0.4: the nominal 5-degree guess is 0.5 degrees off.
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(0.4 * M_PI / 180, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(5.3 * M_PI / 180, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  const Eigen::Vector3d up_true = R * Eigen::Vector3d(0, -1, 0);
  const Eigen::Vector3d guess(0, -std::cos(5 * M_PI / 180), -std::sin(5 * M_PI / 180));
  ASSERT_GT(angle_deg(up_true, guess), 0.4);
  const cv::Mat depth = floor_and_wall(cam, up_true, 1.0, 0.005, 7);
  const auto floor = estimate_floor_plane(depth, cam, guess);
  ASSERT_TRUE(floor.has_value());
  EXPECT_LT(angle_deg(floor->up_c, up_true), 0.05);
  EXPECT_NEAR(floor->height_m, 1.0, 0.005);
  EXPECT_GT(floor->inliers, 1000u);
}

TEST(FloorPlane, NoFloorInViewGivesNone) {
  const PinholeCamera cam = kinect_camera();
  // Looking up at 40 degrees: no pixel sees the floor, only the wall above the camera.
  const Eigen::Vector3d up_c = (Eigen::AngleAxisd(40 * M_PI / 180, Eigen::Vector3d::UnitX()) * Eigen::Vector3d(0, -1, 0));
  cv::Mat depth = floor_and_wall(cam, up_c, 1.0, 0.0, 1);
  const Eigen::Vector3d guess(0, -1, 0);
  EXPECT_FALSE(estimate_floor_plane(depth, cam, guess).has_value());
  EXPECT_FALSE(estimate_floor_plane(cv::Mat(), cam, guess).has_value());
  EXPECT_FALSE(estimate_floor_plane(cv::Mat(480, 640, CV_32F, cv::Scalar(0)), cam, guess).has_value());
}

}  // namespace
}  // namespace builtscene::slam
