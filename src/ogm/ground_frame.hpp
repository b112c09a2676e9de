#pragma once
// The ground frame of a map: z up, floor at z = 0, x/y spanning the floor. Every 2D map
// (occupancy grid, 2D poses, points of interest) is expressed in it. A trajectory's world
// frame relates to it by T_gw:
//   - a generated world (z-up, floor at 0): identity;
//   - a SLAM map whose world is its first camera (x right, y down, z forward): ground x from
//     camera x, ground y from camera z, up = -y, floor `camera_height` below the first camera
//     (the source's convention);
//   - or estimated from the data: up and the floor from the dominant floor plane of the depth
//     points (searched near the cameras' mean down direction), x from the world's x axis.
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "core/camera.hpp"
#include "core/se3.hpp"

namespace builtscene {

struct Pose2D {
  double x = 0, y = 0, theta = 0;  // theta counter-clockwise from +x
};

class GroundFrame {
 public:
  GroundFrame() = default;
  explicit GroundFrame(const SE3& T_gw) : T_gw_(T_gw) {}

  static GroundFrame z_up() { return GroundFrame(); }
  static GroundFrame first_camera(double camera_height);
  // Up = minus the mean of the cameras' y axes; floor = lowest dense layer of depth points.
  static GroundFrame estimate(const std::vector<SE3>& T_wc, const std::vector<cv::Mat>& depths,
                              const PinholeCamera& camera);

  const SE3& T_gw() const { return T_gw_; }
  SE3 camera_in_ground(const SE3& T_wc) const { return T_gw_ * T_wc; }
  // Position on the floor and heading: the camera's forward (z) axis projected on the floor.
  Pose2D to_2d(const SE3& T_wc) const;

 private:
  SE3 T_gw_;
};

// Parses --world: "zup", "camera" (with camera_height), a grid's YAML (its ground_frame_T_gw:
// regions and 2D poses on that grid) or "auto" (needs data; returns false).
bool parse_ground_frame(const std::string& name, double camera_height, GroundFrame& out);

}  // namespace builtscene
