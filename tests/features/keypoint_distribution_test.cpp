#include <gtest/gtest.h>

#include "features/keypoint_distribution.hpp"

namespace builtscene {
namespace {

TEST(DistributeQuadtree, KeepsStrongestAndSpreads) {
  // A dense strong cluster in one corner and sparse weak points elsewhere: a response-only
  // selection would take only the cluster; the quadtree must also keep the sparse ones.
  std::vector<cv::KeyPoint> kps;
  for (int y = 0; y < 40; ++y)
    for (int x = 0; x < 40; ++x) kps.emplace_back(cv::Point2f(10.0f + x, 10.0f + y), 7.f, -1.f, 100.0f + x + y);
  for (int i = 0; i < 20; ++i) kps.emplace_back(cv::Point2f(100.0f + 25.0f * i, 300.0f), 7.f, -1.f, 1.0f);
  const auto out = distribute_quadtree(kps, cv::Rect2f(0, 0, 640, 480), 100);
  EXPECT_LE(out.size(), 100u);
  EXPECT_GE(out.size(), 90u);
  int sparse = 0;
  for (const auto& k : out) sparse += k.pt.y == 300.0f;
  EXPECT_GE(sparse, 15);
}

TEST(DistributeQuadtree, FewerThanWantedReturnsAll) {
  std::vector<cv::KeyPoint> kps{cv::KeyPoint(5, 5, 7), cv::KeyPoint(50, 50, 7)};
  EXPECT_EQ(distribute_quadtree(kps, cv::Rect2f(0, 0, 100, 100), 10).size(), 2u);
  EXPECT_TRUE(distribute_quadtree({}, cv::Rect2f(0, 0, 100, 100), 10).empty());
  EXPECT_TRUE(distribute_quadtree(kps, cv::Rect2f(0, 0, 100, 100), 0).empty());
}

TEST(DistributeQuadtree, DuplicatePositionsTerminate) {
  std::vector<cv::KeyPoint> kps(500, cv::KeyPoint(20.5f, 30.5f, 7));
  for (int i = 0; i < 500; ++i) kps[static_cast<std::size_t>(i)].response = static_cast<float>(i);
  const auto out = distribute_quadtree(kps, cv::Rect2f(0, 0, 64, 64), 50);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].response, 499.0f);
}

TEST(GridCoverage, CountsOccupiedCells) {
  std::vector<cv::KeyPoint> kps{cv::KeyPoint(1, 1, 7), cv::KeyPoint(99, 99, 7)};
  EXPECT_DOUBLE_EQ(grid_coverage(kps, cv::Size(100, 100), 2, 2), 0.5);
}

}  // namespace
}  // namespace builtscene
