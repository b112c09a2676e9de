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

// Spread of a keypoint set for evaluation: the fraction of cells of a cols x rows grid over
// the image that hold at least one keypoint.
double grid_coverage(const std::vector<cv::KeyPoint>& keypoints, cv::Size image, int cols, int rows);

}  // namespace builtscene
