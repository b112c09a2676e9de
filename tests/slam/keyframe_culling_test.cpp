// ORB-SLAM's keyframe culling rule on hand-built keyframes: redundant when more than 90 % of
// its close map points are seen by at least 3 other keyframes at the same or a finer scale.
#include <gtest/gtest.h>

#include "slam/key_frame.hpp"
#include "slam/local_mapping.hpp"
#include "slam/map.hpp"
#include "slam/map_point.hpp"

namespace builtscene::slam {
namespace {

class KeyFrameCulling : public ::testing::Test {
 protected:
  void SetUp() override {
    RgbdCameraSettings s;
    s.camera = {525, 525, 319.5, 239.5, 0, 0, 0, 0, 0, 640, 480};
    ctx_ = FrameContext::make(s, ScalePyramid::make(1.2f, 8), DescriptorMetric::orb());
  }

  // A keyframe with n keypoints at `octave`; the first n_close have depth 1 m (close), the
  // rest have no depth.
  std::shared_ptr<KeyFrame> make_kf(long id, int n, int n_close, int octave) {
    auto f = std::make_shared<FrameFeatures>();
    f->ctx = ctx_;
    for (int i = 0; i < n; ++i) {
      cv::KeyPoint k(cv::Point2f(20.0f + 10.0f * static_cast<float>(i), 100.0f), 31.0f, 0.0f, 50.0f, octave);
      f->keys.push_back(k);
      f->keys_un.push_back(k);
      f->depth.push_back(i < n_close ? 1.0f : -1.0f);
      f->u_right.push_back(i < n_close ? k.pt.x - 40.0f : -1.0f);
    }
    f->descriptors = cv::Mat::zeros(n, 32, CV_8U);
    f->grid_start.assign(FrameContext::kGridCols * FrameContext::kGridRows + 1, 0);
    Frame frame(id, static_cast<double>(id), f);
    auto kf = std::make_shared<KeyFrame>(id, frame);
    map_.add_keyframe(kf);
    return kf;
  }

  // Point i of `target` observed by each keyframe in `others` (at their keypoint i).
  void share(const std::shared_ptr<KeyFrame>& target, int i, const std::vector<std::shared_ptr<KeyFrame>>& others) {
    auto p = target->points[static_cast<std::size_t>(i)];
    if (!p) {
      p = std::make_shared<MapPoint>(map_.next_point_id(), Eigen::Vector3d(0, 0, 1), target.get(), target->id);
      p->add_observation(target.get(), i);
      target->add_point(i, p);
      map_.add_point(p);
    }
    for (const auto& o : others) {
      p->add_observation(o.get(), i);
      o->add_point(i, p);
    }
  }

  std::shared_ptr<const FrameContext> ctx_;
  Map map_;
  void TearDown() override { map_.clear(); }
};

TEST_F(KeyFrameCulling, AllPointsSeenThreeTimesElsewhereIsRedundant) {
  auto kf = make_kf(5, 10, 10, 1);
  std::vector<std::shared_ptr<KeyFrame>> others{make_kf(6, 10, 10, 1), make_kf(7, 10, 10, 1), make_kf(8, 10, 10, 2)};
  for (int i = 0; i < 10; ++i) share(kf, i, others);
  EXPECT_TRUE(is_redundant_keyframe(*kf));
}

TEST_F(KeyFrameCulling, NinetyPercentExactlyIsNotRedundant) {
  // The rule is strictly more than 90 %.
  auto kf = make_kf(5, 10, 10, 1);
  std::vector<std::shared_ptr<KeyFrame>> others{make_kf(6, 10, 10, 1), make_kf(7, 10, 10, 1), make_kf(8, 10, 10, 1)};
  for (int i = 0; i < 9; ++i) share(kf, i, others);
  share(kf, 9, {others[0]});
  EXPECT_FALSE(is_redundant_keyframe(*kf));
}

TEST_F(KeyFrameCulling, TwoOtherObserversAreNotEnough) {
  auto kf = make_kf(5, 10, 10, 1);
  std::vector<std::shared_ptr<KeyFrame>> others{make_kf(6, 10, 10, 1), make_kf(7, 10, 10, 1)};
  for (int i = 0; i < 10; ++i) share(kf, i, others);
  EXPECT_FALSE(is_redundant_keyframe(*kf));
}

TEST_F(KeyFrameCulling, CoarserScaleObservationsDoNotCount) {
  // Other keyframes see the points two levels coarser: they cannot replace this keyframe's
  // finer measurements.
  auto kf = make_kf(5, 10, 10, 1);
  std::vector<std::shared_ptr<KeyFrame>> others{make_kf(6, 10, 10, 3), make_kf(7, 10, 10, 3), make_kf(8, 10, 10, 3)};
  for (int i = 0; i < 10; ++i) share(kf, i, others);
  EXPECT_FALSE(is_redundant_keyframe(*kf));
}

TEST_F(KeyFrameCulling, FarPointsAreIgnoredForRgbd) {
  // 10 close points all redundant, 10 far points seen nowhere else: still redundant.
  auto kf = make_kf(5, 20, 10, 0);
  std::vector<std::shared_ptr<KeyFrame>> others{make_kf(6, 20, 20, 0), make_kf(7, 20, 20, 0), make_kf(8, 20, 20, 0)};
  for (int i = 0; i < 10; ++i) share(kf, i, others);
  for (int i = 10; i < 20; ++i) share(kf, i, {});
  EXPECT_TRUE(is_redundant_keyframe(*kf));
}

TEST_F(KeyFrameCulling, FirstAndProtectedKeyFramesAreKept) {
  auto first = make_kf(0, 10, 10, 0);
  auto kept = make_kf(9, 10, 10, 0);
  kept->keep = true;
  std::vector<std::shared_ptr<KeyFrame>> others{make_kf(6, 10, 10, 0), make_kf(7, 10, 10, 0), make_kf(8, 10, 10, 0)};
  for (int i = 0; i < 10; ++i) {
    share(first, i, others);
    share(kept, i, {});
    for (const auto& o : others) {
      kept->points[static_cast<std::size_t>(i)]->add_observation(o.get(), i);
    }
  }
  EXPECT_FALSE(is_redundant_keyframe(*first));
  EXPECT_FALSE(is_redundant_keyframe(*kept));
}

TEST_F(KeyFrameCulling, SetBadUnlinksEverything) {
  auto kf = make_kf(5, 20, 20, 1);
  std::vector<std::shared_ptr<KeyFrame>> others{make_kf(6, 20, 20, 1), make_kf(7, 20, 20, 1), make_kf(8, 20, 20, 1)};
  for (int i = 0; i < 20; ++i) share(kf, i, others);
  for (auto& o : others) o->update_connections();
  kf->update_connections();
  EXPECT_EQ(kf->connections.size(), 3u);  // 20 shared points each, above the weight threshold of 15
  const auto before = map_.keyframe_count();
  kf->set_bad(map_);
  EXPECT_EQ(map_.keyframe_count(), before - 1);
  for (const auto& o : others) {
    EXPECT_EQ(o->connections.count(kf.get()), 0u);
    for (const auto& p : o->points) {
      ASSERT_TRUE(p);
      EXPECT_FALSE(p->observed_by(kf.get()));
      EXPECT_FALSE(p->bad);  // still seen by 3 keyframes
    }
  }
}

}  // namespace
}  // namespace builtscene::slam
