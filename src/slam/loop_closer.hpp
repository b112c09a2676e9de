#pragma once
// The loop-closing thread (ORB-SLAM2's LoopClosing for RGB-D, written here; SE3 instead of
// Sim3 because depth fixes the scale). For every keyframe local mapping has finished:
//
//  1. detection: the KeyFrameDatabase's loop candidates (not covisible with the keyframe,
//     scoring at least the keyframe's lowest score against its covisible keyframes), kept
//     only when temporally consistent (loop_consistency.hpp);
//  2. verification: bag-of-words matches between the candidate's map points and the
//     keyframe's keypoints, an SE3 by RANSAC on their 3D-3D pairs, motion-only BA of the
//     keyframe against those points, a guided projection search over the candidate's
//     covisible keyframes, acceptance by inlier count;
//  3. correction: local mapping paused; the keyframe and its covisible keyframes moved by the
//     correction with their points; duplicated points fused with the loop side; the loop edge
//     added; pose-graph optimization over the essential graph (spanning tree, covisibility
//     edges with weight >= 100, loop edges); every point moved with the keyframe that
//     corrected it (or its reference keyframe); local mapping resumed; a LoopEvent;
//  4. global bundle adjustment in its own thread (aborted by the next loop), merged into the
//     map with local mapping paused; keyframes and points added since move with their
//     spanning-tree parent / reference keyframe; a second LoopEvent.
//
// Ownership and locks: the LoopCloser owns its keyframe queue (own mutex), its consistency
// state and the global-BA thread. Map and KeyFrameDatabase state is touched only under
// Map::mutex(). Detection and verification hold the map lock (like tracking a frame); the
// correction holds it from the first moved pose to the last moved point, including the
// pose-graph solve, so tracking never sees a half-corrected map. Global BA solves on a copy
// without the lock. Lock order: local mapping is paused (LocalMapping::request_pause /
// wait_until_paused, with no lock held) before the map lock is taken, never the other way.
#include <atomic>
#include <condition_variable>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>

#include "core/stage_timer.hpp"
#include "slam/bridge_links.hpp"
#include "slam/plane_landmark.hpp"
#include "slam/loop_consistency.hpp"
#include "slam/loop_event.hpp"

