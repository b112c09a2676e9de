// The temporal consistency rule of loop detection on constructed candidate sequences.
#include <gtest/gtest.h>

#include "slam/loop_consistency.hpp"

namespace builtscene::slam {
namespace {

using C = LoopConsistency::Candidate;

TEST(LoopConsistency, SamePlaceOnFourConsecutiveKeyframesIsAcceptedOnTheFourth) {
  LoopConsistency lc(3);
  EXPECT_TRUE(lc.update({C{5, {4, 6}}}).empty());
  EXPECT_TRUE(lc.update({C{6, {5, 7}}}).empty());
  EXPECT_TRUE(lc.update({C{5, {4, 6}}}).empty());
  EXPECT_EQ(lc.update({C{7, {6, 8}}}), std::vector<long>{7});
  // The chain goes on being consistent.
  EXPECT_EQ(lc.update({C{8, {7, 9}}}), std::vector<long>{8});
}

TEST(LoopConsistency, AGapOrAnotherPlaceBreaksTheChain) {
  LoopConsistency lc(3);
  lc.update({C{5, {4, 6}}});
  lc.update({C{5, {4, 6}}});
  lc.update({C{5, {4, 6}}});
  EXPECT_TRUE(lc.update({}).empty());  // no candidate at this keyframe
  EXPECT_TRUE(lc.update({C{5, {4, 6}}}).empty());
  lc.reset();
  // Disjoint places every time are never accepted.
  for (long k = 0; k < 10; ++k) EXPECT_TRUE(lc.update({C{100 + 10 * k, {101 + 10 * k}}}).empty());
}

TEST(LoopConsistency, OnlyTheConsistentOfSeveralCandidatesIsAccepted) {
  LoopConsistency lc(3);
  for (long k = 0; k < 3; ++k) lc.update({C{20, {21}}, C{200 + k, {}}});
  const auto accepted = lc.update({C{300, {}}, C{21, {22}}});
  EXPECT_EQ(accepted, std::vector<long>{21});
}

TEST(LoopConsistency, OneChainDoesNotMultiply) {
  // Two candidates of the next keyframe both touching one previous group: both are
  // consistent with it, but only the first carries it on, so one group remains.
  LoopConsistency lc(1);
  lc.update({C{1, {2}}});
  EXPECT_EQ(lc.update({C{2, {}}, C{1, {}}}), (std::vector<long>{2, 1}));
  ASSERT_EQ(lc.groups().size(), 1u);
  EXPECT_EQ(lc.groups()[0].consistency, 1);
}

}  // namespace
}  // namespace builtscene::slam
