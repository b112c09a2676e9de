#pragma once
// The SLAM facade: give it RGB-D frames, get poses, trajectories and statistics. It owns the
// map, the tracker (run in the caller's thread) and the local-mapping thread; a loop-closing
// thread (issue 5) will be owned here too.
//
//   System slam(settings);
//   for (...) slam.track_rgbd(bgr, depth_m, t);
//   slam.shutdown();
//   write_tum_trajectory("traj.txt", slam.trajectory());
#include <filesystem>
#include <memory>

#include <opencv2/core.hpp>

#include "core/camera.hpp"
#include "core/stage_timer.hpp"
#include "features/orb_extractor.hpp"
#include "io/trajectory.hpp"
#include "slam/local_mapping.hpp"
#include "slam/map.hpp"
#include "slam/tracking.hpp"

namespace builtscene {
class BowVocabulary;
}

namespace builtscene::slam {

struct SystemOptions {
  OrbExtractorOptions orb;
  TrackingOptions tracking;
  LocalMappingOptions mapping;
  bool mapping_thread = true;  // false: local mapping runs inline after each keyframe (deterministic)
  // Bag-of-words vocabulary for the keyframe database and relocalization. Empty: the
  // shipped default (default_vocabulary_path()); when that is missing too, a lost frame
  // is only matched against the last reference keyframe.
  std::filesystem::path vocabulary;
  bool relocalization = true;
};

// The shipped ORB vocabulary: the source tree's data/vocab/orb_k10_L4.bsvoc, else the
// installed copy; empty when neither exists.
std::filesystem::path default_vocabulary_path();

class KeyFrameDatabase;
class Relocalizer;

class System {
 public:
  System(const RgbdCameraSettings& settings, SystemOptions options = {});
  ~System();
  System(const System&) = delete;
  System& operator=(const System&) = delete;

  // Colour (8-bit BGR, or RGB when the settings say so) or grayscale image, depth in metres
  // (CV_32F, 0 = none; an empty or mismatched depth image is treated as no depth).
  TrackingOutcome track_rgbd(const cv::Mat& image, const cv::Mat& depth_m, double timestamp);

  // Lets local mapping finish its queue and stops it. Idempotent.
  void shutdown();

  // Poses (camera in world) of every tracked frame, through its reference keyframe's final
  // pose; lost frames are left out.
  Trajectory trajectory() const;
  Trajectory keyframe_trajectory() const;
  std::size_t keyframe_count() const;
  std::size_t map_point_count() const;
  LocalMapping::Stats mapping_stats() const { return mapping_->stats(); }
  TrackingState state() const { return tracker_->state(); }
  StageTimer& timer() { return timer_; }
  const FrameContext& context() const { return *ctx_; }

  // Place recognition: null / empty without a vocabulary. The database is guarded by the
  // map lock (see keyframe_database.hpp).
  const KeyFrameDatabase* keyframe_database() const { return database_.get(); }
  std::shared_ptr<const BowVocabulary> vocabulary() const { return vocabulary_; }
  // Frame ids (0-based count of frames passed to track_rgbd) where relocalization succeeded.
  std::vector<long> relocalized_frames() const { return tracker_->relocalized_frames(); }

 private:
  RgbdCameraSettings settings_;
  SystemOptions options_;
  StageTimer timer_;
  OrbExtractor extractor_;
  std::shared_ptr<const FrameContext> ctx_;
  Map map_;
  std::unique_ptr<LocalMapping> mapping_;
  std::unique_ptr<Tracker> tracker_;
  std::shared_ptr<const BowVocabulary> vocabulary_;
  std::unique_ptr<KeyFrameDatabase> database_;
  std::unique_ptr<Relocalizer> relocalizer_;
  long next_frame_id_ = 0;
  bool shut_down_ = false;
};

}  // namespace builtscene::slam
