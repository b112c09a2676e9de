#include "features/saft_extractor.hpp"

#include "features/saft_patch.hpp"

namespace builtscene {

SaftExtractor::SaftExtractor(OrbExtractorOptions orb_options, SaftNetwork network)
    : orb_(orb_options), network_(std::move(network)) {}

void SaftExtractor::extract(const cv::Mat& gray, std::vector<cv::KeyPoint>& keypoints, cv::Mat& descriptors) {
  cv::Mat binary;
  orb_.extract(gray, keypoints, binary);
  if (keypoints.empty()) {
    descriptors = cv::Mat(0, SaftNetwork::kDimension, CV_32F);
    patches_ = cv::Mat(0, kSaftPatchPixels, CV_8U);
    return;
  }
  patches_ = sample_saft_patches(orb_.levels(), orb_.pyramid(), keypoints);
  network_.describe(normalize_saft_patches(patches_), descriptors);
}

DescriptorMetric SaftExtractor::saft_metric() {
  DescriptorMetric m = DescriptorMetric::float_l2(SaftNetwork::kDimension);
  // The distances that accept as many true matches as ORB's Hamming 50 / 100 on the
  // patch-verification pairs of `saft eval` (docs/saft.md, saft_threshold_same_tpr).
  m.strict = 0.77f;
  m.loose = 1.08f;
  return m;
}

}  // namespace builtscene
