// Mode schedules and the region rule.
#include <gtest/gtest.h>

#include "core/errors.hpp"
#include "slam/mode_plan.hpp"

namespace builtscene::slam {
namespace {

TEST(ModeSchedule, ParsesRangesAndLeavesGapsAlone) {
  const auto s = ModeSchedule::parse("0-199:slam,200-399:localize,500-:slam");
  EXPECT_EQ(s.mode_at(0), Mode::kSlam);
  EXPECT_EQ(s.mode_at(199), Mode::kSlam);
  EXPECT_EQ(s.mode_at(200), Mode::kLocalization);
  EXPECT_EQ(s.mode_at(399), Mode::kLocalization);
  EXPECT_EQ(s.mode_at(400), std::nullopt);
  EXPECT_EQ(s.mode_at(100000), Mode::kSlam);
}

TEST(ModeSchedule, RejectsMalformedListsNamingTheOption) {
  for (const char* bad : {"", "0-10", "0:slam", "a-10:slam", "10-5:slam", "0-10:map", "0-10:slam,5-20:localize",
                          "0-10:slam,", "-5-10:slam"}) {
    try {
      ModeSchedule::parse(bad);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const InputError& e) {
      EXPECT_EQ(std::string(e.what()).rfind("--mode-schedule:", 0), 0u) << e.what();
    }
  }
}

TEST(ModePlan, ScheduleWinsThenRegionThenNoChange) {
  ModePlan plan;
  EXPECT_TRUE(plan.empty());
  EXPECT_FALSE(plan.decide(0, SE3()).has_value());
  plan.set_schedule(ModeSchedule::parse("0-9:localize"));
  // Inside: x within [0, 2] of the world.
  plan.set_region([](const SE3& T_wc) { return T_wc.translation().x() >= 0 && T_wc.translation().x() <= 2; });
  const SE3 inside(Eigen::Quaterniond::Identity(), Eigen::Vector3d(1, 0, 0));
  const SE3 outside(Eigen::Quaterniond::Identity(), Eigen::Vector3d(3, 0, 0));
  EXPECT_EQ(plan.decide(5, inside)->mode, Mode::kLocalization);
  EXPECT_STREQ(plan.decide(5, inside)->reason, "schedule");
  EXPECT_EQ(plan.decide(10, inside)->mode, Mode::kSlam);
  EXPECT_EQ(plan.decide(10, outside)->mode, Mode::kLocalization);
  EXPECT_STREQ(plan.decide(10, outside)->reason, "region");
  EXPECT_FALSE(plan.decide(10, std::nullopt).has_value());  // lost: keep the current mode
}

}  // namespace
}  // namespace builtscene::slam
