#pragma once
// A keyframe: a frame kept in the map, with its map points, its place in the covisibility
// graph (weights = shared map points) and in the spanning tree (parent = the keyframe it
// shares most points with when it joins).
//
// Locking: `features`, `id`, `frame_id`, `timestamp` never change; every other member is
// guarded by the Map's mutex. The Map owns keyframes. Covisibility and children use raw
// pointers to keyframes in the map (a keyframe unlinks itself when it turns bad); the parent
// is a shared_ptr so a culled keyframe keeps the chain needed to express frame poses
// relative to it.
#include <map>
#include <memory>
#include <set>
#include <vector>

#include "features/bow_vector.hpp"
#include "slam/frame.hpp"
#include "slam/id_order.hpp"
#include "slam/local_bundle_adjuster.hpp"
#include "slam/plane_landmark.hpp"

namespace builtscene::slam {

class Map;

class KeyFrame : public std::enable_shared_from_this<KeyFrame> {
 public:
  KeyFrame(long id, const Frame& frame);

  const long id;
  const long frame_id;
  const double timestamp;
  const std::shared_ptr<const FrameFeatures> f;

  const SE3& pose() const { return T_cw_; }  // world -> camera
  SE3 pose_inverse() const { return T_cw_.inverse(); }
  Eigen::Vector3d camera_center() const { return T_wc_.translation(); }
  void set_pose(const SE3& T_cw) {
    T_cw_ = T_cw;
    T_wc_ = T_cw.inverse();
  }

  std::vector<std::shared_ptr<MapPoint>> points;  // per keypoint, null when none

  void add_point(int index, const std::shared_ptr<MapPoint>& p) { points[static_cast<std::size_t>(index)] = p; }
  void erase_point(int index) { points[static_cast<std::size_t>(index)] = nullptr; }
  // Non-bad map points observed by at least min_obs keyframes.
  int tracked_points(int min_obs) const;
  std::vector<std::shared_ptr<MapPoint>> good_points() const;

  // Covisibility graph.
  KeyFrameMap<int> connections;
  std::vector<KeyFrame*> ordered_connections;  // by weight, heaviest first
  void update_connections(int min_weight = 15);
  std::vector<KeyFrame*> best_covisibles(std::size_t n) const;
  void add_connection(KeyFrame* other, int weight);
  void erase_connection(KeyFrame* other);

  // Spanning tree.
  std::shared_ptr<KeyFrame> parent;
  KeyFrameSet children;
  bool has_parent_link = false;  // set once the keyframe joined the tree
  // Joins the tree under `p` (once; no-op when already linked).
  void link_to_parent(KeyFrame& p);
  SE3 T_cp;                      // pose relative to parent, frozen when this keyframe turns bad
  // Made while the depth-odometry bridge held the pose (features could not): it shares no map
  // point with older keyframes, so covisibility cannot give it a parent. `odometry_parent` is
  // the keyframe the bridge carried the pose from, until local mapping makes it the parent
  // (and drops this pointer); `parent_by_odometry` then tells the essential graph to weigh
  // that edge as odometry, not as shared points.
  std::shared_ptr<KeyFrame> odometry_parent;
  bool parent_by_odometry = false;
  // FarDepth's exception: a keyframe the bridge made keeps its far depth readings as disparity
  // measurements in bundle adjustment, since it shares no point that could hold its range (the
  // generated office's doorway keyframe slid 5 m without them). Every other keyframe and every
  // frame treats them as monocular. Call with the map lock held.
  bool keeps_far_readings() const { return f->ctx->far_depth > 0 && (parent_by_odometry || odometry_parent); }
  // Depth link: point-to-plane ICP between this keyframe's depth image and the previous
  // keyframe's, made by tracking; measured T_this_prev and the information of its residuals
  // (left increment (t, w) of T_this_prev). Bundle adjustment adds it as a relative-pose
  // term, so directions the map points cannot fix (a slide and a turn towards far points
  // down a plain corridor) are held by the walls and floor.
  std::weak_ptr<KeyFrame> depth_link_to;
  SE3 depth_link_T;
  Eigen::Matrix<double, 6, 6> depth_link_information = Eigen::Matrix<double, 6, 6>::Zero();

  // Planes measured in this keyframe's depth (set by tracking before the keyframe joins the
  // map, with TrackingOptions::depth_planes) and their map planes (set by local mapping).
  std::vector<KeyFramePlane> planes;

  // Bag of words of the keypoint descriptors and its direct index, set once when the keyframe
  // enters the KeyFrameDatabase (empty before). Guarded by the map lock like the rest.
  BowVector bow;
  FeatureVector bow_features;

  // Loop edges of the essential graph (both ends hold the edge). Keyframes with a loop edge
  // are kept (`keep`), so these raw pointers never dangle.
  KeyFrameSet loop_edges;

  bool bad = false;
  bool keep = false;  // protected from culling (the first keyframe, both ends of every loop)
  // Marks so a pass visits each keyframe once.
  long local_map_mark = -1, ba_local_mark = -1, ba_fixed_mark = -1, fuse_mark = -1;

  // Unlinks this keyframe from its points, its covisibility neighbours and the spanning
  // tree (children move to its parent), and removes it from the map.
  void set_bad(Map& map);

 private:
  SE3 T_cw_, T_wc_;
  void sort_connections();
};

// Adds to `pb` the depth link of every camera in `cams` (its cameras, in order) whose other
// end is among them too. The caller holds the map lock.
void add_depth_links(const std::vector<std::shared_ptr<KeyFrame>>& cams, BundleAdjustmentProblem& pb);

}  // namespace builtscene::slam
