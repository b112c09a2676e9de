#pragma once
// What loop closing tells the rest of the system (System::subscribe_loop_events): a loop was
// closed, or the global bundle adjustment that follows a loop (or the one that ends a run) has
// been merged into the map.
// Either way every keyframe pose may have moved, so consumers that hold keyframe poses (the
// occupancy grid) rebuild from `keyframes`.
#include <vector>

#include "core/se3.hpp"

namespace builtscene::slam {

struct LoopEvent {
  enum class Stage {
    kPoseGraph,             // the loop corrected, points fused, essential graph optimized
    kGlobalBundleAdjustment, // the global BA started by that loop finished and was merged
    kFinalBundleAdjustment   // the run's final bundle adjustment (LoopCloser::refine_map) was merged
  };
  Stage stage = Stage::kPoseGraph;
  long loop = 0;              // 1-based count of closed loops this event belongs to
  long frame = 0;             // frame id (0-based count of frames given to track_rgbd) of the current keyframe
  double timestamp = 0;       // of the current keyframe
  long keyframe = 0;          // current keyframe id
  long matched_keyframe = 0;  // the keyframe it was recognised against
  int inliers = 0;            // map-point matches that accepted the loop
  // Correction of the current keyframe at detection: T_wc_corrected * T_wc_before^-1 (a world
  // motion: applied to the drifted camera it gives the corrected one).
  SE3 correction;
  struct KeyFramePose {
    long id = 0;
    double timestamp = 0;
    SE3 T_wc;
  };
  std::vector<KeyFramePose> keyframes;  // every keyframe in the map, poses after this stage
};

// The stage's name in the LOOP_EVENTS message (ogm_messages.lcm, loop_event_t.stage).
inline const char* stage_name(LoopEvent::Stage stage) {
  switch (stage) {
    case LoopEvent::Stage::kPoseGraph: return "pose_graph";
    case LoopEvent::Stage::kGlobalBundleAdjustment: return "global_ba";
    case LoopEvent::Stage::kFinalBundleAdjustment: return "final_ba";
  }
  return "?";
}

}  // namespace builtscene::slam
