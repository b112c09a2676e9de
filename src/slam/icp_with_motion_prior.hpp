#pragma once
// Point-to-plane ICP between two depth images that also weighs the constant-velocity
// prediction, for scenes whose geometry does not fix all six degrees of freedom.
//
// A robot turning in front of a plain end wall sees one plane (and a sliver of floor): depth
// fixes the distance to the wall and two rotations, but not the sliding along it nor the turn
// about its normal. OpenCV's RgbdICPOdometry refuses such a system outright (its normal
// matrix is singular), so tracking was lost for a second at every corridor end. Here the
// prediction enters as a weak Gaussian prior: where the depth constrains a direction the
// thousands of point-to-plane residuals outweigh it; where it does not, the prediction is
// kept. This is what a filter fusing odometry with a motion model does; the caller still
// checks that the result explains the current depth image.
#include <optional>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "core/se3.hpp"

namespace builtscene::slam {

struct IcpWithPriorOptions {
  double min_depth = 0.4, max_depth = 4.0;  // metres; readings outside are not used
  int stride = 4;                           // every stride-th pixel of the previous image
  int iterations = 15;
  double max_gap_m = 0.1;                   // association gate along the ray
  double huber_m = 0.01;                    // point-to-plane residuals beyond this are down-weighted
  double sigma_m = 0.01;                    // point-to-plane noise
  double prior_sigma_rad = 0.005;           // prediction error per frame (~0.3 degrees)
  double prior_sigma_m = 0.01;
  int min_correspondences = 300;
};

// T_cur_prev (previous-frame points into the current frame) starting from and pulled towards
// `prediction`; nothing when too few pixels can be associated or the solve breaks down.
// Depth images: CV_32F metres, 0 or NaN = no reading; pinhole intrinsics without distortion.
std::optional<SE3> icp_with_motion_prior(const cv::Mat& prev_depth, const cv::Mat& cur_depth, double fx, double fy,
                                         double cx, double cy, const SE3& prediction,
                                         const IcpWithPriorOptions& options = {},
                                         Eigen::Matrix<double, 6, 6>* correspondence_information = nullptr);

}  // namespace builtscene::slam
