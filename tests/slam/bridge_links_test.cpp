// Bridge links (bridge_links.hpp) on a hand-built spanning tree: which cameras of a global
// bundle adjustment problem get linked, to which ancestor, and with what relative pose and
// information.
#include <gtest/gtest.h>

#include <cmath>

#include "slam/bridge_links.hpp"
#include "slam/map.hpp"
#include "synthetic_scene.hpp"

namespace builtscene::slam {
namespace {

class BridgeLinks : public ::testing::Test {
 protected:
  // Keyframes 0..9 along a curve, each the tree child of the one before. Keyframes 4 and 5
  // were made on the depth-odometry bridge (their tree edges are odometry), and so was 8.
  void SetUp() override {
    RgbdCameraSettings s;
    s.camera = {525, 525, 319.5, 239.5, 0, 0, 0, 0, 0, 640, 480};
    const auto ctx = FrameContext::make(s, ScalePyramid::make(1.2f, 8), DescriptorMetric::orb());
    for (int k = 0; k < 10; ++k) {
      auto f = std::make_shared<FrameFeatures>();
      f->ctx = ctx;
      f->descriptors = cv::Mat::zeros(0, 32, CV_8U);
      f->grid_start.assign(FrameContext::kGridCols * FrameContext::kGridRows + 1, 0);
      Frame frame(10 * k, static_cast<double>(k), f);
      const double a = 0.2 * k;
      frame.set_pose(SE3(Eigen::Quaterniond(Eigen::AngleAxisd(a, Eigen::Vector3d::UnitY())),
                         Eigen::Vector3d(0.5 * k, 0.02 * k * k, -0.3 * k)));
      auto kf = std::make_shared<KeyFrame>(k, frame);
      if (k > 0) kf->link_to_parent(*kfs_.back());
      kf->parent_by_odometry = k == 4 || k == 5 || k == 8;
      map_.add_keyframe(kf);
      kfs_.push_back(kf);
    }
  }

  std::vector<std::shared_ptr<KeyFrame>> cams(std::initializer_list<int> ids) const {
    std::vector<std::shared_ptr<KeyFrame>> out;
    for (int id : ids) out.push_back(kfs_[static_cast<std::size_t>(id)]);
    return out;
  }

  Map map_;
  std::vector<std::shared_ptr<KeyFrame>> kfs_;
};

TEST_F(BridgeLinks, LinkAcrossTheBridgedStretchAndOverABridgedEdgeOnly) {
  // 3, 4, 5 are left out of the problem (no points to hold them). Walking up from 6: 5 and 4
  // came by odometry, 3 is out, 2 is in: link 6 -> 2. 8's own edge is odometry: 8 -> 7.
  // 1 -> 0, 2 -> 1, 7 -> 6 and 9 -> 8 are plain covisibility edges: no link.
  const auto c = cams({0, 1, 2, 6, 7, 8, 9});
  BundleAdjustmentProblem pb;
  ASSERT_EQ(add_bridge_links(c, BridgeLinkOptions{}, pb), 2);
  ASSERT_EQ(pb.relative_poses.size(), 2u);
  const auto& a = pb.relative_poses[0];
  const auto& b = pb.relative_poses[1];
  EXPECT_EQ(a.i, 3);  // camera index of keyframe 6
  EXPECT_EQ(a.j, 2);  // keyframe 2
  EXPECT_EQ(b.i, 5);  // keyframe 8
  EXPECT_EQ(b.j, 4);  // keyframe 7
  // The held relative pose is the current one: T_6w * T_2w^-1, checked through the centres.
  const SE3 T62 = a.T_ij;
  const Eigen::Vector3d c2_in_6 = kfs_[6]->pose() * kfs_[2]->camera_center();
  EXPECT_LT((T62.translation() - c2_in_6).norm(), 1e-9);
  EXPECT_LT(test::rotation_error_deg(T62, kfs_[6]->pose() * kfs_[2]->pose_inverse()), 1e-6);
  // 2 cm and 0.5 degrees by default.
  EXPECT_NEAR(a.information(0, 0), 1.0 / (0.02 * 0.02), 1e-6);
  EXPECT_NEAR(a.information(5, 5), 1.0 / std::pow(0.5 * M_PI / 180.0, 2), 1e-3);
  EXPECT_DOUBLE_EQ(a.information(0, 1), 0.0);
}

TEST_F(BridgeLinks, AKeyFrameOnTheStretchThatIsInTheProblemSplitsTheLink) {
  // With 4 in the problem: 4 -> 2 (its own edge is odometry, 3 is out) and 6 -> 4 (over 5).
  const auto c = cams({0, 1, 2, 4, 6});
  BundleAdjustmentProblem pb;
  ASSERT_EQ(add_bridge_links(c, BridgeLinkOptions{}, pb), 2);
  EXPECT_EQ(pb.relative_poses[0].i, 3);
  EXPECT_EQ(pb.relative_poses[0].j, 2);
  EXPECT_EQ(pb.relative_poses[1].i, 4);
  EXPECT_EQ(pb.relative_poses[1].j, 3);
}

TEST_F(BridgeLinks, NoAncestorInTheProblemOrNoSigmaGivesNoLink) {
  // 6's chain reaches the root without meeting a camera of the problem.
  BundleAdjustmentProblem pb;
  EXPECT_EQ(add_bridge_links(cams({6, 7}), BridgeLinkOptions{}, pb), 0);
  EXPECT_TRUE(pb.relative_poses.empty());
  // Off: sigma 0.
  BridgeLinkOptions off;
  off.sigma_m = 0.0;
  EXPECT_EQ(add_bridge_links(cams({0, 1, 2, 6, 7, 8, 9}), off, pb), 0);
  EXPECT_TRUE(pb.relative_poses.empty());
}

}  // namespace
}  // namespace builtscene::slam
