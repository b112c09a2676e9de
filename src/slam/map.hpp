#pragma once
// The map: owner of every keyframe and map point, and of the one lock that guards their
// mutable state.
//
// Locking rule (the whole SLAM follows it): any thread that reads or writes a KeyFrame's or a
// MapPoint's mutable members (poses, positions, observations, covisibility, tree, flags)
// holds `Map::mutex()` for the duration. Tracking holds it while it matches and optimizes a
// frame against the map; local mapping holds it while it inserts, fuses and culls; bundle
// adjustment copies its problem out under the lock, solves without it, and writes back
// under it (skipping anything that turned bad meanwhile). A future loop-closing thread
// follows the same rule. Immutable data (FrameFeatures, ids) needs no lock. A single coarse
// lock is deliberate: on two cores the threads mostly alternate anyway, and it makes the
// invariants (no dangling observation, no half-updated point) easy to keep.
#include <atomic>
#include <memory>
#include <mutex>
#include <unordered_map>
#include <vector>

#include "slam/key_frame.hpp"
#include "slam/map_point.hpp"

namespace builtscene::slam {

class Map {
 public:
  std::mutex& mutex() const { return mutex_; }

  // All of the following require the caller to hold mutex().
  void add_keyframe(const std::shared_ptr<KeyFrame>& kf);
  void add_point(const std::shared_ptr<MapPoint>& p);
  void erase_keyframe(KeyFrame* kf);
  void erase_point(MapPoint* p);
  std::shared_ptr<KeyFrame> keyframe(KeyFrame* kf) const;
  std::vector<std::shared_ptr<KeyFrame>> keyframes() const;     // sorted by id
  std::vector<std::shared_ptr<MapPoint>> points() const;
  std::size_t keyframe_count() const { return keyframes_.size(); }
  std::size_t point_count() const { return points_.size(); }
  void clear();
  // Plane landmarks (plane_landmark.hpp), in the order they were made.
  void add_plane(const std::shared_ptr<MapPlane>& p) { planes_.push_back(p); }
  const std::vector<std::shared_ptr<MapPlane>>& planes() const { return planes_; }
  void erase_plane(const MapPlane* p) { std::erase_if(planes_, [p](const auto& q) { return q.get() == p; }); }
  long next_plane_id() { return next_plane_id_++; }
  long peek_next_plane_id() const { return next_plane_id_; }
  void set_next_plane_id(long id) { next_plane_id_ = id; }

  // Thread-safe id sources.
  long next_keyframe_id() { return next_kf_id_++; }
  long next_point_id() { return next_point_id_++; }
  // Ids continue after a loaded map's (see map_serializer.hpp).
  long peek_next_keyframe_id() const { return next_kf_id_.load(); }
  long peek_next_point_id() const { return next_point_id_.load(); }
  void set_next_ids(long keyframe_id, long point_id) {
    next_kf_id_ = keyframe_id;
    next_point_id_ = point_id;
  }

 private:
  mutable std::mutex mutex_;
  std::unordered_map<KeyFrame*, std::shared_ptr<KeyFrame>> keyframes_;
  std::unordered_map<MapPoint*, std::shared_ptr<MapPoint>> points_;
  std::vector<std::shared_ptr<MapPlane>> planes_;
  long next_plane_id_ = 0;
  std::atomic<long> next_kf_id_{0}, next_point_id_{0};
};

}  // namespace builtscene::slam