namespace builtscene::slam {

class Map;
class KeyFrame;
class MapPoint;
class KeyFrameDatabase;
class LocalMapping;

struct LoopClosingOptions {
  PlanarMotion planar;  // a ground robot's planar motion in global BA (planar_motion.hpp)
  PlaneLandmarkOptions planes;  // plane landmarks in global BA (plane_landmark.hpp)
  int min_keyframes = 10;       // map size before loops are searched, and keyframes between two loops (ORB-SLAM2)
  int min_keyframe_gap = 20;    // candidates at least this many keyframe ids older (not the recent past)
  int consistency = 3;          // ORB-SLAM2's covisibility consistency threshold
  // At the end of a run (finish), the candidates that fell one short of `consistency` at one
  // of the last close_at_end_window checked keyframes (the newest such keyframe) are verified
  // and, if they pass every geometric check, closed: no later keyframe can confirm them. A
  // robot that ends where it started would otherwise leave its last lap open (the generated
  // corridor: the start is recognised a keyframe or two before the data ends).
  bool close_at_end = true;
  int close_at_end_window = 3;
  int min_bow_matches = 20;     // per candidate (ORB-SLAM2)
  double ransac_inlier_m = 0.08;  // 3D-3D residual; Kinect depth noise at 4 m is ~3 cm per point
  int ransac_min_inliers = 15;
  int ransac_iterations = 300;
  int min_refined_inliers = 20;   // after motion-only BA on the RANSAC inliers (ORB-SLAM2: 20)
  int min_inliers = 40;           // after the guided search (ORB-SLAM2: 40)
  float guided_search_radius = 4.0f;
  float fuse_radius = 4.0f;       // ORB-SLAM2 fuses loop points with th = 4
  // A keyframe that already shares points with keyframes older than min_keyframe_gap sits in
  // a part of the map an earlier loop (or re-observation) has tied together; a loop that
  // would move it further than this away from those links contradicts them. Seen on the
  // generated lab-room: a look-alike place 4.3 m away gave a 5.9 m "correction" with 95
  // inliers in the second lap (docs/slam.md).
  double max_anchored_correction_m = 0.5;
  double max_anchored_correction_deg = 5.0;
  // "Came back to": the path from the older keyframe to this one is longer than
  // revisit_path_ratio x their distance + revisit_margin_m (a lap of the lab room: ~17 m of
  // path for < 1 m apart; a corridor seen far ahead: path = distance).
  double revisit_path_ratio = 2.0;
  double revisit_margin_m = 2.0;
  // Any loop: the correction must be a drift the path between the two keyframes could have
  // built up: at most base + per_metre x path length (the keyframe centres from the matched
  // keyframe to this one, in id order). Seen on the generated lab room carried by hand (900
  // frames, 1.1 cm ATE without loops): look-alike places in the first lap gave "loops" of
  // 4.0 m / 152 deg and 4.6 m / 124 deg after ~10 m of walking.
  double max_correction_base_m = 0.3;
  double max_correction_per_metre = 0.1;
  double max_correction_base_deg = 5.0;
  double max_correction_deg_per_metre = 1.0;
  int strong_covisibility = 100;  // essential-graph covisibility edges
  // Weight of a tree edge to a keyframe made on the depth-odometry bridge (others weigh 1):
  // frame-to-frame ICP drifts more than poses held by shared map points, so a loop's error
  // goes there first.
  double odometry_edge_weight = 0.1;
  int pose_graph_iterations = 20;
  bool global_bundle_adjustment = true;
  int global_ba_iterations = 10;  // Ceres iterations (robust phase; as many after outlier classification)
  int global_ba_min_shared_points = 10;  // fewer: the keyframe follows its parent instead
  // After the run (refine_map, from System::shutdown), when a loop was closed: one more global
  // bundle adjustment over the whole map, the depth readings weighed (and judged in its
  // outlier test) by the disparity noise the map's own readings show (disparity_noise.hpp),
  // never looser than the global BA's sigma nor tighter than final_ba_min_disparity_sigma
  // (pixels). Ends a run, so it cannot change which loops close. docs/slam.md, "The final
  // bundle adjustment".
  bool final_bundle_adjustment = true;
  int final_ba_iterations = 20;  // in each of its two phases
  double final_ba_min_disparity_sigma = 0.02;
  // Relative-pose terms across stretches the depth-odometry bridge carried (bridge_links.hpp).
  BridgeLinkOptions bridge_links;
};

class LoopCloser {
 public:
  using EventSink = std::function<void(const LoopEvent&)>;

  // `mapping` (may be null) is paused during corrections; `threaded` runs global BA in its
  // own thread (else inline, for deterministic runs).
  LoopCloser(Map& map, const KeyFrameDatabase& database, LocalMapping* mapping, LoopClosingOptions options,
             bool threaded, StageTimer* timer = nullptr);
  ~LoopCloser();
  LoopCloser(const LoopCloser&) = delete;
  LoopCloser& operator=(const LoopCloser&) = delete;

  // Called in the loop-closing thread (or the global-BA thread, or the caller's thread in
  // inline mode), without the map lock; keep it short. Set before start().
  void set_event_sink(EventSink sink) { sink_ = std::move(sink); }
  // Before the first keyframe is inserted (the queue orders it before any use in BA).
  void set_planar(const PlanarMotion& planar) { opt_.planar = planar; }

