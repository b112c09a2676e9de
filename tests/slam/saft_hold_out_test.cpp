// The hand-over check's held-out split (slam::hold_out_pairs): a batch laid out as make_pairs()
// writes it (positive pair of point k in row 2k, a negative pair of the same point in row
// 2k + 1) splits into a quarter held out and three quarters to train on, both balanced, every
// row in exactly one part and unchanged.
#include <gtest/gtest.h>

#include "features/saft_patch.hpp"
#include "slam/saft_learning.hpp"

namespace builtscene::slam {
namespace {

TEST(SaftHoldOut, AQuarterOfTheCouplesIsHeldOutAndBothPartsAreBalanced) {
  constexpr int kPoints = 64;  // 128 rows
  SaftLabelledPairs batch;
  batch.first.create(2 * kPoints, kSaftPatchPixels, CV_8U);
  batch.second.create(2 * kPoints, kSaftPatchPixels, CV_8U);
  for (int r = 0; r < 2 * kPoints; ++r) {
    batch.first.row(r).setTo(r);         // the row's number, to find it again
    batch.second.row(r).setTo(255 - r);
    batch.label.push_back(r % 2 == 0 ? +1 : -1);
  }
  const auto [train, held] = hold_out_pairs(batch, 4);
  ASSERT_EQ(held.size(), 2 * kPoints / 4);
  ASSERT_EQ(train.size(), 2 * kPoints - held.size());
  const auto positives = [](const SaftLabelledPairs& p) {
    int n = 0;
    for (int l : p.label) n += l > 0;
    return n;
  };
  EXPECT_EQ(2 * positives(held), held.size());
  EXPECT_EQ(2 * positives(train), train.size());
  std::vector<int> seen(2 * kPoints, 0);
  for (const auto* part : {&train, &held})
    for (int i = 0; i < part->size(); ++i) {
      const int r = part->first.at<std::uint8_t>(i, 0);
      ++seen[static_cast<std::size_t>(r)];
      EXPECT_EQ(part->second.at<std::uint8_t>(i, kSaftPatchPixels - 1), 255 - r);
      EXPECT_EQ(part->label[static_cast<std::size_t>(i)], r % 2 == 0 ? +1 : -1);
    }
  for (int r = 0; r < 2 * kPoints; ++r) EXPECT_EQ(seen[static_cast<std::size_t>(r)], 1) << "row " << r;
  // A point's positive and negative pair stay together.
  for (int i = 0; i + 1 < held.size(); i += 2)
    EXPECT_EQ(held.first.at<std::uint8_t>(i + 1, 0), held.first.at<std::uint8_t>(i, 0) + 1);
}

}  // namespace
}  // namespace builtscene::slam
