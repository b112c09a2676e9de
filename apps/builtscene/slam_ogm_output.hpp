#pragma once
// `slam --ogm-out`: the occupancy grid built live beside the feature map (the source's
// OGM-enhanced SLAM). For every new keyframe the SLAM's PosesAndLaserScans batch of one updates
// the grid; every N keyframes, after every loop closure and at the end, the batch of all
// keyframes with their optimized poses rebuilds it. Batches and the SLAM's loop events also go
// out over LCM (--lcm URL).
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include "ogm/lcm_publisher.hpp"
#include "ogm/occupancy_grid_mapper.hpp"
#include "ogm/poses_and_laser_scans.hpp"
#include "slam/system.hpp"

namespace builtscene::app {

struct SlamOgmOptions {
  std::filesystem::path out;       // MAP: writes MAP.yaml, MAP.pgm, MAP.state, MAP.png
  std::string world = "auto";      // auto: floor found in the first keyframe's depth; camera: first camera level
  double camera_height = 1.0;      // world = camera: first camera above the floor, m
  PosesAndLaserScansOptions batches;
  std::string lcm_url;             // empty: no LCM
  std::filesystem::path frames;    // folder for a picture of the grid after each keyframe (empty: none)
  // Folder for the grid just before and just after each loop-closure rebuild, each with the
  // keyframe poses it was built from, so the rebuild can be scored (empty: none).
  std::filesystem::path loop_snapshots;
  bool enabled() const { return !out.empty() || !lcm_url.empty() || !frames.empty() || !loop_snapshots.empty(); }
};

class SlamOgmOutput {
 public:
  SlamOgmOutput(SlamOgmOptions options, const PinholeCamera& camera);

  // Registers for the SLAM's loop events: after each loop closure (and after the global BA
  // that follows it) the grid is rebuilt from every keyframe's optimized pose. Call once,
  // before the first frame; `system` must outlive this object's use of it.
  void subscribe(slam::System& system);
  // After each tracked frame. `depth` is the frame's depth (CV_32F metres).
  void after_frame(slam::System& system, const slam::TrackingOutcome& outcome, double timestamp,
                   const cv::Mat& depth);
  // After the SLAM has shut down: the final rebuild, then the files. JSON summary.
  nlohmann::json finish(slam::System& system);

 private:
  SlamOgmOptions options_;
  PinholeCamera camera_;
  std::optional<PosesAndLaserScansEmitter> emitter_;
  OccupancyGridMapper mapper_;
  std::unique_ptr<LcmPublisher> lcm_;
  std::vector<Pose2D> keyframe_poses_;
  std::map<double, SE3> grid_poses_;  // the SLAM-world pose each keyframe in the grid was drawn with
  long batches_ = 0, full_batches_ = 0, keyframes_drawn_ = 0;
  LaserScan last_scan_;
  long loop_rebuilds_ = 0;
  // Loop events arrive in the loop-closing thread; the emitter and the grid belong to the
  // tracking thread, so events only raise this count (guarded by loop_mutex_) and
  // after_frame() rebuilds.
  std::mutex loop_mutex_;
  long loop_events_pending_ = 0;
  // With --lcm the events themselves go out on LOOP_EVENTS, published from the tracking
  // thread (after_frame, finish) like every other message of this publisher.
  std::vector<LcmLoopEvent> lcm_events_pending_;
  void publish_loop_events();
  void rebuild_after_loops(slam::System& system);

  void consume(const PosesAndLaserScans& batch);
  void write_snapshot(const std::string& name) const;
};

}  // namespace builtscene::app
