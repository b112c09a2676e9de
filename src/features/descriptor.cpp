#include "features/descriptor.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>

namespace builtscene {

DescriptorMetric DescriptorMetric::orb() { return {DescriptorKind::kBinary, 50.0f, 100.0f}; }

DescriptorMetric DescriptorMetric::float_l2(int /*dimension*/) {
  // For unit vectors the distance lies in [0, 2]; 1.0 corresponds to orthogonal vectors.
  return {DescriptorKind::kFloat, 0.7f, 1.0f};
}

DescriptorMetric DescriptorMetric::for_mat(const cv::Mat& descriptors) {
  if (descriptors.type() == CV_32F) return float_l2(descriptors.cols);
  return orb();
}

int hamming256(const std::uint8_t* a, const std::uint8_t* b) {
  std::uint64_t x[4], y[4];
  std::memcpy(x, a, 32);
  std::memcpy(y, b, 32);
  return std::popcount(x[0] ^ y[0]) + std::popcount(x[1] ^ y[1]) + std::popcount(x[2] ^ y[2]) +
         std::popcount(x[3] ^ y[3]);
}

int hamming(const std::uint8_t* a, const std::uint8_t* b, int bytes) {
  if (bytes == 32) return hamming256(a, b);
  int d = 0;
  for (int i = 0; i < bytes; ++i) d += std::popcount(static_cast<unsigned>(a[i] ^ b[i]));
  return d;
}

float l2_distance(const float* a, const float* b, int n) {
  float s = 0;
  for (int i = 0; i < n; ++i) {
    const float d = a[i] - b[i];
    s += d * d;
  }
  return std::sqrt(s);
}

float DescriptorMetric::distance(const cv::Mat& a, int i, const cv::Mat& b, int j) const {
  if (kind == DescriptorKind::kBinary) return static_cast<float>(hamming(a.ptr<std::uint8_t>(i), b.ptr<std::uint8_t>(j), a.cols));
  return l2_distance(a.ptr<float>(i), b.ptr<float>(j), a.cols);
}

int most_representative_descriptor(const std::vector<cv::Mat>& candidates, const DescriptorMetric& metric) {
  const int n = static_cast<int>(candidates.size());
  if (n == 0) return -1;
  if (n <= 2) return 0;
  std::vector<float> d(static_cast<std::size_t>(n * n), 0.0f);
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j) d[i * n + j] = d[j * n + i] = metric.distance(candidates[i], 0, candidates[j], 0);
  int best = 0;
  float best_median = metric.infinity();
  std::vector<float> row(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    std::copy(d.begin() + i * n, d.begin() + (i + 1) * n, row.begin());
    std::nth_element(row.begin(), row.begin() + (n - 1) / 2, row.end());
    if (row[(n - 1) / 2] < best_median) {
      best_median = row[(n - 1) / 2];
      best = i;
    }
  }
  return best;
}

std::vector<int> match_brute_force(const cv::Mat& query, const cv::Mat& train, const DescriptorMetric& metric,
                                   float threshold, float ratio) {
  std::vector<int> result(static_cast<std::size_t>(query.rows), -1);
  if (query.empty() || train.empty()) return result;
  for (int i = 0; i < query.rows; ++i) {
    float best = metric.infinity(), second = metric.infinity();
    int best_j = -1;
    for (int j = 0; j < train.rows; ++j) {
      const float dist = metric.distance(query, i, train, j);
      if (dist < best) {
        second = best;
        best = dist;
        best_j = j;
      } else if (dist < second) {
        second = dist;
      }
    }
    if (best_j >= 0 && best < threshold && best < ratio * second) result[static_cast<std::size_t>(i)] = best_j;
  }
  return result;
}

}  // namespace builtscene
