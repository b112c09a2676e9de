#pragma once
// Frame-to-frame RGB-D odometry for the moments when features cannot hold the pose: a robot
// turning in front of a plain wall sees a handful of keypoints, but its depth image still shows
// the wall and the floor. Point-to-plane ICP with the motion prediction as a weak prior
// (icp_with_motion_prior.hpp) aligns the last frame with the current one, OpenCV's
// RgbdICPOdometry (contrib `rgbd` module) where too few pixels associate. It is used only as a
// bridge by the tracker (see tracking.cpp): the ORB pipeline stays primary.
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
  // from `guess` (OpenCV's RgbdICPOdometry; where it refuses a degenerate scene, such as one
  // plain wall, point-to-plane ICP with `guess` as a prior); nothing when the alignment fails, moves implausibly far for one frame, or
  // does not explain the current depth image (see depth_agreement): ICP always returns some
  // small motion, also between two unrelated views (a kidnapped camera), and a wrong pose
  // taken as a bridge would be built into the map. keep_guess_along_slide: where the depth
  // does not measure the motion along its direction (last_slide_measured), return the guess's
  // motion along it rather than ICP's (which the depth camera's disparity steps bias towards
  // no motion).
  // gray: CV_8U; depth: CV_32F metres (0 or NaN = none).
  std::optional<SE3> align(const cv::Mat& prev_gray, const cv::Mat& prev_depth, const cv::Mat& cur_gray,
                           const cv::Mat& cur_depth, const SE3& guess, bool keep_guess_along_slide = false) const;

  // Of the previous frame's depth points (every 4th pixel) that T_cur_prev moves into the
  // current image onto a pixel with a reading, the fraction whose depth agrees with that
  // reading (within 2 cm + 2 % of the depth); 0 when fewer than 1 % of the points can be
  // compared. A true alignment explains nearly all of them (occlusions and noise aside).
  double depth_agreement(const cv::Mat& prev_depth, const cv::Mat& cur_depth, const SE3& T_cur_prev) const;

  // Alignments whose depth_agreement is below this are refused.
  static constexpr double kMinDepthAgreement = 0.6;
  // So are prior-weighted alignments this far (metres) from the prediction (OpenCV's own
  // limit on its results is 0.15 m of motion).
  static constexpr double kMaxTranslationFromGuess = 0.15;

  // How many accepted alignments came from the prior-weighted ICP (the rest from OpenCV's).
  long prior_alignments() const { return prior_alignments_; }

  // Whether the last alignment measured the motion along its own direction (the depth holds
  // structure facing it), rather than keeping the prediction there (a plain corridor): only a
  // measured bridge frame's speed tells the tracker how fast the camera moves. See align().
  bool last_slide_measured() const { return last_slide_measured_; }
  // The probe: a second alignment from a prediction this much (metres) further along the
  // motion; the slide counts as measured when it moves the result by less than this fraction
  // of the probe. Not probed below kMinProbeSpeed (metres per frame; no direction to probe).
  static constexpr double kSlideProbe = 0.01;
  static constexpr double kSlideMeasuredFollow = 0.3;
  static constexpr double kMinProbeSpeed = 0.002;

 private:
  double fx_, fy_, cx_, cy_;
  cv::Ptr<cv::rgbd::RgbdICPOdometry> odometry_;
  mutable long prior_alignments_ = 0;
  mutable bool last_slide_measured_ = false;
};

}  // namespace builtscene::slam