  void start();
  void insert_keyframe(std::shared_ptr<KeyFrame> kf);
  // Without start(): processes the queue in the caller's thread (global BA inline too).
  void run_pending();
  // Processes what is queued, waits for a running global BA, stops the threads.
  void finish();
  // After finish(): the final bundle adjustment (LoopClosingOptions::final_bundle_adjustment)
  // when this run closed a loop; once. Sends a kFinalBundleAdjustment event.
  void refine_map();

  struct Stats {
    long keyframes_checked = 0;
    long consistent_candidates = 0;  // candidates that passed the consistency check
    // ... of which checked at the end of the run one short of it (close_at_end), and the loops
    // they closed
    long end_candidates = 0, loops_closed_at_end = 0;
    long rejected = 0;               // ... and failed geometric verification
    long rejected_anchored = 0;      // ... of which verified, but contradicting old links
    long rejected_implausible = 0;   // ... of which verified, but larger than the path could drift
    long loops = 0;
    long points_fused = 0;
    long planes_merged = 0;  // plane landmarks joined after corrections (refit_and_merge_planes)
    long global_ba_runs = 0, global_ba_aborted = 0, global_ba_merged = 0;
    // The final bundle adjustment (refine_map): 1 when it ran (final_ba_aborted: 1 when it then
    // failed to solve or was aborted, and the map was left as it was), and the disparity sigma it
    // used (pixels) with the robust spread it measured (0 when it did not run).
    long final_ba_runs = 0, final_ba_aborted = 0;
    double final_ba_disparity_sigma = 0, final_ba_measured_disparity_sigma = 0;
    // The most connected parts any loop's essential graph fell into: 1 when every keyframe is
    // tied to the rest (a part no edge joins would move rigidly and leave a step).
    long max_pose_graph_parts = 0;
  };
  Stats stats() const;

 private:
  struct LoopMatch;

  Map& map_;
  const KeyFrameDatabase& db_;
  LocalMapping* mapping_;
  LoopClosingOptions opt_;
  bool threaded_;
  bool refined_ = false;
  StageTimer* timer_;
  EventSink sink_;

  mutable std::mutex queue_mutex_;
  std::condition_variable queue_cv_;
  std::deque<std::shared_ptr<KeyFrame>> queue_;
  bool stop_ = false;
  std::thread thread_;

  LoopConsistency consistency_;  // loop-closing thread only
  // The newest keyframe whose candidates fell one short of consistency, and those candidates
  // (close_at_end); cleared when a loop closes after it.
  std::weak_ptr<KeyFrame> end_query_;
  std::vector<std::weak_ptr<KeyFrame>> end_candidates_;
  long consistency_checks_ = 0;  // keyframes checked for consistency so far
  long end_check_ = 0;           // ... when end_query_ was
  long last_loop_kf_id_ = -1000000;
  long loops_ = 0;

  std::thread gba_thread_;
  std::atomic<bool> abort_gba_{false};

  mutable std::mutex stats_mutex_;
  Stats stats_;

  void run();
  void process(const std::shared_ptr<KeyFrame>& kf);
  // Map lock held.
  std::unique_ptr<LoopMatch> detect(KeyFrame& kf);
  std::unique_ptr<LoopMatch> verify(KeyFrame& kf, KeyFrame& candidate);
  // The first candidate that verify accepts, counting each tried (stats: consistent_candidates,
  // end_candidates when at_end, rejected).
  std::unique_ptr<LoopMatch> verify_first(KeyFrame& kf, const std::vector<KeyFrame*>& candidates, bool at_end);
  void correct(const std::shared_ptr<KeyFrame>& kf, const LoopMatch& match);
  void close_at_end();
  void stop_global_ba();
  // final_pass: refine_map's adjustment (its own sigma and iterations, its own event).
  void run_global_ba(long loop, long keyframe, long matched, bool final_pass = false);
  void emit(const LoopEvent& e) const;
  void add_time(const char* stage, std::chrono::steady_clock::time_point start) const;
};

}  // namespace builtscene::slam
