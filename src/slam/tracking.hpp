#pragma once
// The tracking thread's work for one frame (ORB-SLAM2's Tracking for RGB-D): initialization
// from the first frame with enough depth, the constant-velocity motion model with projection
// search, the fallback of matching against the reference keyframe, tracking of the local
// map, pose optimization, and the keyframe decision. It runs in the thread that calls
// System::track_rgbd (the caller's thread is the tracking thread, as in ORB-SLAM).
//
// Ownership: the Tracker owns the current and last Frame and its per-frame records; it takes
// the map lock for the whole of a frame's matching and optimization (see map.hpp).
#include <functional>
#include <deque>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "core/stage_timer.hpp"
#include "slam/depth_odometry.hpp"
#include "slam/frame.hpp"
#include "slam/matcher.hpp"
#include "slam/planar_motion.hpp"
#include "slam/plane_landmark.hpp"
#include "slam/pose_optimizer.hpp"

namespace builtscene::slam {

class Map;
class KeyFrame;
class KeyFrameSink;
class Relocalizer;

struct TrackingOptions {
  // Keypoints needed to start a map. ORB-SLAM2 asks for 500 of its 1000, but there the budget
  // fills with sensor-noise corners on plain surfaces; with the noise-adaptive FAST threshold
  // (orb_extractor.hpp) a real view of the generated lab room gives 440-480 true corners,
  // ~90 % with depth, and waited 15 frames for 500.
  int min_init_points = 300;
  int min_init_depth_points = 100; // ... of which with depth
  int max_frames_between_kf = 30;  // ORB-SLAM: the camera fps
  int min_frames_between_kf = 0;
  int min_tracked_close = 100;     // "need close points" rule for RGB-D
  int min_untracked_close = 70;
  int new_kf_min_points = 100;     // new points from depth per keyframe (all close ones at least)
  int min_local_map_inliers = 30;
  // After the depth-odometry bridge carried a frame: the local map searched from its pose is
  // kept when it gives at least this many map inliers (tracking.cpp). 0 = off; -1 = 10 with
  // planar motion, else off (the office got worse in a single run, docs/slam.md).
  int bridge_local_map_inliers = -1;
  float motion_model_radius = 15.0f;  // ORB-SLAM RGB-D
  float local_map_radius = 3.0f;
  std::size_t recovery_keyframes = 5;
  std::size_t max_keyframe_queue = 3;       // keyframes waiting for local mapping (ORB-SLAM)
  std::size_t max_keyframe_queue_weak = 6;  // ... while tracking is weak
  int weak_tracking_inliers = 100;          // below: keyframes and odometry use every depth point  // when lost: reference's neighbours and newest keyframes tried
  // Depth links between consecutive keyframes (KeyFrame::depth_link_*; local and global BA add them):
  // ICP information per residual relative to independent 1 cm noise, times the weight. With
  // the motion prior below (weight 0.1) the corridor goes 0.805 -> 0.259 m and the lab room
  // 1.89 -> 0.90 cm, but the real kitchen (depth not registered to colour) 4.99 -> 6.40 cm
  // and the office 12.3 -> 21.0 cm, so both are off by default: docs/slam.md, 2026-12-03.
  bool depth_links = false;
  double depth_link_weight = 1.0;
  // The motion model's prediction as a prior in the frame's pose optimization
  // (PoseOptimizerOptions::prior_*), only when the pose came from the motion model.
  bool motion_prior = false;
  double motion_prior_sigma_m = 0.01, motion_prior_sigma_rad = 0.005;
  // The frame's depth aligned to the newest keyframe's (ICP from the motion model's pose) as
  // a prior with the ICP's information times this weight in local-map tracking's pose
  // optimization (0 = off): where a few far features leave a slide and a turn alike (a
  // corridor's end wall, the only texture in view under colour noise), the walls' and the
  // floor's depth tell them apart. Only after a frame with fewer local-map inliers than
  // depth_prior_below_inliers (0 = every frame): where the features are many the prior's
  // own errors (depth not registered to colour on real sensors) cost more than it gives.
  // Measured: docs/slam.md, "The depth prior". Localization mode makes no keyframes: there
  // the last frame's depth is the reference, and only while the last frame matched at least
  // min_local_map_inliers map points (docs/slam.md, "Localization in a long corridor").
  double depth_prior_weight = 0.1;
  int depth_prior_below_inliers = 100;
  // Localization mode, when the covisible local map has too few points in view: the nearest
  // keyframes within this radius whose optical axes are within this angle of the frame's.
  double nearby_keyframe_radius_m = 3.0;
  double nearby_keyframe_max_angle_deg = 45.0;
  std::size_t nearby_keyframes = 20;
  // A ground robot's planar motion (off by default; planar_motion.hpp): a prior in local-map
  // tracking's pose optimization.
  PlanarMotion planar;
  // Plane landmarks (plane_landmark.hpp): each new keyframe's depth planes are measured here.
  PlaneLandmarkOptions planes;
};

enum class TrackingState { kNotInitialized, kOk, kLost };
const char* to_string(TrackingState s);

struct TrackingOutcome {
  TrackingState state = TrackingState::kNotInitialized;
  int inliers = 0;              // map points matched after local-map tracking
  int keypoints = 0;            // features extracted from the frame
  bool new_keyframe = false;
  bool used_motion_model = false;
  // Matches and inliers of the pose optimizations (the source's Figure 3.13 plots their
  // ratio): after the initial pose (motion model, reference keyframe or relocalization) and
  // after local-map tracking; 0 / 0 when that step did not run.
  int initial_matches = 0, initial_inliers = 0;
  int local_map_matches = 0, local_map_inliers = 0;
};

// Where new keyframes go (local mapping); an interface so tracking can be tested alone.
class KeyFrameSink {
 public:
  virtual ~KeyFrameSink() = default;
  virtual void insert_keyframe(std::shared_ptr<KeyFrame> kf) = 0;
  virtual bool accepts_keyframes() const = 0;  // idle
  virtual std::size_t queue_size() const = 0;
  virtual void interrupt_bundle_adjustment() = 0;
};

class Tracker {
 public:
  Tracker(std::shared_ptr<const FrameContext> ctx, Map& map, KeyFrameSink* sink, TrackingOptions options,
          StageTimer* timer = nullptr);

