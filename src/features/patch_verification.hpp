#pragma once
// Patch verification on image sequences with known homographies (HPatches layout: 1.png ...
// 6.png and H_1_k mapping image 1 to image k): ORB keypoints of image 1 and their mapped
// positions in image k give matching pairs; a keypoint of image 1 against the mapped
// position of another keypoint gives a non-matching pair. Each method describes both
// images itself (its own orientation at the mapped place), so the numbers include ORB's
// orientation error, as in the SLAM.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "features/saft_network.hpp"

namespace builtscene {

struct HomographySequence {
  std::string name;
  cv::Mat reference;                 // image 1, gray
  std::vector<cv::Mat> targets;      // images k = 2.., gray
  std::vector<cv::Matx33d> h;        // H_1_k
};

// Reads DIR/1.png and every DIR/k.png with DIR/H_1_k (k = 2, 3, ...); InputError naming the
// file for a missing or unreadable image or a malformed homography.
HomographySequence read_homography_sequence(const std::filesystem::path& dir);

struct PatchVerificationOptions {
  int keypoints = 1000;
  std::uint64_t seed = 1;
  float min_negative_distance = 12.0f;  // non-matching keypoints at least this far apart (pixels of image 1)
};

// Distances of matching and non-matching pairs for each method.
struct PatchVerificationDistances {
  std::vector<double> orb_pos, orb_neg;            // Hamming
  std::vector<double> saft_pos, saft_neg;          // L2 of unit descriptors
  std::vector<double> raw_pos, raw_neg;            // L2 of the descriptors before normalization
  void append(const PatchVerificationDistances& other);
};

PatchVerificationDistances verify_patches(const HomographySequence& sequence, SaftNetwork& network,
                                          const PatchVerificationOptions& options);

}  // namespace builtscene
