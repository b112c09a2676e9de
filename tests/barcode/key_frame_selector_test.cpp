#include "barcode/key_frame_selector.hpp"

#include <gtest/gtest.h>

namespace builtscene::barcode {
namespace {

TEST(KeyFrameSelector, HistogramDifferenceBounds) {
  const cv::Mat black(60, 80, CV_8UC3, cv::Scalar::all(0)), white(60, 80, CV_8UC3, cv::Scalar::all(255));
  const auto hb = KeyFrameSelector::histogram(black), hw = KeyFrameSelector::histogram(white);
  EXPECT_DOUBLE_EQ(KeyFrameSelector::difference(hb, hb), 0.0);
  EXPECT_NEAR(KeyFrameSelector::difference(hb, hw), 2.0, 1e-6);
  // Half black, half white: L1 distance 1 from either.
  cv::Mat half = black.clone();
  half(cv::Rect(0, 0, 40, 60)).setTo(cv::Scalar::all(255));
  EXPECT_NEAR(KeyFrameSelector::difference(hb, KeyFrameSelector::histogram(half, 1)), 1.0, 1e-6);
}

// Worked example of the source's four steps.
TEST(KeyFrameSelector, SelectsTheFrameBeforeEachLargeDifferencePerShot) {
  //                          0  1  2  3  4  5  6   7  8  9 10 11 12
  const std::vector<double> d{0, 1, 1, 1, 3, 1, 1, 50, 2, 2, 2, 6, 2};
  // Shot threshold 10 splits at frame 7. Shot 1 mean (frames 1..6) = 8/6; shot 2 mean (8..12) = 14/5.
  KeyFrameOptions o{1.0, 10.0};
  EXPECT_EQ(KeyFrameSelector::select(d, o), (std::vector<std::size_t>{3, 6, 10}));
  // k = 0.5: every difference above half the mean, i.e. all of shot 1 (> 0.67) and shot 2 (> 1.4).
  o.k = 0.5;
  EXPECT_EQ(KeyFrameSelector::select(d, o), (std::vector<std::size_t>{0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}));
}

TEST(KeyFrameSelector, AutomaticShotThresholdSplitsOnOutliersOnly) {
  std::vector<double> d(200, 1.0);
  for (std::size_t i = 0; i < d.size(); ++i) d[i] = 1.0 + 0.1 * static_cast<double>(i % 5);
  d[100] = 40.0;
  const double thr = KeyFrameSelector::auto_shot_threshold(d);
  EXPECT_GT(thr, 1.4);
  EXPECT_LT(thr, 40.0);
}

TEST(KeyFrameSelector, EmptyAndSingleFrame) {
  EXPECT_TRUE(KeyFrameSelector::select({}, {}).empty());
  EXPECT_EQ(KeyFrameSelector::select({0.0}, {}), (std::vector<std::size_t>{0}));
}

}  // namespace
}  // namespace builtscene::barcode
