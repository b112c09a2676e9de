#pragma once
// Training data for SAFT without a patch data set: each image is warped by random
// homographies and photometric changes (brightness, contrast, blur, noise); ORB keypoints of
// the original and their mapped positions in the warped copy give matching patch pairs with
// exact ground truth. Blur is isotropic (defocus) or linear (camera motion during the
// exposure, as a handheld or robot camera sees it). Non-matching pairs combine patches of
// two different keypoints.
#include <cstdint>
#include <random>
#include <vector>

#include <opencv2/core.hpp>

#include "features/orb_extractor.hpp"

namespace builtscene {

struct SaftPairGeneratorOptions {
  int warps_per_image = 4;
  int keypoints_per_image = 300;
  // Homography ranges: log-scale change, in-plane rotation (degrees), perspective strength
  // (corner displacement as a fraction of the image size).
  double max_log_scale = 0.45;
  double max_rotation_deg = 30.0;
  double max_perspective = 0.12;
  // Half the warped copies are blurred; of those, this share with a linear motion kernel of
  // up to max_motion_blur_px pixels (the generated 20 ms exposure smears up to ~14 px) and
  // the rest with a Gaussian.
  double motion_blur_share = 0.5;
  double max_motion_blur_px = 14.0;
  std::uint64_t seed = 1;
};

// A pool of matching pairs: row i of `first` and row i of `second` (8-bit patches, see
// sample_saft_patches) show the same point; `source` and `position` identify the keypoint so
// that non-matching pairs never pair a point with itself or a close neighbour.
struct SaftPairPool {
  cv::Mat first, second;
  std::vector<int> source;               // image index
  std::vector<cv::Point2f> position;     // level-0 pixels in the original image
  int size() const { return first.rows; }
};

// Warps, perturbs and samples; deterministic for a seed.
SaftPairPool generate_saft_pairs(const std::vector<cv::Mat>& gray_images, const SaftPairGeneratorOptions& options);

// A random homography (centred on the image) and the warped, photometrically changed image.
struct WarpedImage {
  cv::Matx33d h;  // original -> warped pixels
  cv::Mat image;
};
WarpedImage random_warp(const cv::Mat& gray, const SaftPairGeneratorOptions& options, std::mt19937_64& rng);

// The image seen by a camera that moved `length_px` pixels along direction `angle_rad`
// (image x to the right, y down) during the exposure: the average of the image over that
// segment, centred on each pixel; borders reflected. Any depth; float images stay float.
cv::Mat linear_motion_blur(const cv::Mat& image, double length_px, double angle_rad);

// Index of a partner for row i that is a different keypoint (another image, or at least
// `min_distance` level-0 pixels away); drawn uniformly among the others.
int draw_non_matching(const SaftPairPool& pool, int i, std::mt19937_64& rng, float min_distance = 12.0f);

}  // namespace builtscene
