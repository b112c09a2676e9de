// FPR95 against closed-form answers: hand-countable integer distances and two Gaussians whose
// false positive rate at 95 % recall is Phi(z95 - d).
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "core/errors.hpp"
#include "features/descriptor_roc.hpp"

namespace builtscene {
namespace {

std::vector<double> range(int from, int to) {
  std::vector<double> v;
  for (int i = from; i <= to; ++i) v.push_back(i);
  return v;
}

TEST(DescriptorRoc, CountedCases) {
  // Positives 1..100: 95 % are accepted at threshold 95. Negatives 51..150: 45 of them <= 95.
  const RocPoint r = fpr_at_tpr(range(1, 100), range(51, 150));
  EXPECT_DOUBLE_EQ(r.threshold, 95.0);
  EXPECT_DOUBLE_EQ(r.tpr, 0.95);
  EXPECT_DOUBLE_EQ(r.fpr, 0.45);
  // Perfectly separable; identical distributions.
  EXPECT_DOUBLE_EQ(fpr_at_tpr(range(1, 100), range(101, 200)).fpr, 0.0);
  EXPECT_DOUBLE_EQ(fpr_at_tpr(range(1, 100), range(1, 100)).fpr, 0.95);
  // Order of the inputs does not matter.
  std::vector<double> shuffled = range(1, 100);
  std::shuffle(shuffled.begin(), shuffled.end(), std::mt19937(3));
  EXPECT_DOUBLE_EQ(fpr_at_tpr(shuffled, range(51, 150)).fpr, 0.45);
}

TEST(DescriptorRoc, TiesAtTheThresholdCountForBoth) {
  // All distances equal: everything is accepted.
  const RocPoint r = fpr_at_tpr(std::vector<double>(10, 2.0), std::vector<double>(10, 2.0));
  EXPECT_DOUBLE_EQ(r.tpr, 1.0);
  EXPECT_DOUBLE_EQ(r.fpr, 1.0);
}

TEST(DescriptorRoc, GaussianDistancesMatchTheNormalCdf) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> pos(0.0, 1.0), neg(2.0, 1.0);
  std::vector<double> p, n;
  for (int i = 0; i < 200000; ++i) {
    p.push_back(pos(rng));
    n.push_back(neg(rng));
  }
  // Threshold z95 = 1.6449; FPR = Phi(1.6449 - 2) = 0.3612.
  const double expected = 0.5 * std::erfc(-(1.6448536 - 2.0) / std::sqrt(2.0));
  EXPECT_NEAR(fpr_at_tpr(p, n).fpr, expected, 0.005);
  const auto curve = roc_curve(p, n, 20);
  ASSERT_EQ(curve.size(), 20u);
  for (std::size_t i = 1; i < curve.size(); ++i) EXPECT_GE(curve[i].fpr, curve[i - 1].fpr);
  EXPECT_NEAR(curve.back().tpr, 1.0, 1e-12);
}

TEST(DescriptorRoc, RejectsEmptyInput) {
  EXPECT_THROW(fpr_at_tpr({}, {1.0}), InputError);
  EXPECT_THROW(fpr_at_tpr({1.0}, {}), InputError);
  EXPECT_THROW(fpr_at_tpr({1.0}, {1.0}, 0.0), InputError);
}

}  // namespace
}  // namespace builtscene
