#pragma once
// A 3D landmark: position, mean viewing direction, the representative descriptor (least median
// distance among its observations), the distance range over which ORB can see it at some
// pyramid level, and the keyframes observing it.
//
// Locking: every member except `id` is guarded by the Map's mutex (Map::mutex()); the
// owner of a MapPoint is the Map, which holds the only long-lived shared_ptr. Observations
// point at keyframes by raw pointer: a keyframe removes itself from all its points before it
// leaves the map, so these never dangle.
#include <map>
#include <memory>

#include <opencv2/core.hpp>

#include "core/se3.hpp"
#include "features/orb_extractor.hpp"
#include "slam/id_order.hpp"

namespace builtscene::slam {

class KeyFrame;
class Map;

class MapPoint : public std::enable_shared_from_this<MapPoint> {
 public:
  MapPoint(long id, const Eigen::Vector3d& position, KeyFrame* reference, long created_by_kf);

  const long id;
  Eigen::Vector3d position;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // mean unit viewing direction (towards the point)
  cv::Mat descriptor;                                // one row
  float min_distance = 0, max_distance = 0;          // scale-invariance range (metres)
  KeyFrameMap<int> observations;                     // keyframe -> keypoint index
  KeyFrame* reference = nullptr;
  long created_by_kf = 0;
  // Tracking statistics: predicted visible in a frame / actually matched there.
  int visible = 1, found = 1;
  bool bad = false;
  std::shared_ptr<MapPoint> replaced_by;  // set when fused into another point
  // Marks (frame or keyframe ids) so a pass visits each point once.
  long local_map_mark = -1, track_mark = -1, fuse_mark = -1, ba_mark = -1;

  float found_ratio() const { return static_cast<float>(found) / static_cast<float>(std::max(visible, 1)); }
  int observation_count() const { return static_cast<int>(observations.size()); }
  bool observed_by(const KeyFrame* kf) const;

  void add_observation(KeyFrame* kf, int index);
  // Removes kf's observation; the point turns bad when fewer than two keyframes remain.
  void erase_observation(KeyFrame* kf, Map& map);
  // Removes the point from every observing keyframe and from the map.
  void set_bad(Map& map);
  // Moves every observation to `other` and retires this point.
  void replace_with(const std::shared_ptr<MapPoint>& other, Map& map);
  void update_descriptor();
  void update_normal_and_depth();
  // Pyramid level at which ORB would detect this point seen from `distance` metres.
  int predict_level(double distance, const ScalePyramid& pyramid) const;
};

}  // namespace builtscene::slam
