// The fixed-point smoothing against the second tool it replaces: cv::GaussianBlur with the
// same kernel size, sigma and border must give the same bytes.
#include <gtest/gtest.h>

#include <filesystem>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "features/brief_smoothing.hpp"

namespace builtscene {
namespace {

cv::Mat opencv_smoothing(const cv::Mat& src) {
  cv::Mat dst;
  cv::GaussianBlur(src, dst, cv::Size(7, 7), 2, 2, cv::BORDER_REFLECT_101);
  return dst;
}

void expect_same_as_opencv(const cv::Mat& src, const std::string& what) {
  cv::Mat ours;
  std::vector<std::uint16_t> scratch;
  smooth_for_brief(src, ours, scratch);
  const cv::Mat ref = opencv_smoothing(src);
  ASSERT_EQ(ours.size(), ref.size()) << what;
  ASSERT_EQ(ours.type(), CV_8UC1) << what;
  EXPECT_EQ(cv::norm(ours, ref, cv::NORM_INF), 0.0) << what << ": " << cv::countNonZero(ours != ref) << " pixels differ";
}

TEST(BriefSmoothing, KernelIsAGaussianOfSigma2SummingTo256) {
  const auto k = brief_smoothing_kernel();
  int sum = 0;
  for (auto v : k) sum += v;
  EXPECT_EQ(sum, 256);
  const cv::Mat g = cv::getGaussianKernel(7, 2, CV_64F);
  for (int i = 0; i < 7; ++i) {
    EXPECT_EQ(k[static_cast<std::size_t>(i)], k[static_cast<std::size_t>(6 - i)]);
    EXPECT_NEAR(k[static_cast<std::size_t>(i)] / 256.0, g.at<double>(i), 1.0 / 256.0) << i;
  }
}

TEST(BriefSmoothing, EqualsOpenCvGaussianBlurOnNoiseOfManySizes) {
  cv::RNG rng(7);
  // Odd widths exercise the vector loops' tails; 4 x 4 is the smallest mirrored case.
  for (const cv::Size size : {cv::Size(640, 480), cv::Size(533, 400), cv::Size(37, 33), cv::Size(4, 4), cv::Size(5, 97),
                              cv::Size(101, 6), cv::Size(1000, 3)}) {
    cv::Mat img(size, CV_8UC1);
    rng.fill(img, cv::RNG::UNIFORM, 0, 256);
    expect_same_as_opencv(img, std::to_string(size.width) + "x" + std::to_string(size.height));
  }
}

TEST(BriefSmoothing, EqualsOpenCvGaussianBlurOnExtremesAndRegions) {
  // Saturated values (the largest 16- and 32-bit sums), steps, and a region cut from a
  // larger image.
  cv::Mat white(48, 64, CV_8UC1, cv::Scalar(255));
  expect_same_as_opencv(white, "white");
  cv::Mat steps(48, 64, CV_8UC1, cv::Scalar(0));
  steps(cv::Rect(10, 0, 20, 48)) = 255;
  steps(cv::Rect(0, 30, 64, 3)) = 128;
  expect_same_as_opencv(steps, "steps");
  cv::Mat big(100, 120, CV_8UC1);
  cv::RNG(3).fill(big, cv::RNG::UNIFORM, 0, 256);
  expect_same_as_opencv(big(cv::Rect(20, 10, 60, 50)).clone(), "region");
}

TEST(BriefSmoothing, EqualsOpenCvGaussianBlurOnARealPhotograph) {
  const auto file = std::filesystem::path(BUILTSCENE_SOURCE_DIR) / "../shared/data/7scenes-kitchen/rgb/1010.000000.jpg";
  cv::Mat img;
  if (std::filesystem::exists(file)) img = cv::imread(file.string(), cv::IMREAD_GRAYSCALE);
  if (img.empty()) {
    // Without the shared data: a smooth synthetic scene instead of noise.
    img.create(480, 640, CV_8UC1);
    cv::RNG(11).fill(img, cv::RNG::UNIFORM, 0, 256);
    cv::GaussianBlur(img, img, cv::Size(15, 15), 4);
  }
  expect_same_as_opencv(img, "photograph");
}

}  // namespace
}  // namespace builtscene
