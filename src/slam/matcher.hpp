#pragma once
// Descriptor matching between frames, keyframes and map points, guided by geometry: search by
// projection (motion model, local map), search by descriptor against a keyframe (the
// reference-keyframe fallback; brute force until a vocabulary exists, issue 5), and fusion of
// map points into a keyframe. Distances and thresholds come from the frame's
// DescriptorMetric, so binary and float descriptors share this code.
//
// Every function reads map point state and requires the caller to hold the map lock.
#include <memory>
#include <vector>

#include "slam/frame.hpp"

namespace builtscene::slam {

class KeyFrame;
class MapPoint;
class Map;

// Rotation consistency (ORB-SLAM): the orientation difference of matched keypoints is
// histogrammed in 30 bins; matches outside the three fullest bins are dropped.
class RotationConsistency {
 public:
  void add(float angle_a_deg, float angle_b_deg, int match);
  // Matches to discard.
  std::vector<int> inconsistent() const;

 private:
  static constexpr int kBins = 30;
  std::vector<int> bins_[kBins];
};

// Projects the matched map points of `last` with current.T_cw and matches them in `current`
// within radius th * scale(level). Returns the number of new matches.
int search_by_projection(Frame& current, const Frame& last, float th);

// A map point predicted in view of a frame (tracking's frustum test).
struct ProjectedPoint {
  std::shared_ptr<MapPoint> point;
  float u = 0, v = 0, u_right = -1;
  int level = 0;
  float view_cos = 1;
};

// Matches projected local-map points into the frame's unmatched keypoints; radius
// th * (2.5 when seen head-on, else 4) * scale(level). Returns the number of new matches.
int search_local_points(Frame& frame, const std::vector<ProjectedPoint>& candidates, float th);

// Projects the map points of `keyframe` and its `neighbours` best covisible keyframes (those
// not matched in the frame yet, in front, inside the scale range and the viewing cone) into
// the frame at its current pose and matches them (search_local_points). Relocalization and
// loop closing use it to extend matches found by bag of words. Returns new matches.
int search_keyframe_neighbourhood(Frame& frame, const KeyFrame& keyframe, std::size_t neighbours, float th);

// Matches the keyframe's map points to the frame's keypoints by descriptor alone
// (best < strict threshold, Lowe ratio 0.7, rotation consistency). Returns the match count.
int search_by_descriptor(const KeyFrame& kf, Frame& frame);

// Projects `points` into `kf` and, for each, either adds the observation or, when the matched
// keypoint already has a point, keeps the better-observed of the two. Returns fused count.
int fuse(KeyFrame& kf, const std::vector<std::shared_ptr<MapPoint>>& points, Map& map, float th = 3.0f);

}  // namespace builtscene::slam
