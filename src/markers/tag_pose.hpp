#pragma once
// The pose of a detected square tag in the camera frame, T_cg. Tag frame: origin at the
// tag's centre, x to the tag's right and y to its top as the tag is read upright, z out of
// the printed face (so a tag lying face-up on the floor has z up). From the four corners by
// OpenCV's IPPE for squares; then, where the depth image has readings on the tag, the
// translation is rescaled along the viewing ray so that the tag plane passes through the
// measured depth (monocular tag range error grows with distance; depth does not drift).
#include <optional>

#include <opencv2/core.hpp>

#include "core/camera.hpp"
#include "core/se3.hpp"
#include "markers/apriltag_detector.hpp"

namespace builtscene {

struct TagPose {
  int id = -1;
  SE3 T_cg;
  double reprojection_rms_px = 0;
  bool depth_refined = false;
  double distance = 0;           // metres, camera centre to tag centre
  double viewing_angle_deg = 0;  // between the tag's normal and the direction to the camera
};

// depth: CV_32F metres or empty. Returns nullopt when the corners give no valid pose.
std::optional<TagPose> estimate_tag_pose(const TagDetection& detection, double tag_size, const PinholeCamera& camera,
                                         const cv::Mat& depth = {});

// The tag's corners in the tag frame, in the detector's corner order.
std::array<Eigen::Vector3d, 4> tag_corners(double tag_size);

}  // namespace builtscene
