#pragma once
// Descriptor matching guided by the vocabulary's direct index (ORB-SLAM2's SearchByBoW):
// only features filed under the same vocabulary node are compared, the best must be below
// the metric's strict threshold and below 0.75 of the second best, and the matches must
// agree on the keypoint rotation. Much cheaper than brute force and with fewer false
// matches, because a node groups similar descriptors.
//
// Reads map point state: the caller holds the map lock.
#include <memory>
#include <vector>

#include "features/bow_vector.hpp"
#include "slam/frame.hpp"

namespace builtscene::slam {

class KeyFrame;
class MapPoint;

// Matches the map points of `kf` (its bow_features must be set) to the keypoints of a frame
// with direct index `frame_features`. Returns, per frame keypoint, the matched map point or
// null; `count` receives the number of matches.
std::vector<std::shared_ptr<MapPoint>> search_by_bow(const KeyFrame& kf, const FrameFeatures& frame,
                                                     const FeatureVector& frame_features, int* count = nullptr,
                                                     float ratio = 0.75f);

}  // namespace builtscene::slam
