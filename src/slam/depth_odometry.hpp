#pragma once
// Frame-to-frame RGB-D odometry for the moments when features cannot hold the pose: a robot
// turning in front of a plain wall sees a handful of keypoints, but its depth image still shows
// the wall and the floor. OpenCV's RgbdICPOdometry (contrib `rgbd` module: point-to-plane ICP
// plus a photometric term, coarse to fine) aligns the last frame with the current one. It is
// used only as a bridge by the tracker (see tracking.cpp): the ORB pipeline stays primary.
#include <optional>

#include <opencv2/core.hpp>

#include "core/se3.hpp"

namespace cv::rgbd {
class RgbdICPOdometry;
}

namespace builtscene::slam {

class DepthOdometry {
 public:
  DepthOdometry(double fx, double fy, double cx, double cy);
  ~DepthOdometry();
  DepthOdometry(const DepthOdometry&) = delete;
  DepthOdometry& operator=(const DepthOdometry&) = delete;

  // T_cur_prev (a point in the previous camera frame, expressed in the current one), starting
  // from `guess`; nothing when the alignment fails or moves implausibly far for one frame.
  // gray: CV_8U; depth: CV_32F metres (0 or NaN = none).
  std::optional<SE3> align(const cv::Mat& prev_gray, const cv::Mat& prev_depth, const cv::Mat& cur_gray,
                           const cv::Mat& cur_depth, const SE3& guess) const;

 private:
  cv::Ptr<cv::rgbd::RgbdICPOdometry> odometry_;
};

}  // namespace builtscene::slam
