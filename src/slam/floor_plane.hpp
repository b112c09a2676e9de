#pragma once
// The floor in one depth image: for planar motion (planar_motion.hpp) the floor's normal in
// the first camera's coordinates decides the plane every later camera is held to, and a
// normal taken from the robot's nominal pitch is off by the first frame's wobble (0.27
// degrees on the generated corridor: 12 cm of height over 26 m). The floor itself, seen in
// the first keyframe's depth, is exact for that camera (the map's world).
#include <optional>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "core/camera.hpp"

namespace builtscene::slam {

struct FloorPlane {
  Eigen::Vector3d up_c;   // unit normal in camera coordinates, pointing from the floor to the camera
  double height_m = 0;    // camera centre above the floor
  std::size_t inliers = 0;
};

struct FloorPlaneOptions {
  double max_tilt_from_guess_deg = 15;  // the plane's normal within this of the guess
  double inlier_m = 0.02;
  double min_height_m = 0.1;            // below the camera by at least this
  std::size_t min_inliers = 500;
  double max_depth_m = 4.0;              // farther readings are too noisy to help
  int stride_px = 4;
  int normal_step_px = 6;               // a point's own surface normal from neighbours this far
  double max_local_tilt_deg = 30;       // ... within this of the guess
  int iterations = 300;
};

// RANSAC over the depth's points (metres, CV_32F, 0 = none; undistorted pinhole) for the
// plane below the camera whose normal is nearest `up_guess_c`, then a least-squares refit to
// its inliers. None when no such plane holds `min_inliers` points. Deterministic.
std::optional<FloorPlane> estimate_floor_plane(const cv::Mat& depth_m, const PinholeCamera& cam,
                                               const Eigen::Vector3d& up_guess_c, const FloorPlaneOptions& opt = {});

}  // namespace builtscene::slam
