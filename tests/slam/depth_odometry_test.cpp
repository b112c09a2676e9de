// The depth-odometry bridge on real Kinect frames (7-Scenes kitchen) against their
// KinectFusion ground truth: consecutive frames are aligned to the true relative motion,
// and two views of different places (a kidnapped camera) are refused instead of being
// given some small wrong motion. Skipped when the shared data folder is absent.
#include <cstdio>
#include <filesystem>

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "io/tum_dataset.hpp"
#include "slam/depth_odometry.hpp"

namespace builtscene::slam {
namespace {

const std::filesystem::path kKitchen = std::filesystem::path(BUILTSCENE_SOURCE_DIR) / "../shared/data/7scenes-kitchen";

class KitchenDepthOdometry : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::filesystem::exists(kKitchen / "rgb.txt")) GTEST_SKIP() << "7scenes-kitchen not found at " << kKitchen;
    data_.emplace(TumDataset::open(kKitchen));
    gt_ = data_->groundtruth();
    ASSERT_EQ(gt_.size(), data_->size());
    const auto& c = data_->settings().camera;
    odometry_.emplace(c.fx, c.fy, c.cx, c.cy);
  }
  cv::Mat gray(std::size_t i) const {
    cv::Mat g;
    cv::cvtColor(data_->load_rgb(i), g, cv::COLOR_BGR2GRAY);
    return g;
  }
  // T_cur_prev from ground truth (camera-to-world poses).
  SE3 true_motion(std::size_t prev, std::size_t cur) const {
    EXPECT_NEAR(gt_[prev].timestamp, data_->entry(prev).timestamp, 0.02);
    EXPECT_NEAR(gt_[cur].timestamp, data_->entry(cur).timestamp, 0.02);
    return gt_[cur].pose.inverse() * gt_[prev].pose;
  }
  std::optional<TumDataset> data_;
  Trajectory gt_;
  std::optional<DepthOdometry> odometry_;
};

TEST_F(KitchenDepthOdometry, ConsecutiveFramesGiveTheTrueMotion) {
  for (std::size_t prev : {40u, 150u, 260u, 520u, 800u}) {
    const std::size_t cur = prev + 1;
    const cv::Mat prev_depth = data_->load_depth(prev), cur_depth = data_->load_depth(cur);
    const auto T = odometry_->align(gray(prev), prev_depth, gray(cur), cur_depth, SE3());
    ASSERT_TRUE(T.has_value()) << "frames " << prev << "-" << cur;
    const SE3 err = true_motion(prev, cur).inverse() * *T;
    EXPECT_LT(err.translation().norm(), 0.02) << "frames " << prev << "-" << cur;
    EXPECT_LT(err.log().tail<3>().norm() * 180 / M_PI, 2.0) << "frames " << prev << "-" << cur;
    const double agreement =
        odometry_->depth_agreement(prev_depth, cur_depth, true_motion(prev, cur));
    std::printf("frames %zu-%zu: error %.1f mm, depth agreement under the true motion %.3f\n", prev, cur,
                1000 * err.translation().norm(), agreement);
    EXPECT_GT(agreement, DepthOdometry::kMinDepthAgreement);
  }
}

TEST_F(KitchenDepthOdometry, ViewsOfAnotherPlaceAreRefused) {
  // Frame 299 and frame 80: 0.76 m and 30 degrees apart (the relocalization test's jump).
  const SE3 jump = true_motion(299, 80);
  ASSERT_GT(jump.translation().norm(), 0.5);
  const cv::Mat depth_299 = data_->load_depth(299), depth_80 = data_->load_depth(80);
  const auto T = odometry_->align(gray(299), depth_299, gray(80), depth_80, SE3());
  EXPECT_FALSE(T.has_value()) << "accepted a motion of " << T->translation().norm() << " m";
  // The refusal is by the depth check: the identity motion does not explain the other view.
  const double agreement = odometry_->depth_agreement(depth_299, depth_80, SE3());
  std::printf("frames 299-80: depth agreement under no motion %.3f\n", agreement);
  EXPECT_LT(agreement, DepthOdometry::kMinDepthAgreement);
}

}  // namespace
}  // namespace builtscene::slam
