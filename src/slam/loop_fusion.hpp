#pragma once
// Merging the two copies of a place that a loop closure finds (ORB-SLAM2's fusion step of
// CorrectLoop): the current keyframe's keypoints matched to loop-side map points take the
// loop-side point (a duplicate point of the current side is retired into it, its
// observations moved), and the loop-side points are projected into every corrected keyframe
// and fused there (matcher.hpp's fuse).
//
// The caller holds the map lock.
#include <memory>
#include <vector>

namespace builtscene::slam {

class KeyFrame;
class MapPoint;
class Map;

// `loop_points[i]`: the loop-side point matched to keypoint i of kf (null: none). Returns
// how many keypoints now refer to a loop-side point they did not refer to before.
int fuse_loop_matches(KeyFrame& kf, const std::vector<std::shared_ptr<MapPoint>>& loop_points, Map& map);

// The good map points of `keyframe` and its covisible keyframes, each once.
std::vector<std::shared_ptr<MapPoint>> neighbourhood_points(const KeyFrame& keyframe);

}  // namespace builtscene::slam