  TrackingOutcome track(Frame frame);
  TrackingState state() const { return state_; }

  // One record per frame passed to track(): the pose relative to its reference keyframe, so
  // the final trajectory follows later keyframe corrections (local BA, loop closing).
  struct FrameRecord {
    double timestamp = 0;
    std::shared_ptr<KeyFrame> reference;
    SE3 T_cr;
    bool tracked = false;
  };
  const std::vector<FrameRecord>& records() const { return records_; }
  // The frame last passed to track() when it was tracked (its inlier matches to map points
  // kept), for online learning; read with the map lock held.
  const Frame& last_frame() const { return last_; }
  void reset();

  // Localization mode turns keyframe creation (and so map growth) off; with it off an empty
  // map is not initialized either.
  void set_keyframe_creation(bool enabled) { keyframe_creation_ = enabled; }
  bool keyframe_creation() const { return keyframe_creation_; }
  // After a map was loaded: the next frames must be relocalized in it.
  void start_lost();
  // Test hook, tried before the relocalizer on every lost frame with the map lock held: on
  // success it has set the frame's pose, matches and reference keyframe.
  using RelocalizationHook = std::function<bool(Frame& frame)>;
  void set_relocalization_hook(RelocalizationHook hook) { relocalization_hook_ = std::move(hook); }
  // Re-expresses records held by culled keyframes relative to the nearest live ancestor, so
  // the records stop keeping culled keyframes alive. Takes the map lock.
  void compact_records();
  // When set, a lost frame is relocalized against the whole map (BoW candidates, EPnP)
  // instead of matched against the last reference keyframe only. Not owned.
  void set_relocalizer(const Relocalizer* relocalizer) { relocalizer_ = relocalizer; }
  void set_planar(const PlanarMotion& planar) { opt_.planar = planar; }
  // The images of the frame about to be tracked (gray CV_8U, depth CV_32F metres), for the
  // depth-odometry bridge; without them (or with `enable_depth_odometry(false)`) it is off.
  void set_images(const cv::Mat& gray, const cv::Mat& depth) {
    gray_ = gray;
    depth_ = depth;
  }
  void enable_depth_odometry(bool on) { depth_odometry_on_ = on; }
  // Frames whose pose came from depth odometry because features alone could not hold it.
  long depth_odometry_frames() const { return depth_odometry_frames_; }
  // Of those, the frames aligned by the prior-weighted ICP (icp_with_motion_prior.hpp; the
  // rest by OpenCV's RgbdICPOdometry, its fallback).
  long depth_odometry_prior_frames() const;
  // Ids of the frames where tracking resumed through relocalization.
  const std::vector<long>& relocalized_frames() const { return relocalized_frames_; }
  // Localization mode: frames on visual odometry whose pose came from relocalization instead.
  long odometry_relocalizations() const { return odometry_relocalizations_; }

