#pragma once
// The SLAM facade: give it RGB-D frames, get poses, trajectories and statistics. It owns the
// map, the tracker (run in the caller's thread), the local-mapping thread and the
// loop-closing thread (with its global-BA thread), see loop_closer.hpp.
//
//   System slam(settings);
//   slam.load_map("old.map");              // optional: extend or localize in a saved map
//   slam.set_mode(Mode::kLocalization);    // optional, any time between frames
//   for (...) slam.track_rgbd(bgr, depth_m, t);
//   slam.shutdown();
//   write_tum_trajectory("traj.txt", slam.trajectory());
//   slam.save_map("new.map");
//
// Modes: in SLAM mode tracking makes keyframes and local mapping grows the map (a new one,
// or a loaded one once tracking has relocalized in it). In localization mode no keyframe or
// point is added: tracking only matches against the map, and local mapping, getting no
// keyframes, finishes its queue and idles. After a map is loaded, or whenever tracking is
// lost, each frame is relocalized (bag-of-words relocalizer when a vocabulary is loaded).
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include <opencv2/core.hpp>

#include "core/camera.hpp"
#include "core/stage_timer.hpp"
#include "features/feature_extractor.hpp"
#include "features/orb_extractor.hpp"
#include "io/trajectory.hpp"
#include "slam/local_mapping.hpp"
#include "slam/floor_plane.hpp"
#include "slam/loop_closer.hpp"
#include "slam/loop_event.hpp"
#include "slam/map.hpp"
#include "slam/map_serializer.hpp"
#include "slam/mode_plan.hpp"
#include "slam/saft_learning.hpp"
#include "slam/tracking.hpp"

namespace builtscene {
class BowVocabulary;
}

namespace builtscene::slam {

struct SystemOptions {
  OrbExtractorOptions orb;
  // Descriptor of every feature (tracking, mapping, place recognition, saved maps): ORB's
  // binary one or SAFT's learned one (ORB's keypoints; docs/saft.md). SAFT: the weights in
  // `saft_weights` (empty: the shipped ones) and online learning as `saft_learning` says.
  DescriptorChoice descriptor = DescriptorChoice::kOrb;
  std::filesystem::path saft_weights;
  SaftLearningOptions saft_learning;
  TrackingOptions tracking;
  LocalMappingOptions mapping;
  bool mapping_thread = true;  // false: local mapping runs inline after each keyframe (deterministic)
  // Bag-of-words vocabulary for the keyframe database and relocalization. Empty: the
  // shipped default (default_vocabulary_path()); when that is missing too, a lost frame
  // is only matched against the last reference keyframe.
  std::filesystem::path vocabulary;
  bool relocalization = true;
  // Loop closing (needs the vocabulary). With mapping_thread == false it runs inline after
  // local mapping, global BA included (deterministic).
  bool loop_closing = true;
  LoopClosingOptions loop;
  // A ground robot's planar motion (planar_motion.hpp), off by default; System copies it into
  // the tracking, local mapping and loop closing options.
  PlanarMotion planar;
  // Plane landmarks from the keyframes' depth (plane_landmark.hpp), off by default; copied
  // likewise.
  PlaneLandmarkOptions planes;
};

// A fingerprint of a vocabulary, stored in saved maps (never 0).
std::uint64_t vocabulary_checksum(const BowVocabulary& vocabulary);

// The shipped vocabulary for a descriptor: the source tree's data/vocab/orb_k10_L4.bsvoc
// (ORB) or saft_k10_L4.bsvoc (SAFT, made with the shipped weights), else the installed copy;
// empty when neither exists.
std::filesystem::path default_vocabulary_path(DescriptorChoice descriptor = DescriptorChoice::kOrb);

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

  // Lets local mapping finish its queue and stops it, then loop closing (with its final bundle
  // adjustment when the run closed a loop: LoopCloser::refine_map). Idempotent.
  void shutdown();

  // Replaces the (empty) map by a saved one; tracking then relocalizes. Only before the first
  // frame. InputError on a bad file or a map made with another camera or vocabulary.
  MapFileInfo load_map(const std::filesystem::path& path);
  // Saves the map once local mapping has processed its queue (call after shutdown(), or
  // between frames: it waits for the queue).
  MapFileInfo save_map(const std::filesystem::path& path);

