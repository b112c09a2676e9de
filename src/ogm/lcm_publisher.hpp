#pragma once
// Publishes the locating system's live messages over LCM (types in src/ogm/lcm/ogm_messages.lcm):
// PosesAndLaserScans batches on POSES_AND_LASER_SCANS, points-of-interest events on
// POI_EVENTS and the SLAM's loop closures on LOOP_EVENTS. Any LCM URL works: udpm:// for other processes and hosts, file://LOG?mode=w to
// record to an LCM log.
#include <memory>
#include <string>
#include <vector>

#include "ogm/poses_and_laser_scans.hpp"

namespace builtscene {

struct LcmPoiEvent {
  double time = 0;
  long frame = 0;
  Pose2D pose;
  std::string poi;
  double distance = 0;
};

// slam::LoopEvent as the message carries it (this module does not depend on the SLAM).
struct LcmLoopEvent {
  std::string stage;  // "pose_graph" | "global_ba" | "final_ba" (slam::stage_name)
  long loop = 0, frame = 0;
  double time = 0;
  long keyframe = 0, matched_keyframe = 0;
  int inliers = 0;
  SE3 correction;
  std::vector<long> keyframe_ids;
  std::vector<double> stamps;
  std::vector<SE3> T_wc;
};

class LcmPublisher {
 public:
  // InputError naming the URL when LCM cannot open it.
  explicit LcmPublisher(const std::string& url);
  ~LcmPublisher();
  LcmPublisher(const LcmPublisher&) = delete;
  LcmPublisher& operator=(const LcmPublisher&) = delete;

  void publish(const PosesAndLaserScans& batch, const std::string& channel = "POSES_AND_LASER_SCANS");
  void publish(const LcmPoiEvent& event, const std::string& channel = "POI_EVENTS");
  void publish(const LcmLoopEvent& event, const std::string& channel = "LOOP_EVENTS");
  long published() const { return published_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  long published_ = 0;
};

}  // namespace builtscene
