#pragma once
// Patches for the SAFT network: 32 x 32 pixels around a keypoint, sampled on the pyramid
// level the keypoint was found on and rotated to its orientation, so the descriptor inherits
// ORB's scale and rotation invariance instead of having to learn it.
#include <vector>

#include <opencv2/core.hpp>

#include "features/orb_extractor.hpp"

namespace builtscene {

constexpr int kSaftPatchSize = 32;
constexpr int kSaftPatchPixels = kSaftPatchSize * kSaftPatchSize;

// One 8-bit row of kSaftPatchPixels per keypoint. `levels` is the image pyramid the
// keypoints refer to (level 0 = the image), made with `pyramid`, which maps level-0 pixels to
// level l; keypoints carry pt (level-0 pixels), octave and angle (degrees) as OrbExtractor
// sets them. Pixels outside the level replicate its border.
cv::Mat sample_saft_patches(const std::vector<cv::Mat>& levels, const ScalePyramid& pyramid,
                            const std::vector<cv::KeyPoint>& keypoints);

// The network's input: each row converted to float with zero mean and unit standard
// deviation (a flat patch stays all zero), which removes brightness and contrast changes.
cv::Mat normalize_saft_patches(const cv::Mat& patches8u);

}  // namespace builtscene