  // Takes effect from the next frame. Switching to localization with no map does nothing
  // useful (an empty map is not initialized in localization mode).
  void set_mode(Mode mode, const std::string& reason = "api");
  Mode mode() const { return mode_; }
  const std::vector<ModeSwitch>& mode_switches() const { return mode_switches_; }
  // Planar motion (SystemOptions::planar): its floor normal is measured in the depth of the
  // new map's first keyframe when it sees the floor (floor_plane.hpp), else taken from the
  // pitch; a loaded map keeps the pitch's.
  const PlanarMotion& planar() const { return options_.planar; }
  const std::optional<FloorPlane>& floor_plane() const { return floor_; }
  // Test hook tried before the relocalizer on lost frames (see Tracker::set_relocalization_hook).
  void set_relocalization_hook(Tracker::RelocalizationHook hook) { tracker_->set_relocalization_hook(std::move(hook)); }
  long first_relocalized_frame() const {  // -1: none yet
    const auto& f = tracker_->relocalized_frames();
    return f.empty() ? -1 : f.front();
  }

  // Camera-to-world pose of the last frame passed to track_rgbd, if it was tracked.
  std::optional<SE3> last_pose() const;

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
  std::shared_ptr<const FrameContext> context_ptr() const { return ctx_; }
  // The map itself, for relocalizers and inspection; follow its lock rule (map.hpp).
  Map& map() { return map_; }

  // Place recognition: null / empty without a vocabulary. The database is guarded by the
  // map lock (see keyframe_database.hpp).
  const KeyFrameDatabase* keyframe_database() const { return database_.get(); }
  std::shared_ptr<const BowVocabulary> vocabulary() const { return vocabulary_; }
  // Frame ids (0-based count of frames passed to track_rgbd) where relocalization succeeded.
  std::vector<long> relocalized_frames() const { return tracker_->relocalized_frames(); }
  // Localization mode: frames on visual odometry whose pose came from relocalization instead.
  long odometry_relocalizations() const { return tracker_->odometry_relocalizations(); }
  // Frames on which relocalization was tried (successful or not); 0 without place recognition.
  long relocalization_attempts() const;
  // Frames whose pose came from RGB-D odometry because features could not hold it.
  long depth_odometry_frames() const { return tracker_->depth_odometry_frames(); }
  long depth_odometry_prior_frames() const { return tracker_->depth_odometry_prior_frames(); }

  // Loop closures. A subscriber is called for every LoopEvent (a loop corrected, then its
  // global BA merged) in the loop-closing or global-BA thread (the caller's thread in inline
  // mode), without the map lock: it may call this System's const queries, and should hand
  // heavy work to its own thread (slam_ogm_output.cpp queues the event for the tracking
  // thread). Subscribe before the first frame.
  using LoopEventSubscriber = std::function<void(const LoopEvent&)>;
  void subscribe_loop_events(LoopEventSubscriber subscriber);
  // Every event so far, in order.
  std::vector<LoopEvent> loop_events() const;
  LoopCloser::Stats loop_closing_stats() const;
  bool loop_closing_enabled() const { return loop_closer_ != nullptr; }
  // SAFT online learning; null with ORB descriptors.
  const SaftLearning* saft_learning() const { return learning_.get(); }
  SaftExtractor* saft_extractor() { return saft_; }

 private:
  RgbdCameraSettings settings_;
  SystemOptions options_;
  StageTimer timer_;
  std::unique_ptr<FeatureExtractor> extractor_;
  SaftExtractor* saft_ = nullptr;  // extractor_ when it is SAFT's
  std::unique_ptr<SaftLearning> learning_;
  std::shared_ptr<const FrameContext> ctx_;
  Map map_;
  std::unique_ptr<LocalMapping> mapping_;
  std::unique_ptr<Tracker> tracker_;
  std::shared_ptr<const BowVocabulary> vocabulary_;
  std::unique_ptr<KeyFrameDatabase> database_;
  std::unique_ptr<Relocalizer> relocalizer_;
  std::unique_ptr<LoopCloser> loop_closer_;
  mutable std::mutex events_mutex_;  // guards events_ and subscribers_
  std::vector<LoopEvent> events_;
  std::vector<LoopEventSubscriber> subscribers_;
  void on_loop_event(const LoopEvent& event);
  void floor_from_this_frame(const cv::Mat& depth_m);
  long next_frame_id_ = 0;
  bool shut_down_ = false;
  bool floor_settled_ = false;
  Eigen::Vector3d planar_guess_ = Eigen::Vector3d::Zero();  // the up axis the given pitch implies
  std::optional<FloorPlane> floor_;  // planar motion's floor, in the new map's first keyframe
  Mode mode_ = Mode::kSlam;
  std::vector<ModeSwitch> mode_switches_;
  double last_timestamp_ = 0;
  long culled_seen_ = 0;

  SE3 record_pose(const Tracker::FrameRecord& r) const;  // T_cw; map lock held
};

}  // namespace builtscene::slam
