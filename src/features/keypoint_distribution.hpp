#pragma once
// Spreading keypoints evenly over an image with a quadtree: the region is split, most crowded
// cell first, until there are as many non-empty cells as keypoints wanted (or no cell can be
// split further); each cell then keeps its strongest keypoint. Flat textured regions thus
// cannot take all the budget, which is what gives ORB-SLAM's extractor its even coverage.
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/core/types.hpp>

namespace builtscene {

// Keeps at most `wanted` keypoints of `keypoints` (coordinates inside `bounds`), one per
// quadtree cell, strongest response first. Deterministic for a given input order.
std::vector<cv::KeyPoint> distribute_quadtree(const std::vector<cv::KeyPoint>& keypoints, const cv::Rect2f& bounds,
                                              int wanted);

// Working memory of the quadtree, kept by a caller that distributes every frame so the
// tree allocates nothing once warm.
struct QuadtreeScratch {
  struct Cell {
    cv::Rect2f box;
    int begin, end;  // range of `members`
    int size() const { return end - begin; }
  };
  std::vector<Cell> cells;
  std::vector<int> members, tmp, heap, root_count, root_fill;
  std::vector<char> split_away;
};
// The same, writing into `out` (cleared first) and reusing `scratch`.
void distribute_quadtree(const std::vector<cv::KeyPoint>& keypoints, const cv::Rect2f& bounds, int wanted,
                         std::vector<cv::KeyPoint>& out, QuadtreeScratch& scratch);

// Spread of a keypoint set for evaluation: the fraction of cells of a cols x rows grid over
// the image that hold at least one keypoint.
double grid_coverage(const std::vector<cv::KeyPoint>& keypoints, cv::Size image, int cols, int rows);

}  // namespace builtscene
