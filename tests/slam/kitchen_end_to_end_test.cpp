// End to end on real data: the 1000 Kinect frames of 7-Scenes "kitchen" (TUM layout) against
// their KinectFusion ground truth. Skipped when the shared data folder is absent.
#include <filesystem>

#include <gtest/gtest.h>

#include "io/tum_dataset.hpp"
#include "slam/system.hpp"
#include "trajectory_alignment.hpp"

namespace builtscene::slam {
namespace {

const std::filesystem::path kKitchen = std::filesystem::path(BUILTSCENE_SOURCE_DIR) / "../shared/data/7scenes-kitchen";

TEST(KitchenEndToEnd, TracksNearlyEveryFrameWithinAFewCentimetres) {
  if (!std::filesystem::exists(kKitchen / "rgb.txt")) GTEST_SKIP() << "7scenes-kitchen not found at " << kKitchen;
  const auto data = TumDataset::open(kKitchen);
  ASSERT_EQ(data.size(), 1000u);
  System slam(data.settings());
  int tracked = 0;
  for (std::size_t i = 0; i < data.size(); ++i) {
    const auto out = slam.track_rgbd(data.load_rgb(i), data.load_depth(i), data.entry(i).timestamp);
    tracked += out.state == TrackingState::kOk;
  }
  slam.shutdown();
  const auto traj = slam.trajectory();
  const auto ate = test::absolute_trajectory_error(data.groundtruth(), traj);
  const auto kf_ate = test::absolute_trajectory_error(data.groundtruth(), slam.keyframe_trajectory());
  std::printf("tracked %d/1000, keyframes %zu, map points %zu, ATE RMSE %.2f cm (median %.2f, max %.2f) over %zu poses; "
              "keyframes %.2f cm; tracking median %.1f ms/frame\n",
              tracked, slam.keyframe_count(), slam.map_point_count(), 100 * ate.rmse, 100 * ate.median, 100 * ate.max,
              ate.matched, 100 * kf_ate.rmse, slam.timer().median_ms("frame"));
  EXPECT_GE(tracked, 950);
  EXPECT_EQ(ate.matched, static_cast<std::size_t>(tracked));
  // Bound: 7-Scenes depth is not registered to colour (the Kinect's two cameras are ~2.5 cm
  // apart, so 3D points are displaced by up to a few cm depending on depth) and its
  // intrinsics are nominal; measured RMSE is 4.2-4.8 cm over repeated runs and
  // configurations (docs/slam.md). 7 cm leaves room for thread-timing variation, and still
  // fails on a real regression (a drifting or wrongly scaled trajectory is tens of cm off).
  EXPECT_LT(ate.rmse, 0.07);
}

}  // namespace
}  // namespace builtscene::slam
