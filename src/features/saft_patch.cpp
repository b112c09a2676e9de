#include "features/saft_patch.hpp"

#include <cmath>

#include <opencv2/imgproc.hpp>

namespace builtscene {

cv::Mat sample_saft_patches(const std::vector<cv::Mat>& levels, const ScalePyramid& pyramid,
                            const std::vector<cv::KeyPoint>& keypoints) {
  cv::Mat out(static_cast<int>(keypoints.size()), kSaftPatchPixels, CV_8UC1);
  constexpr double half = 0.5 * (kSaftPatchSize - 1);
  for (std::size_t i = 0; i < keypoints.size(); ++i) {
    const cv::KeyPoint& k = keypoints[i];
    CV_Assert(k.octave >= 0 && static_cast<std::size_t>(k.octave) < levels.size());
    const auto l = static_cast<std::size_t>(k.octave);
    const cv::Point2f at_level = pyramid.to_level(k.pt, k.octave, levels[0].size());
    const double cx = at_level.x, cy = at_level.y;
    const double a = k.angle * CV_PI / 180.0, c = std::cos(a), s = std::sin(a);
    // Patch pixel (u, v) reads the level at centre + R(angle) * (u - half, v - half): the
    // same rotation ORB applies to its BRIEF pattern.
    const cv::Matx23d to_level(c, -s, cx - c * half + s * half, s, c, cy - s * half - c * half);
    cv::Mat patch(kSaftPatchSize, kSaftPatchSize, CV_8UC1, out.ptr<std::uint8_t>(static_cast<int>(i)));
    cv::warpAffine(levels[l], patch, to_level, patch.size(), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                   cv::BORDER_REPLICATE);
  }
  return out;
}

cv::Mat normalize_saft_patches(const cv::Mat& patches8u) {
  CV_Assert(patches8u.type() == CV_8UC1 && patches8u.cols == kSaftPatchPixels);
  cv::Mat out;
  patches8u.convertTo(out, CV_32F);
  for (int r = 0; r < out.rows; ++r) {
    float* p = out.ptr<float>(r);
    double sum = 0.0, sum2 = 0.0;
    for (int i = 0; i < kSaftPatchPixels; ++i) {
      sum += p[i];
      sum2 += static_cast<double>(p[i]) * p[i];
    }
    const double mean = sum / kSaftPatchPixels;
    const double var = std::max(0.0, sum2 / kSaftPatchPixels - mean * mean);
    // The floor keeps a nearly flat patch from amplifying its sensor noise to unit variance.
    const double inv = 1.0 / std::max(std::sqrt(var), 2.0);
    for (int i = 0; i < kSaftPatchPixels; ++i) p[i] = static_cast<float>((p[i] - mean) * inv);
  }
  return out;
}

}  // namespace builtscene
