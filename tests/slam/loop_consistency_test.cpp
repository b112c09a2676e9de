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

TEST(LoopConsistency, ThePlaceRecognisedOnOneKeyframeTooFewIsOneShort) {
  // What a run's end leaves (LoopCloser::close_at_end): the place seen on three consecutive
  // keyframes of four needed is one short; a fresh or a broken chain is not, and an accepted
  // candidate is not listed again.
  LoopConsistency lc(3);
  lc.update({C{5, {4, 6}}});
  EXPECT_TRUE(lc.one_short().empty());  // consistency 0
  lc.update({C{6, {5, 7}}, C{90, {}}});
  EXPECT_TRUE(lc.one_short().empty());  // 1 and 0
  lc.update({C{5, {4, 6}}, C{91, {}}});
  EXPECT_EQ(lc.one_short(), std::vector<long>{5});  // 2 of 3: one short; 91 is new
  EXPECT_EQ(lc.update({C{7, {6, 8}}}), std::vector<long>{7});
  EXPECT_TRUE(lc.one_short().empty());  // accepted, not one short
  EXPECT_TRUE(lc.update({}).empty());
  EXPECT_TRUE(lc.one_short().empty());
  lc.update({C{5, {4, 6}}});
  lc.update({C{5, {4, 6}}});
  lc.update({C{5, {4, 6}}});
  ASSERT_EQ(lc.one_short(), std::vector<long>{5});  // the chain begun again after the gap
  lc.reset();
  EXPECT_TRUE(lc.one_short().empty());
  // With one consistent keyframe required, every new place is one short.
  LoopConsistency one(1);
  one.update({C{40, {}}, C{50, {}}});
  EXPECT_EQ(one.one_short(), (std::vector<long>{40, 50}));
}

}  // namespace
}  // namespace builtscene::slam
