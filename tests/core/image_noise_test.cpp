// The noise estimate against images with noise of a known sigma added: a smooth ramp (the
// mask must cancel it) and a scene with strong edges over a fifth of its pixels (the median
// must ignore them).
#include <cmath>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "core/image_noise.hpp"

namespace builtscene {
namespace {

cv::Mat ramp(int w, int h) {
  cv::Mat img(h, w, CV_32F);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img.at<float>(y, x) = 60.0f + 0.15f * static_cast<float>(x) + 0.1f * static_cast<float>(y);
  return img;
}

cv::Mat with_noise(const cv::Mat& clean, double sigma, std::uint64_t seed) {
  cv::Mat noise(clean.size(), CV_32F);
  cv::RNG rng(seed);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, sigma);
  cv::Mat out;
  cv::Mat(clean + noise).convertTo(out, CV_8U);  // rounds and saturates, as a camera does
  return out;
}

class ImageNoiseOfKnownSigma : public ::testing::TestWithParam<double> {};

TEST_P(ImageNoiseOfKnownSigma, RampIsCancelledAndSigmaRecovered) {
  const double sigma = GetParam();
  const double est = estimate_image_noise_sigma(with_noise(ramp(640, 480), sigma, 11));
  // Rounding to whole grey levels adds variance 1/12.
  const double expected = std::sqrt(sigma * sigma + 1.0 / 12.0);
  EXPECT_NEAR(est, expected, 0.08 * expected + 0.1) << "sigma " << sigma;
}

TEST_P(ImageNoiseOfKnownSigma, EdgesOnAFifthOfThePixelsDoNotRaiseIt) {
  const double sigma = GetParam();
  cv::Mat scene = ramp(640, 480);
  // Bars 4 px wide every 20 px, 80 grey levels of contrast: a fifth of the pixels sit on or
  // next to an edge, whose mask response is hundreds of grey levels.
  for (int x = 0; x < scene.cols; x += 20) cv::rectangle(scene, cv::Rect(x, 0, 4, scene.rows), cv::Scalar(200), cv::FILLED);
  const double est = estimate_image_noise_sigma(with_noise(scene, sigma, 12));
  const double expected = std::sqrt(sigma * sigma + 1.0 / 12.0);
  EXPECT_NEAR(est, expected, 0.2 * expected + 0.15) << "sigma " << sigma;
}

INSTANTIATE_TEST_SUITE_P(Sigmas, ImageNoiseOfKnownSigma, ::testing::Values(0.7, 1.5, 2.5, 5.0));

TEST(ImageNoise, NoiselessAndTinyImages) {
  cv::Mat clean;
  ramp(320, 240).convertTo(clean, CV_8U);
  EXPECT_LT(estimate_image_noise_sigma(clean), 0.3);
  EXPECT_EQ(estimate_image_noise_sigma(cv::Mat(2, 2, CV_8UC1, cv::Scalar(5))), 0.0);
  EXPECT_LT(estimate_image_noise_sigma(cv::Mat(100, 100, CV_8UC1, cv::Scalar(5))), 0.2);
}

}  // namespace
}  // namespace builtscene
