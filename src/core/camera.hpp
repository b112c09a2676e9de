#pragma once
// Pinhole camera with radial-tangential (OpenCV / ORB-SLAM "k1 k2 p1 p2 k3") distortion,
// plus the RGB-D settings that travel with it in camera.yaml.
#include <filesystem>

#include <Eigen/Core>

namespace builtscene {

struct PinholeCamera {
  double fx = 0, fy = 0, cx = 0, cy = 0;
  double k1 = 0, k2 = 0, p1 = 0, p2 = 0, k3 = 0;
  int width = 0, height = 0;

  bool has_distortion() const { return k1 != 0 || k2 != 0 || p1 != 0 || p2 != 0 || k3 != 0; }

  // Camera frame: x right, y down, z forward. Projects with distortion applied.
  Eigen::Vector2d project(const Eigen::Vector3d& p_c) const;
  // Normalized undistorted coordinates (x/z, y/z) -> distorted normalized coordinates.
  Eigen::Vector2d distort(const Eigen::Vector2d& xn) const;
  // Inverse of distort by fixed-point iteration (converges for ordinary lens distortion).
  Eigen::Vector2d undistort(const Eigen::Vector2d& xd) const;
  // Pixel (distorted) -> undistorted pixel in the same intrinsics.
  Eigen::Vector2d undistort_pixel(const Eigen::Vector2d& px) const;
  // Pixel and depth (metres along z) -> camera-frame point; removes distortion.
  Eigen::Vector3d unproject(const Eigen::Vector2d& px, double depth) const;
  bool in_image(const Eigen::Vector2d& px, double border = 0.0) const;
};

struct RgbdCameraSettings {
  PinholeCamera camera;
  double fps = 30.0;
  double bf = 40.0;                // baseline (m) times fx: the virtual stereo of RGB-D
  double th_depth = 40.0;          // close/far threshold in baselines (ORB-SLAM ThDepth)
  double depth_map_factor = 5000;  // depth PNG value per metre
  // Standard deviation (pixels) of the disparity bf / depth that a keypoint's depth reading
  // implies: the depth residual of the optimizers is weighted by it, apart from the keypoint's
  // pixel noise. 0 = ORB-SLAM's virtual right coordinate with the keypoint's pyramid sigma.
  // [DisparitySigma]; see docs/slam.md, "Depth weight".
  double disparity_sigma = 0.2;
  // The same in global bundle adjustment (after a loop closure), where every point is
  // estimated anew from all its readings: there it can be the sensor's own disparity noise (the
  // generated Kinect's is ~0.07-0.08 px at every range), while frame tracking keeps
  // DisparitySigma, which also covers the error of the map points it holds fixed.
  // [GlobalBADisparitySigma], pixels; 0 = DisparitySigma (the default).
  // Ignored when DisparitySigma is 0 (ORB-SLAM's form). Off by default (docs/slam.md, "Where
  // the corridor's straights get too long"): 0.1 took the generated corridor's 5-seed median
  // from 6.83 to 5.29 cm and its markers from 9 to 12 of 15 tags within 5 cm, but one of three
  // generated offices from 4.0 to 12.2 cm.
  double global_ba_disparity_sigma = 0.0;
  // The same in local bundle adjustment, fixed. [LocalBADisparitySigma], pixels; 0 (the
  // default) = DisparitySigma, or with `slam --adaptive-ba-disparity` the noise each local BA's
  // window shows where the window is held (slam/local_ba_disparity.hpp). A fixed 0.1 with GlobalBADisparitySigma
  // 0.1 gave the generated corridor's markers 14 of 15 tags within 5 cm, but a generated office
  // 5.4 -> 12.9 cm and the real kitchen 4.41 -> 5.41 cm (docs/slam.md, same section).
  double local_ba_disparity_sigma = 0.0;
  // Keypoint depth readings beyond this many metres are not used: such keypoints are treated
  // as having no depth (triangulated like a monocular camera's). A structured-light sensor's
  // depth error grows as depth^2 and its disparity steps reach ~10 cm at 6 m. [MaxDepth],
  // 0 = no limit (the default): 5 m took the generated corridor's west leg from 3.5 % too long
  // to 0.1 % but moved whole corridor runs both ways (docs/slam.md, "Far depth readings").
  double max_depth = 0.0;
  // Keypoint depth readings beyond this many metres are "far": they still place new map points,
  // but the optimizers (frame pose, local and global bundle adjustment) and the matchers'
  // checks treat the keypoint as monocular, without the disparity residual; keyframes made by
  // the depth-odometry bridge keep them as measurements (KeyFrame::keeps_far_readings).
  // [FarDepth], 0 = off (the default): 5 m takes the generated corridor's west leg from 3.5 %
  // too long to 0.0 % and the 5-seed corridor median from 6.83 to 5.50 cm, but the office from
  // 4.28 to 5.66 cm: docs/slam.md, "FarDepth's exception for bridged keyframes only".
  double far_depth = 0.0;
  bool rgb_order = true;           // Camera.RGB: 1 = images are RGB, 0 = BGR

  double close_depth() const { return th_depth * bf / camera.fx; }
};

// Reads ORB-SLAM keys: Camera.fx fy cx cy k1 k2 p1 p2 [k3] width height [fps bf RGB],
// [ThDepth], [DepthMapFactor]. Missing or invalid required keys name the file and key.
RgbdCameraSettings load_camera_settings(const std::filesystem::path& path);
void save_camera_settings(const std::filesystem::path& path, const RgbdCameraSettings& s);

}  // namespace builtscene
