#include "core/stage_timer.hpp"

#include <gtest/gtest.h>

namespace builtscene {

TEST(Quantile, MatchesClosedFormOnArithmeticSequence) {
  std::vector<double> v;
  for (int i = 0; i <= 100; ++i) v.push_back(100 - i);  // 0..100, unsorted
  EXPECT_DOUBLE_EQ(quantile(v, 0.5), 50.0);
  EXPECT_DOUBLE_EQ(quantile(v, 0.95), 95.0);
  EXPECT_DOUBLE_EQ(quantile(v, 0.0), 0.0);
  EXPECT_DOUBLE_EQ(quantile(v, 1.0), 100.0);
  EXPECT_DOUBLE_EQ(quantile({1.0, 2.0}, 0.5), 1.5);
  EXPECT_DOUBLE_EQ(quantile({}, 0.5), 0.0);
}

TEST(StageTimer, SummaryHasMedianP95AndCounts) {
  StageTimer t;
  for (int i = 1; i <= 5; ++i) t.add("a", i);
  t.add("b", 7);
  const auto s = t.summary();
  EXPECT_DOUBLE_EQ(s["a"]["median"].get<double>(), 3.0);
  EXPECT_DOUBLE_EQ(s["a"]["total"].get<double>(), 15.0);
  EXPECT_EQ(s["a"]["count"].get<int>(), 5);
  EXPECT_DOUBLE_EQ(s["b"]["p95"].get<double>(), 7.0);
  EXPECT_EQ(t.count("missing"), 0u);
}

}  // namespace builtscene
