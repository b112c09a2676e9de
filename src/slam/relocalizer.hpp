#pragma once
// Relocalization of a frame against the map (ORB-SLAM2's Tracking::Relocalization, written
// here on OpenCV and the project's pose optimizer): bag-of-words candidates from the
// KeyFrameDatabase, descriptor matching through the vocabulary's direct index, EPnP in
// RANSAC (cv::solvePnPRansac), motion-only bundle adjustment, and a guided search that
// projects the candidate's local map into the frame for more matches. A pose is accepted
// with at least `min_inliers` inliers, or with `min_inliers_twice` when the frame before found
// the same pose (RGB-D maps with sparse keyframes often leave a right place at 40-49).
//
// Runs in the tracking thread with the map lock held (it reads keyframes and map points).
#include <memory>

#include "slam/frame.hpp"

namespace builtscene::slam {

class KeyFrame;
class KeyFrameDatabase;

struct RelocalizerOptions {
  int min_bow_matches = 15;     // per candidate, before RANSAC
  int min_inliers = 50;         // accepted pose
  int ransac_iterations = 300;
  float ransac_reprojection_px = 4.0f;
  int max_candidates = 30;      // the best BoW groups tried per frame
  // A place seen again by two consecutive frames: a pose with at least this many inliers
  // (short of min_inliers) is accepted when the frame before gave one within the motion
  // below. Two independent fits agreeing are the check the missing inliers would have been
  // (0 = off: ORB-SLAM2's single-frame rule only).
  int min_inliers_twice = 30;
  double twice_max_m = 0.10, twice_max_deg = 5.0;
};

class Relocalizer {
 public:
  Relocalizer(const KeyFrameDatabase& database, RelocalizerOptions options = {});

  // On success sets frame's pose and matches (outliers removed) and returns the candidate
  // keyframe it was found from; null otherwise (frame's matches cleared). Caller holds the
  // map lock.
  std::shared_ptr<KeyFrame> relocalize(Frame& frame) const;

  struct Stats {
    long attempts = 0, successes = 0;
  };
  const Stats& stats() const { return stats_; }

 private:
  const KeyFrameDatabase& db_;
  RelocalizerOptions opt_;
  mutable Stats stats_;
  // The last frame's best pose short of min_inliers (for min_inliers_twice).
  struct Tentative {
    long frame_id = -1;
    SE3 T_cw;
  };
  mutable Tentative last_tentative_;

  // Matches more of the candidate's local map by projection; returns new matches.
  int search_local_map(Frame& frame, const KeyFrame& candidate, float th) const;
};

}  // namespace builtscene::slam
