#pragma once
// What the SLAM needs from a feature extractor: keypoints on a scale pyramid, one descriptor
// row per keypoint, and the metric that compares the rows. Two implement it: OrbExtractor
// (binary rotated BRIEF, Hamming) and SaftExtractor (ORB's keypoints, the learned SAFT
// descriptor, L2 on unit vectors). `builtscene slam --descriptor orb|saft` picks one.
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "features/descriptor.hpp"

namespace builtscene {

struct ScalePyramid;
struct OrbExtractorOptions;

class FeatureExtractor {
 public:
  virtual ~FeatureExtractor() = default;
  // Grayscale 8-bit image in; keypoints in level-0 pixels (octave = pyramid level, angle in
  // degrees) and one descriptor row per keypoint.
  virtual void extract(const cv::Mat& gray, std::vector<cv::KeyPoint>& keypoints, cv::Mat& descriptors) = 0;
  virtual const ScalePyramid& pyramid() const = 0;
  virtual DescriptorMetric metric() const = 0;
};

enum class DescriptorChoice { kOrb, kSaft };
DescriptorChoice parse_descriptor_choice(const std::string& name);  // "orb" | "saft"; InputError otherwise
std::string to_string(DescriptorChoice choice);

// ORB, or SAFT with the weights in `saft_weights` (empty: the shipped ones).
std::unique_ptr<FeatureExtractor> make_feature_extractor(DescriptorChoice choice, const OrbExtractorOptions& orb,
                                                         const std::filesystem::path& saft_weights = {});

}  // namespace builtscene
