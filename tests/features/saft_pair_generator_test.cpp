// The augmentations SAFT's offline training draws its pairs with, checked against closed forms.
#include <cmath>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "features/saft_pair_generator.hpp"

namespace builtscene {
namespace {

struct Moments {
  double sum = 0, cx = 0, cy = 0, along = 0, across = 0;
};

// Mass, centroid and the second moments along and across direction `angle`.
Moments moments(const cv::Mat& f, double angle) {
  Moments m;
  for (int y = 0; y < f.rows; ++y)
    for (int x = 0; x < f.cols; ++x) {
      const double w = f.at<float>(y, x);
      m.sum += w;
      m.cx += w * x;
      m.cy += w * y;
    }
  m.cx /= m.sum;
  m.cy /= m.sum;
  const double c = std::cos(angle), s = std::sin(angle);
  for (int y = 0; y < f.rows; ++y)
    for (int x = 0; x < f.cols; ++x) {
      const double w = f.at<float>(y, x) / m.sum;
      const double dx = x - m.cx, dy = y - m.cy;
      m.along += w * std::pow(dx * c + dy * s, 2);
      m.across += w * std::pow(-dx * s + dy * c, 2);
    }
  return m;
}

TEST(LinearMotionBlur, APointBecomesASegmentOfTheGivenLengthAndDirection) {
  for (const double length : {3.0, 8.5, 14.0})
    for (const double angle : {0.0, 0.52, 1.5708, 2.4}) {
      cv::Mat f = cv::Mat::zeros(61, 61, CV_32F);
      f.at<float>(30, 30) = 1.0f;
      const Moments m = moments(linear_motion_blur(f, length, angle), angle);
      SCOPED_TRACE(::testing::Message() << "length " << length << " angle " << angle);
      EXPECT_NEAR(m.sum, 1.0, 1e-4);  // brightness is conserved
      EXPECT_NEAR(m.cx, 30.0, 0.02);
      EXPECT_NEAR(m.cy, 30.0, 0.02);
      // A uniform segment of length L has variance L^2 / 12 along it; bilinear splatting adds
      // at most 1/4 pixel^2 in either direction.
      EXPECT_GE(m.along, length * length / 12.0 - 0.01);
      EXPECT_LE(m.along, length * length / 12.0 + 0.25);
      EXPECT_LE(m.across, 0.25);
    }
}

TEST(LinearMotionBlur, ImagesConstantAlongTheMotionAndLinearRampsAreUnchanged) {
  cv::Mat rows(40, 50, CV_32F), ramp(40, 50, CV_32F);
  for (int y = 0; y < rows.rows; ++y)
    for (int x = 0; x < rows.cols; ++x) {
      rows.at<float>(y, x) = static_cast<float>((y * 37) % 11) * 20.0f;  // varies across rows only
      ramp.at<float>(y, x) = 3.0f * static_cast<float>(x) + 2.0f * static_cast<float>(y);
    }
  // Horizontal motion over a picture that only changes from row to row changes nothing.
  EXPECT_LT(cv::norm(linear_motion_blur(rows, 9.0, 0.0), rows, cv::NORM_INF), 1e-3);
  // A symmetric average of a linear function is its value at the centre (away from borders).
  const cv::Mat blurred = linear_motion_blur(ramp, 10.0, 0.7);
  const cv::Rect inner(8, 8, ramp.cols - 16, ramp.rows - 16);
  EXPECT_LT(cv::norm(blurred(inner), ramp(inner), cv::NORM_INF), 1e-3);
  // Blur along a direction with no change is exact, blur across it is not.
  EXPECT_GT(cv::norm(linear_motion_blur(rows, 9.0, CV_PI / 2), rows, cv::NORM_INF), 10.0);
}

TEST(LinearMotionBlur, NoLengthLeavesTheImageAlone) {
  cv::Mat f(10, 10, CV_8U);
  cv::randu(f, 0, 255);
  EXPECT_EQ(cv::norm(linear_motion_blur(f, 0.5, 1.0), f, cv::NORM_INF), 0.0);
}

}  // namespace
}  // namespace builtscene
