#pragma once
// Where a keypoint lands under a known homography: position, and the pyramid level that
// best matches the local scale change, so a descriptor can be computed at the corresponding
// place in the second image (ground truth for patch pairs, training and evaluation).
#include <optional>

#include <opencv2/core.hpp>

namespace builtscene {

struct ScalePyramid;

// `h` (3x3, CV_64F) maps image-1 pixels to image-2 pixels. Returns the keypoint in image 2
// (pt, octave; angle left to the descriptor) or nothing when the point falls behind the
// camera, needs a level outside the pyramid, or lies closer than `border` pixels of its
// level to the edge of an image of `size2`.
std::optional<cv::KeyPoint> warp_keypoint(const cv::Matx33d& h, const cv::KeyPoint& kp, const ScalePyramid& pyramid,
                                          cv::Size size2, int border);

// Local scale of `h` at `pt`: sqrt(|det J|) of the Jacobian of the mapping.
double homography_local_scale(const cv::Matx33d& h, cv::Point2d pt);

}  // namespace builtscene
