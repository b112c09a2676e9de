// The generator's own PNG encoder writes files that OpenCV (libpng) decodes to the same pixels.
#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include "synth/png_writer.hpp"

namespace synth = builtscene::synth;

TEST(RgbdPng, RoundTripsThroughLibpng) {
  cv::RNG rng(3);
  cv::Mat bgr(37, 53, CV_8UC3), gray(20, 31, CV_8U), d16(48, 64, CV_16U);
  rng.fill(bgr, cv::RNG::UNIFORM, 0, 256);
  rng.fill(gray, cv::RNG::UNIFORM, 0, 256);
  rng.fill(d16, cv::RNG::UNIFORM, 0, 65536);
  d16(cv::Rect(0, 0, 20, 10)).setTo(0);  // runs
  for (const cv::Mat& m : {bgr, gray, d16}) {
    const std::string png = synth::encode_png_fast(m);
    const cv::Mat back = cv::imdecode(cv::Mat(1, static_cast<int>(png.size()), CV_8U, const_cast<char*>(png.data())), cv::IMREAD_UNCHANGED);
    ASSERT_EQ(back.type(), m.type());
    ASSERT_EQ(back.size(), m.size());
    EXPECT_EQ(cv::norm(back, m, cv::NORM_INF), 0.0);
  }
}
