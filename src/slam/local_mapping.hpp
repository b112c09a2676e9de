#pragma once
// The local mapping thread (ORB-SLAM2's LocalMapping, RGB-D): takes keyframes from tracking,
// adds their observations to the map, culls new map points that tracking rarely finds,
// fuses duplicated points with the covisible keyframes, runs local bundle adjustment and
// culls redundant keyframes.
//
// Ownership: LocalMapping owns its keyframe queue (guarded by its own queue mutex) and its
// list of recently created points; map data is touched only under the map lock. Bundle
// adjustment is solved outside the lock on a copy (see local_bundle_adjuster.hpp) and can be
// interrupted by tracking when a new keyframe arrives.
// New points come from depth (created by tracking with each keyframe) and from triangulating
// keypoints still unmatched against the neighbouring keyframes (epipolar-guided matching).
#include <atomic>
#include <condition_variable>
#include <deque>
#include <functional>
#include <list>
#include <memory>
#include <mutex>
#include <thread>

#include "core/stage_timer.hpp"
#include "slam/local_ba_disparity.hpp"
#include "slam/tracking.hpp"

namespace builtscene::slam {

class Map;
class KeyFrame;
class MapPoint;

struct LocalMappingOptions {
  PlanarMotion planar;             // a ground robot's planar motion in local BA (planar_motion.hpp)
  PlaneLandmarkOptions planes;     // plane landmarks: associated here, refined in local BA (plane_landmark.hpp)
  float min_found_ratio = 0.25f;   // new points found in fewer of the frames predicting them are culled
  int min_observations = 3;        // ... and those seen by at most 2 keyframes after 2 keyframes (RGB-D)
  float redundant_ratio = 0.9f;    // keyframe culling
  int redundant_min_observers = 3;
  int covisible_for_fusion = 10;   // ORB-SLAM: 10 for RGB-D/stereo
  int covisible_for_triangulation = 10;
  bool triangulation = true;
  // Two rays are triangulated only when their parallax is at least this many times its own
  // standard error, sqrt(sigma1^2 + sigma2^2) / f with sigma = 1 px x 1.2^level, besides
  // ORB-SLAM's fixed 1.15 degrees (0 = that alone, the default). Near 1.15 degrees two 1 px
  // rays' parallax is uncertain by ~13 %, and the range, going as 1 / parallax, is biased: 1 %
  // short on average on a grazing wall seen driving towards it, 0.3-0.6 % with 12
  // (triangulation_test.cpp). Off by default: 12 took the corridor's west leg from a 3.5 % to a
  // 1.2 % overshoot (bench/west_leg.sh), but starved whole corridor runs of points in other
  // stretches, which then stalled (ATE 57 and 77 cm on seeds 1 and 4 against 7.2 and 6.6;
  // docs/slam.md, "Triangulation only where the parallax is well above its noise").
  double min_parallax_sigmas = 0.0;
  bool bundle_adjustment = true;
  // Local BA window: the new keyframe and its most covisible neighbours (ORB-SLAM takes all
  // covisible keyframes; with Ceres on two cores that makes BA seconds long on dense maps).
  int ba_window = 10;
  // The disparity sigma of each local BA: the window's measured noise where the window is held
  // (local_ba_disparity.hpp; off by default, and where the camera file sets LocalBADisparitySigma).
  LocalBADisparityOptions ba_disparity;
};

// ORB-SLAM's keyframe culling rule: a keyframe is redundant when at least `ratio` of its map
// points (for RGB-D only close ones count) are seen by at least `min_observers` other
// keyframes at the same or a finer scale (level <= own level + 1). The first keyframe and
// protected ones are never redundant. Requires the map lock.
bool is_redundant_keyframe(const KeyFrame& kf, float ratio = 0.9f, int min_observers = 3);

class LocalMapping : public KeyFrameSink {
 public:
  LocalMapping(Map& map, LocalMappingOptions options, StageTimer* timer = nullptr);
  ~LocalMapping() override;

  // Starts the thread. Without start(), keyframes wait in the queue until the owner calls
  // run_pending() (tests, deterministic runs); tracking inserts while holding the map lock,
  // so processing cannot happen inside insert_keyframe.
  void start();
  void run_pending();
  // Processes what is queued, then stops and joins the thread.
  void finish();

  void insert_keyframe(std::shared_ptr<KeyFrame> kf) override;
  bool accepts_keyframes() const override { return idle_.load(); }
  std::size_t queue_size() const override;
  void interrupt_bundle_adjustment() override { abort_ba_ = true; }

  // Before the first keyframe is queued (the queue orders it before any use in BA).
  void set_planar(const PlanarMotion& planar) { opt_.planar = planar; }
  // Every keyframe that comes out of processing still good goes on to this (loop closing's
  // queue). Called in the mapping thread (or by run_pending()); set before start().
  void set_keyframe_output(std::function<void(std::shared_ptr<KeyFrame>)> output) { output_ = std::move(output); }

  // Loop closing's handshake. request_pause() interrupts a running BA; the thread then parks
  // between two keyframes, holding no lock, until resume(). wait_until_paused() returns once
  // it is parked, or at once when no thread runs (inline mode, or after finish()). Keyframes
  // inserted meanwhile wait in the queue. Callers must not hold the map lock while waiting.
  void request_pause();
  void wait_until_paused();
  void resume();

  struct Stats {
    long keyframes_processed = 0;
    long keyframes_culled = 0;
    long points_culled = 0;
    long points_fused = 0;
    long points_triangulated = 0;
    long bundle_adjustments = 0;
    long bundle_adjustments_aborted = 0;
    long bundle_adjustments_measured_disparity = 0;  // weighed at a measured sigma (0.1 px .. DisparitySigma)
    long bundle_adjustments_not_held = 0;            // kept DisparitySigma: a free camera held by too few shared points
    double ba_disparity_sigma_sum = 0;               // over the BAs with a measured sigma (for the mean)
    std::size_t max_queue = 0;
  };
  Stats stats() const;

 private:
  Map& map_;
  LocalMappingOptions opt_;
  StageTimer* timer_;

  mutable std::mutex queue_mutex_;
  std::condition_variable queue_cv_;
  std::deque<std::shared_ptr<KeyFrame>> queue_;
  bool stop_ = false;
  std::thread thread_;
  std::atomic<bool> idle_{true};
  std::atomic<bool> abort_ba_{false};
  std::function<void(std::shared_ptr<KeyFrame>)> output_;
  // Pause handshake, guarded by queue_mutex_.
  std::condition_variable pause_cv_;
  bool pause_requested_ = false, paused_ = false, running_ = false;

  std::list<std::shared_ptr<MapPoint>> recent_points_;
  mutable std::mutex stats_mutex_;
  Stats stats_;

  void run();
  void process(const std::shared_ptr<KeyFrame>& kf);
  void insert_into_map(KeyFrame& kf);
  void cull_recent_points(const KeyFrame& kf);
  void fuse_with_neighbours(KeyFrame& kf);
  void triangulate_with_neighbours(KeyFrame& kf);
  void local_bundle_adjustment(KeyFrame& kf);
  void cull_keyframes(KeyFrame& kf);
  bool queue_empty() const;
};

}  // namespace builtscene::slam