 private:
  std::shared_ptr<const FrameContext> ctx_;
  Map& map_;
  KeyFrameSink* sink_;
  TrackingOptions opt_;
  StageTimer* timer_;

  TrackingState state_ = TrackingState::kNotInitialized;
  Frame current_, last_;
  bool has_last_ = false;
  bool has_velocity_ = false;
  std::optional<SE3> predicted_T_cw_;  // this frame's motion-model prediction (motion_prior)
  SE3 velocity_;  // T_cur_last
  SE3 feature_velocity_;  // velocity_ of the last frame tracked by features (odometry_prediction)
  bool has_feature_velocity_ = false;
  bool last_by_depth_ = false;  // the last frame was carried by the depth odometry
  std::deque<double> recent_speeds_;  // metres per frame of the last frames tracked by features or measured bridge frames
  std::deque<SE3> recent_poses_;      // T_cw of the last kTurnWindow + 1 tracked frames, newest last
  static constexpr std::size_t kTurnWindow = 10;
  // Mean rotation per frame (rad) between the oldest and the newest of recent_poses_: a turn,
  // not the frame-to-frame jitter of a bridge (nothing before kTurnWindow + 1 poses).
  std::optional<double> recent_turn_rate() const;
  // The motion the depth odometry starts from and is pulled towards; `held`: it is the held
  // feature-tracked speed of a straight drive (see the definition).
  struct OdometryPrediction {
    SE3 T_cur_last;
    bool held = false;
  };
  OdometryPrediction odometry_prediction() const;
  // No motion to extrapolate (start, loss, new map): the velocities and the bridge flag.
  void forget_motion();
  std::shared_ptr<KeyFrame> reference_;
  std::vector<std::shared_ptr<KeyFrame>> local_keyframes_;
  std::vector<std::shared_ptr<MapPoint>> local_points_;
  std::vector<MapPoint*> local_map_visible_;  // predicted visible by the last local-map search, not yet counted
  long last_kf_frame_id_ = 0;
  int inliers_ = 0;
  int odometry_inliers_ = 0;  // inliers to the last frame's temporary depth points
  bool bridged_ = false;      // this frame was kept by odometry points alone (see track())
  bool weak_ = false;         // the last tracked frame had few map inliers: map more densely
  std::vector<FrameRecord> records_;
  bool keyframe_creation_ = true;
  RelocalizationHook relocalization_hook_;
  const Relocalizer* relocalizer_ = nullptr;
  std::vector<long> relocalized_frames_;
  long odometry_relocalizations_ = 0;
  std::unique_ptr<DepthOdometry> depth_odometry_;
  bool depth_odometry_on_ = true;
  cv::Mat gray_, depth_, last_gray_, last_depth_;  // this frame's and the last tracked frame's images
  long depth_odometry_frames_ = 0;
  bool track_depth_odometry();  // the last frame's pose moved by RGB-D odometry
  bool refine_depth_odometry_with_local_map();
  void link_by_depth(KeyFrame& kf, const KeyFrame& prev) const;  // KeyFrame::depth_link_*
  std::optional<PosePrior> depth_prior() const;                    // depth_prior_weight
  cv::Mat last_kf_depth_;        // the newest keyframe's depth image and the keyframe
  std::weak_ptr<KeyFrame> last_kf_;

  bool initialize();
  void update_last_frame();
  bool track_motion_model();
  bool track_reference_keyframe();
  bool recover_near_reference();  // lost: the reference, then nearby and newest keyframes
  // Searches the local map and optimizes the pose; with count_observations the matched and
  // predicted-visible map points' found/visible counters are counted at once, otherwise
  // count_local_map_observations() does it when the caller keeps the result.
  bool track_local_map(bool count_observations = true);
  void count_local_map_observations();
  void update_local_map();
  void collect_local_points();  // local_points_ from local_keyframes_
  std::vector<ProjectedPoint> project_local_points();  // local points in view (not yet counted visible)
  bool local_map_from_nearby_keyframes();  // localization mode: see track_local_map()
  int discard_outliers();  // returns matches to real map points
  PoseOptimizerOptions pose_options() const;
  // Matches and inliers of the current frame, for TrackingOutcome's ratios.
  std::pair<int, int> match_counts() const;
  std::pair<int, int> initial_counts_{0, 0}, local_map_counts_{0, 0};
  bool need_new_keyframe() const;
  void create_new_keyframe();
};

}  // namespace builtscene::slam
