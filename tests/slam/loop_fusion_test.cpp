// Fusion of the duplicated points a loop closure finds, on a constructed map: the current
// side (keyframes B, B2) mapped the same places again as points Q_i that duplicate the loop
// side's P_i (keyframes A, A2). After fusion every keypoint that saw Q_i sees P_i, the
// duplicates are retired, and nothing else changed.
#include <gtest/gtest.h>

#include <random>
#include <set>

#include "map_test_fixture.hpp"
#include "slam/loop_fusion.hpp"

namespace builtscene::slam {
namespace {

std::shared_ptr<KeyFrame> make_keyframe(Map& map, const std::shared_ptr<const FrameContext>& ctx, int n, std::mt19937& rng) {
  auto f = std::make_shared<FrameFeatures>();
  f->ctx = ctx;
  std::uniform_real_distribution<float> ux(0, 639), uy(0, 479);
  for (int i = 0; i < n; ++i) {
    f->keys.emplace_back(ux(rng), uy(rng), 31.0f, 0.0f, 1.0f, 0);
    f->depth.push_back(2.0f);
    f->u_right.push_back(f->keys.back().pt.x - static_cast<float>(ctx->bf) / 2.0f);
  }
  f->keys_un = f->keys;
  f->descriptors = cv::Mat(n, 32, CV_8U);
  cv::randu(f->descriptors, 0, 255);
  build_feature_grid(*f);
  Frame frame(map.peek_next_keyframe_id(), 0.0, f);
  frame.set_pose(SE3());
  auto kf = std::make_shared<KeyFrame>(map.next_keyframe_id(), frame);
  map.add_keyframe(kf);
  return kf;
}

std::shared_ptr<MapPoint> make_point(Map& map, std::initializer_list<std::pair<KeyFrame*, int>> obs) {
  auto p = std::make_shared<MapPoint>(map.next_point_id(), Eigen::Vector3d(0, 0, 2), obs.begin()->first, 0);
  for (auto [kf, i] : obs) {
    p->add_observation(kf, i);
    kf->add_point(i, p);
  }
  p->update_descriptor();
  map.add_point(p);
  return p;
}

TEST(LoopFusion, DuplicatesAreRetiredIntoTheLoopSide) {
  Map map;
  std::lock_guard lock(map.mutex());
  const auto ctx = test::kinect_context();
  std::mt19937 rng(5);
  const int n = 12;
  auto A = make_keyframe(map, ctx, n, rng), A2 = make_keyframe(map, ctx, n, rng);
  auto B = make_keyframe(map, ctx, n, rng), B2 = make_keyframe(map, ctx, n, rng);
  std::vector<std::shared_ptr<MapPoint>> P, Q, loop(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) P.push_back(make_point(map, {{A.get(), i}, {A2.get(), i}}));
  // B keypoints 0..7 hold duplicates Q_i (also seen by B2 at keypoint i + 1); 8..9 hold no
  // point yet; 10..11 hold points the loop does not match.
  for (int i = 0; i < 8; ++i) Q.push_back(make_point(map, {{B.get(), i}, {B2.get(), i + 1}}));
  auto other = make_point(map, {{B.get(), 10}, {B2.get(), 0}});
  for (int i = 0; i < 10; ++i) loop[static_cast<std::size_t>(i)] = P[static_cast<std::size_t>(i)];
  const std::size_t points_before = map.point_count();

  EXPECT_EQ(fuse_loop_matches(*B, loop, map), 10);

  for (int i = 0; i < 10; ++i) {
    const auto& p = P[static_cast<std::size_t>(i)];
    EXPECT_EQ(B->points[static_cast<std::size_t>(i)], p) << i;
    EXPECT_TRUE(p->observed_by(B.get()));
    EXPECT_EQ(p->observations.at(B.get()), i);
    EXPECT_FALSE(p->bad);
  }
  for (int i = 0; i < 8; ++i) {
    const auto& q = Q[static_cast<std::size_t>(i)];
    EXPECT_TRUE(q->bad);
    EXPECT_EQ(q->replaced_by, P[static_cast<std::size_t>(i)]);
    // B2's observation of the duplicate moved to the loop point.
    EXPECT_EQ(B2->points[static_cast<std::size_t>(i + 1)], P[static_cast<std::size_t>(i)]);
    EXPECT_EQ(P[static_cast<std::size_t>(i)]->observation_count(), 4);
  }
  EXPECT_EQ(P[8]->observation_count(), 3);  // A, A2 and now B
  EXPECT_EQ(B->points[10], other);
  EXPECT_FALSE(other->bad);
  EXPECT_EQ(map.point_count(), points_before - 8);
  // Running it again changes nothing.
  EXPECT_EQ(fuse_loop_matches(*B, loop, map), 0);
  map.clear();
}

TEST(LoopFusion, NeighbourhoodPointsAreTheKeyframeAndItsCovisiblesEachOnce) {
  Map map;
  std::lock_guard lock(map.mutex());
  test::build_random_map(map, test::kinect_context(), 6, 80);
  const auto kfs = map.keyframes();
  const auto pts = neighbourhood_points(*kfs[2]);
  std::set<const MapPoint*> expected;
  std::vector<const KeyFrame*> group{kfs[2].get()};
  for (const KeyFrame* k : kfs[2]->ordered_connections) group.push_back(k);
  ASSERT_GT(group.size(), 1u);
  for (const KeyFrame* k : group)
    for (const auto& p : k->points)
      if (p && !p->bad) expected.insert(p.get());
  std::set<const MapPoint*> got;
  for (const auto& p : pts) EXPECT_TRUE(got.insert(p.get()).second);
  EXPECT_EQ(got, expected);
  map.clear();
}

}  // namespace
}  // namespace builtscene::slam
