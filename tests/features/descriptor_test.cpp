#include <gtest/gtest.h>

#include "features/descriptor.hpp"

namespace builtscene {
namespace {

TEST(Descriptor, HammingAgreesWithOpenCv) {
  cv::RNG rng(5);
  cv::Mat a(10, 32, CV_8UC1), b(10, 32, CV_8UC1);
  rng.fill(a, cv::RNG::UNIFORM, 0, 256);
  rng.fill(b, cv::RNG::UNIFORM, 0, 256);
  const auto m = DescriptorMetric::orb();
  for (int i = 0; i < 10; ++i)
    EXPECT_EQ(m.distance(a, i, b, i), cv::norm(a.row(i), b.row(i), cv::NORM_HAMMING));
}

TEST(Descriptor, FloatL2AgreesWithOpenCv) {
  cv::RNG rng(6);
  cv::Mat a(4, 64, CV_32F), b(4, 64, CV_32F);
  rng.fill(a, cv::RNG::NORMAL, 0, 1);
  rng.fill(b, cv::RNG::NORMAL, 0, 1);
  const auto m = DescriptorMetric::for_mat(a);
  EXPECT_EQ(m.kind, DescriptorKind::kFloat);
  for (int i = 0; i < 4; ++i) EXPECT_NEAR(m.distance(a, i, b, i), cv::norm(a.row(i), b.row(i), cv::NORM_L2), 1e-4);
}

TEST(Descriptor, RepresentativeIsTheMedoid) {
  // Four close descriptors and one far: the representative is the one with the least median
  // distance to the others (worked out by hand: medians 0.15, 0.1, 0.15, 0.2, 4.85).
  std::vector<cv::Mat> d;
  for (float v : {0.0f, 0.1f, 0.15f, 0.3f, 5.0f}) d.push_back(cv::Mat(1, 2, CV_32F, cv::Scalar(v)));
  EXPECT_EQ(most_representative_descriptor(d, DescriptorMetric::float_l2(2)), 1);
  EXPECT_EQ(most_representative_descriptor({}, DescriptorMetric::orb()), -1);
}

TEST(Descriptor, BruteForceRatioTest) {
  cv::Mat q = (cv::Mat_<float>(2, 1) << 0.0f, 10.0f);
  cv::Mat t = (cv::Mat_<float>(3, 1) << 0.05f, 9.0f, 9.1f);
  const auto r = match_brute_force(q, t, DescriptorMetric::float_l2(1), 2.0f, 0.8f);
  EXPECT_EQ(r[0], 0);
  EXPECT_EQ(r[1], -1);  // ambiguous: 0.9 vs 1.0
}

}  // namespace
}  // namespace builtscene
