#pragma once
// SAFT features for the SLAM: ORB's keypoints (pyramid, FAST, quadtree spread, orientation)
// with the learned descriptor in place of rotated BRIEF: a CV_32F matrix, one unit-length
// row of SaftNetwork::kDimension floats per keypoint, compared by L2 (metric()).
// The 8-bit patches of the last frame stay available (last_patches()): online learning
// builds its training pairs from them.
#include <filesystem>
#include <vector>

#include <opencv2/core.hpp>

#include "features/descriptor.hpp"
#include "features/feature_extractor.hpp"
#include "features/orb_extractor.hpp"
#include "features/saft_network.hpp"

namespace builtscene {

class SaftExtractor : public FeatureExtractor {
 public:
  SaftExtractor(OrbExtractorOptions orb_options, SaftNetwork network);

  // Same keypoints as OrbExtractor::extract on the same image; descriptors N x kDimension.
  void extract(const cv::Mat& gray, std::vector<cv::KeyPoint>& keypoints, cv::Mat& descriptors) override;
  const ScalePyramid& pyramid() const override { return orb_.pyramid(); }
  DescriptorMetric metric() const override { return saft_metric(); }

  // L2 on unit vectors; `strict` and `loose` accept the same fraction of true matches as
  // ORB's Hamming 50 and 100 do on the `saft eval` pairs (docs/saft.md).
  static DescriptorMetric saft_metric();

  // Row i: the 8-bit patch (sample_saft_patches) keypoint i of the last extract() was
  // described from.
  const cv::Mat& last_patches() const { return patches_; }

  OrbExtractor& orb() { return orb_; }
  SaftNetwork& network() { return network_; }

 private:
  OrbExtractor orb_;
  SaftNetwork network_;
  cv::Mat patches_;
};

}  // namespace builtscene
