#pragma once
// Descriptor handling shared by every matcher: a descriptor set is a cv::Mat with one row per
// keypoint, either binary (CV_8U, compared by Hamming distance; ORB's 32 bytes) or float
// (CV_32F, compared by Euclidean distance; a learned descriptor such as SAFT, L2-normalized).
// Matching code never looks at the element type itself: it asks DescriptorMetric for the
// distance and for thresholds expressed in that metric, so a float descriptor plugs in
// without touching tracking or mapping.
#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

namespace builtscene {

enum class DescriptorKind { kBinary, kFloat };

// Distances and match thresholds of one descriptor kind. `strict` is ORB-SLAM's TH_LOW (used
// where a wrong match is expensive, e.g. fusing map points), `loose` its TH_HIGH.
struct DescriptorMetric {
  DescriptorKind kind = DescriptorKind::kBinary;
  float strict = 50.0f;
  float loose = 100.0f;

  static DescriptorMetric orb();                    // Hamming on 256 bits: 50 / 100
  static DescriptorMetric float_l2(int dimension);  // unit vectors: 0.7 / 1.0 (defaults, tunable)
  static DescriptorMetric for_mat(const cv::Mat& descriptors);

  // Distance between row i of a and row j of b (same kind and width).
  float distance(const cv::Mat& a, int i, const cv::Mat& b, int j) const;
  // A value larger than any real distance.
  float infinity() const { return 1e30f; }
};

// Hamming distance of two 32-byte rows (the hot loop: 4 x 64-bit popcounts).
int hamming256(const std::uint8_t* a, const std::uint8_t* b);
int hamming(const std::uint8_t* a, const std::uint8_t* b, int bytes);
float l2_distance(const float* a, const float* b, int n);

// The descriptor among `candidates` (rows, all of one kind) with the least median distance
// to the others: ORB-SLAM's choice of a map point's representative descriptor. Returns the
// row index, or -1 for an empty set.
int most_representative_descriptor(const std::vector<cv::Mat>& candidates, const DescriptorMetric& metric);

// Brute-force nearest neighbour of each row of `query` among the rows of `train`, accepted
// when best < threshold and best < ratio * second best (Lowe's test). Returns, per query row,
// the train row or -1.
std::vector<int> match_brute_force(const cv::Mat& query, const cv::Mat& train, const DescriptorMetric& metric,
                                   float threshold, float ratio);

}  // namespace builtscene
