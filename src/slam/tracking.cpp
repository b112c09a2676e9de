#include "slam/tracking.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <tuple>
#include <unordered_map>

#include <Eigen/Eigenvalues>

#include "core/so3.hpp"
#include "slam/icp_with_motion_prior.hpp"
#include "slam/key_frame.hpp"
#include "slam/map.hpp"
#include "slam/map_point.hpp"
#include "slam/matcher.hpp"
#include "slam/pose_optimizer.hpp"
#include "slam/relocalizer.hpp"

namespace builtscene::slam {

const char* to_string(TrackingState s) {
  switch (s) {
    case TrackingState::kNotInitialized: return "not_initialized";
    case TrackingState::kOk: return "ok";
    case TrackingState::kLost: return "lost";
  }
  return "?";
}

Tracker::Tracker(std::shared_ptr<const FrameContext> ctx, Map& map, KeyFrameSink* sink, TrackingOptions options,
                 StageTimer* timer)
    : ctx_(std::move(ctx)), map_(map), sink_(sink), opt_(options), timer_(timer),
      current_(0, 0, std::make_shared<FrameFeatures>()), last_(0, 0, std::make_shared<FrameFeatures>()) {}

void Tracker::reset() {
  state_ = TrackingState::kNotInitialized;
  has_last_ = weak_ = bridged_ = false;
  forget_motion();
  reference_.reset();
  local_keyframes_.clear();
  local_points_.clear();
}

TrackingOutcome Tracker::track(Frame frame) {
  current_ = std::move(frame);
  TrackingOutcome out;
  initial_counts_ = local_map_counts_ = {0, 0};
  std::unique_lock lock(map_.mutex());
  bool ok = false;
  bool relocalized = false;
  predicted_T_cw_.reset();
  if (state_ == TrackingState::kNotInitialized) {
    ok = keyframe_creation_ && initialize();
    out.state = state_;
    out.new_keyframe = ok;
    out.inliers = ok ? current_.matched_count() : 0;
  } else {
    const bool was_ok = state_ == TrackingState::kOk;
    if (was_ok) {
      update_last_frame();
      if (has_velocity_) {
        ok = track_motion_model();
        out.used_motion_model = ok;
      }
      if (!ok) {
        predicted_T_cw_.reset();
        ok = track_reference_keyframe();
      }
      // Localization mode on visual odometry (the last frame matched too few map points): the
      // place is searched in the whole map as well and its pose wins when found (ORB-SLAM2's
      // mbVO). The odometry alone drifts, and the covisible local map it leaves behind may no
      // longer be where the camera is.
      if (!keyframe_creation_ && relocalizer_ && inliers_ < opt_.min_local_map_inliers) {
        Frame probe = current_;
        const auto start = std::chrono::steady_clock::now();
        auto kf = relocalizer_->relocalize(probe);
        if (timer_) timer_->add("relocalization", ms_since(start));
        if (kf) {
          current_ = std::move(probe);
          reference_ = kf;
          predicted_T_cw_.reset();
          ok = true;
          ++odometry_relocalizations_;
        }
      }
    } else {
      current_.clear_matches();
      if (relocalization_hook_ && relocalization_hook_(current_)) {
        ok = relocalized = true;
        reference_ = current_.reference;
        relocalized_frames_.push_back(current_.id);
      } else if (relocalizer_) {
        // Lost: look for the place in the whole map.
        const auto start = std::chrono::steady_clock::now();
        auto kf = relocalizer_->relocalize(current_);
        if (timer_) timer_->add("relocalization", ms_since(start));
        if (kf) {
          ok = true;
          relocalized = true;
          reference_ = kf;
          relocalized_frames_.push_back(current_.id);
        }
      }
      // Lost and not found by the vocabulary (or none loaded): the best chance is that the
      // camera is still near the keyframes it saw last; try them each frame.
      if (!ok) ok = recover_near_reference();
    }
    current_.reference = reference_;
    bridged_ = false;
    if (ok) {
      const auto start = std::chrono::steady_clock::now();
      ok = track_local_map();
      if (timer_) timer_->add("local_map", ms_since(start));
      // Entering unmapped space faster than keyframes arrive (a fast turn, or local mapping
      // starved of CPU) leaves too few map points in view although the frame-to-frame depth
      // points still pin the pose down. In SLAM mode keep the pose they give and make a
      // keyframe at once, so the map catches up instead of tracking being lost in a place it
      // cannot recover.
      if (!ok && keyframe_creation_ && inliers_ + odometry_inliers_ >= opt_.min_local_map_inliers &&
          inliers_ > 0) {
        ok = true;
        bridged_ = true;
      }
      // Localization mode keeps going on visual odometry when too few map points are in
      // view (ORB-SLAM's mbVO); the local map is searched again on every frame.
      if (!ok && !keyframe_creation_ && was_ok && current_.matched_count() >= 20) ok = true;
    }
    // Features could not hold the pose (a plain wall in view) but the depth image still shows
    // wall and floor: take the pose from RGB-D odometry against the last frame; in SLAM mode
    // make a keyframe at once, so new map points from depth are there when texture returns.
    bool by_depth = false;
    if (!ok && was_ok && track_depth_odometry()) {
      ok = true;
      bridged_ = keyframe_creation_;
      if (!refine_depth_odometry_with_local_map()) {
        by_depth = true;
        inliers_ = 0;
        ++depth_odometry_frames_;
      }
    }
    weak_ = ok && inliers_ < opt_.weak_tracking_inliers;
    state_ = ok ? TrackingState::kOk : TrackingState::kLost;
    out.state = state_;
    out.inliers = ok ? inliers_ : 0;
    if (ok) {
      velocity_ = current_.T_cw * last_.T_cw.inverse();
      // After a loss or relocalization the last tracked frame is from another time and place:
      // no motion to extrapolate.
      has_velocity_ = was_ok && !relocalized;
      // The first frame features hold again after a bridge also carries the correction of the
      // bridge's drift: not a velocity.
      const bool by_features = has_velocity_ && !by_depth && !last_by_depth_;
      // A bridge frame whose depth measured the motion along its direction (structure facing
      // it) also says how fast the camera moves; one that kept the prediction there does not.
      // The generated corridor, seed 4: the features give out at frame 19 while the robot
      // still speeds up, a cabinet's end in the depth measures 2.3 cm per frame to frame 80
      // against the features' last 1.8, and from frame 150 the plain corridor holds the speed.
      const bool measured_bridge =
          has_velocity_ && by_depth && depth_odometry_ && depth_odometry_->last_slide_measured();
      if (by_features || measured_bridge) {
        recent_speeds_.push_back(velocity_.translation().norm());
        if (recent_speeds_.size() > 30) recent_speeds_.pop_front();
      }
      if (by_features) {
        feature_velocity_ = velocity_;
        has_feature_velocity_ = true;
      }
      if (!has_velocity_) {
        recent_speeds_.clear();
        recent_poses_.clear();
        has_feature_velocity_ = false;
      }
      last_by_depth_ = by_depth;
      recent_poses_.push_back(current_.T_cw);
      if (recent_poses_.size() > kTurnWindow + 1) recent_poses_.pop_front();
      // Temporary (visual-odometry) matches do not count towards the map.
      for (auto& p : current_.points)
        if (p && p->observation_count() == 0) p = nullptr;
      if (keyframe_creation_ && need_new_keyframe()) {
        create_new_keyframe();
        out.new_keyframe = true;
      }
      for (std::size_t i = 0; i < current_.points.size(); ++i)
        if (current_.outlier[i]) current_.points[i] = nullptr;
    } else {
      forget_motion();
    }
  }
  FrameRecord rec;
  rec.timestamp = current_.timestamp;
  rec.tracked = state_ == TrackingState::kOk;
  if (rec.tracked && current_.reference) {
    rec.reference = current_.reference;
    rec.T_cr = current_.T_cw * current_.reference->pose_inverse();
  }
  records_.push_back(rec);
  std::tie(out.initial_matches, out.initial_inliers) = initial_counts_;
  std::tie(out.local_map_matches, out.local_map_inliers) = local_map_counts_;
  if (state_ == TrackingState::kOk) {
    last_ = std::move(current_);
    has_last_ = true;
    last_gray_ = gray_;
    last_depth_ = depth_;
  } else {
    last_gray_.release();
    last_depth_.release();
  }
  gray_.release();
  depth_.release();
  return out;
}

void Tracker::forget_motion() {
  has_velocity_ = has_feature_velocity_ = last_by_depth_ = false;
  recent_poses_.clear();
}

std::optional<double> Tracker::recent_turn_rate() const {
  if (recent_poses_.size() < kTurnWindow + 1) return std::nullopt;
  const SE3 d = recent_poses_.back() * recent_poses_.front().inverse();
  return so3_log(d.rotation()).norm() / static_cast<double>(recent_poses_.size() - 1);
}

Tracker::OdometryPrediction Tracker::odometry_prediction() const {
  if (!has_velocity_) return {};
  // On a depth-odometry bridge (the last frame was carried by it) the prediction is the last
  // feature-tracked frame's motion, not the last frame's: along a plain corridor the depth
  // leaves the slide free and returns the prediction plus noise there, and feeding that back
  // made the speed a random walk; capped from above and free below, it drifted down, and the
  // generated corridor's second world stalled at a quarter of the true speed for 100 frames
  // (2.3 m short).
  // Only while driving straight: into a turn a robot slows down (the generated office turns in
  // front of plain walls on the bridge, and holding the speed there cost it 4.8 -> 52 cm).
  // Straight is judged on the net turn over the last kTurnWindow frames: a bridge frame's own
  // rotation jitters by 0.1-0.3 degrees on a straight (ICP noise), and judged frame by frame
  // the hold dropped out on every third frame there, each time feeding the last frame's speed
  // back (the random walk above, 20 % slow over 110 frames of the generated corridor's start).
  // The window lags a turn's start, so the last frame must not be turning either: above
  // kTurning (the generated robot turns at about 1 degree per frame, and slows to 60 % there;
  // held into a corner of the generated corridor, seed 3, 20 frames covered 3.4 times their
  // true distance: ATE 7.9 -> 50 cm with --depth-planes; the office 6.2 -> 55 cm).
  constexpr double kStraight = 0.2 * M_PI / 180.0;  // rad per frame
  constexpr double kTurning = 0.5 * M_PI / 180.0;
  const double last_turn = so3_log(velocity_.rotation()).norm();
  const auto turn = recent_turn_rate();
  const bool straight = so3_log(feature_velocity_.rotation()).norm() < kStraight &&
                        (turn ? *turn < kStraight && last_turn < kTurning : last_turn < kStraight);
  const bool hold = last_by_depth_ && has_feature_velocity_ && straight;
  const SE3& v = hold ? feature_velocity_ : velocity_;
  if (recent_speeds_.size() < 5) return {v, hold};
  // Its speed is the median of the last 30 feature-tracked frames (and bridge frames whose
  // depth measured the slide, see track()): held at it on the bridge,
  // capped at it otherwise. The depth odometry keeps the prediction where one plane leaves a
  // direction free, so an inflated velocity (a few weakly tracked frames before the features
  // gave out) would run away along the wall. (At 1.5 times the median the generated
  // corridor's 30-frame gaps still ran at 1.8 times the true speed.)
  std::vector<double> s(recent_speeds_.begin(), recent_speeds_.end());
  std::nth_element(s.begin(), s.begin() + static_cast<long>(s.size() / 2), s.end());
  const double median = s[s.size() / 2];
  const double speed = v.translation().norm();
  if ((speed <= median && !hold) || !(speed > 1e-9)) return {v, hold};
  return {SE3(v.rotation(), v.translation() * (median / speed)), hold};
}

long Tracker::depth_odometry_prior_frames() const {
  return depth_odometry_ ? depth_odometry_->prior_alignments() : 0;
}

bool Tracker::track_depth_odometry() {
  if (!depth_odometry_on_ || last_gray_.empty() || last_depth_.empty() || gray_.empty() || depth_.empty()) return false;
  if (!depth_odometry_) {
    const Intrinsics K = intrinsics_of(*ctx_);
    depth_odometry_ = std::make_unique<DepthOdometry>(K.fx, K.fy, K.cx, K.cy);
  }
  const auto start = std::chrono::steady_clock::now();
  const auto prediction = odometry_prediction();
  const auto T_cur_last =
      depth_odometry_->align(last_gray_, last_depth_, gray_, depth_, prediction.T_cur_last, prediction.held);
  if (timer_) timer_->add("depth_odometry", ms_since(start));
  if (!T_cur_last) return false;
  current_.clear_matches();
  current_.set_pose(*T_cur_last * last_.T_cw);
  return true;
}

bool Tracker::refine_depth_odometry_with_local_map() {
  // The depth odometry's pose is measured, not extrapolated: the local map is searched from
  // it. The far map points (an end wall's poster beyond the depth's range) are what the
  // motion model lost, and a keyframe that shares them keeps the bridge tied to the map;
  // without them every bridge keyframe holds only the few close points of a plain corridor
  // and the motion model never finds its 20 matches again.
  const int min_inliers = opt_.bridge_local_map_inliers;
  if (min_inliers <= 0) return false;
  // A rejected search must leave no trace: the map points' visible/found counters are only
  // counted when the result is kept, and the reference keyframe is put back.
  const SE3 odometry = current_.T_cw;
  const auto reference = reference_;
  const auto frame_reference = current_.reference;
  const auto start = std::chrono::steady_clock::now();
  track_local_map(/*count_observations=*/false);
  if (timer_) timer_->add("local_map", ms_since(start));
  const SE3 d = current_.T_cw * odometry.inverse();
  if (inliers_ >= min_inliers && d.translation().norm() < 0.1 &&
      so3_log(d.rotation()).norm() < 3.0 * M_PI / 180.0) {
    count_local_map_observations();
    return true;
  }
  local_map_visible_.clear();
  reference_ = reference;
  current_.reference = frame_reference;
  current_.clear_matches();
  current_.set_pose(odometry);
  return false;
}

void Tracker::link_by_depth(KeyFrame& kf, const KeyFrame& prev) const {
  const double w = opt_.depth_link_weight;
  if (!(w > 0)) return;
  const Intrinsics K = intrinsics_of(*ctx_);
  IcpWithPriorOptions o;
  o.iterations = 30;
  o.min_correspondences = 100;
  o.max_gap_m = 0.3;
  o.prior_sigma_m = 0.05;  // tracking's relative pose, loose: the depth decides where it can
  o.prior_sigma_rad = 0.02;
  const SE3 predicted = kf.pose() * prev.pose_inverse();
  Eigen::Matrix<double, 6, 6> info;
  const auto T = icp_with_motion_prior(last_kf_depth_, depth_, K.fx, K.fy, K.cx, K.cy, predicted, o, &info);
  if (!T) return;
  const SE3 d = *T * predicted.inverse();
  if (d.translation().norm() > 0.5 || so3_log(d.rotation()).norm() > 8.0 * M_PI / 180.0) return;
  kf.depth_link_to = std::const_pointer_cast<KeyFrame>(prev.shared_from_this());
  kf.depth_link_T = *T;
  kf.depth_link_information = w * info;
}

std::optional<PosePrior> Tracker::depth_prior() const {
  if (!(opt_.depth_prior_weight > 0) || depth_.empty()) return std::nullopt;
  // inliers_ still holds the last frame's count here.
  if (opt_.depth_prior_below_inliers > 0 && inliers_ >= opt_.depth_prior_below_inliers) return std::nullopt;
  // The depth to align to: the newest keyframe's in SLAM mode; in localization mode, where no
  // keyframe is made, the last tracked frame's.
  const cv::Mat* ref_depth = nullptr;
  SE3 T_ref_cw;
  if (keyframe_creation_) {
    const auto kf = last_kf_.lock();
    if (!kf || kf->bad || last_kf_depth_.empty()) return std::nullopt;
    ref_depth = &last_kf_depth_;
    T_ref_cw = kf->pose();
  } else {
    // Only while the map holds the pose: on visual odometry alone (a plain corridor) the
    // frame-to-frame alignment slides along the walls and drags the pose with it.
    if (!has_last_ || last_depth_.empty() || inliers_ < opt_.min_local_map_inliers) return std::nullopt;
    ref_depth = &last_depth_;
    T_ref_cw = last_.T_cw;
  }
  const auto start = std::chrono::steady_clock::now();
  const Intrinsics K = intrinsics_of(*ctx_);
  IcpWithPriorOptions o;
  o.stride = 8;
  o.iterations = 15;
  o.min_correspondences = 100;
  o.max_gap_m = 0.3;
  o.prior_sigma_m = 0.05;  // as the keyframe links: the depth decides where it can
  o.prior_sigma_rad = 0.02;
  const SE3 predicted = current_.T_cw * T_ref_cw.inverse();
  Eigen::Matrix<double, 6, 6> info;  // (translation, rotation) of the left perturbation
  const auto T = icp_with_motion_prior(*ref_depth, depth_, K.fx, K.fy, K.cx, K.cy, predicted, o, &info);
  if (timer_) timer_->add("depth_prior", ms_since(start));
  if (!T) return std::nullopt;
  const SE3 d = *T * predicted.inverse();
  if (d.translation().norm() > 0.5 || so3_log(d.rotation()).norm() > 8.0 * M_PI / 180.0) return std::nullopt;
  // PosePrior wants (rotation, translation) and the square root of the information.
  Eigen::Matrix<double, 6, 6> H;
  H << info.block<3, 3>(3, 3), info.block<3, 3>(3, 0), info.block<3, 3>(0, 3), info.block<3, 3>(0, 0);
  H = 0.5 * (H + H.transpose()) * opt_.depth_prior_weight;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> es(H);
  if (es.info() != Eigen::Success) return std::nullopt;
  const Eigen::Matrix<double, 6, 1> s = es.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  return PosePrior{*T * T_ref_cw, s.asDiagonal() * es.eigenvectors().transpose()};
}

void Tracker::start_lost() {
  reset();
  state_ = TrackingState::kLost;
}

void Tracker::compact_records() {
  std::lock_guard lock(map_.mutex());
  for (auto& r : records_) {
    while (r.reference && r.reference->bad && r.reference->parent) {
      r.T_cr = r.T_cr * r.reference->T_cp;
      r.reference = r.reference->parent;
    }
  }
}

bool Tracker::initialize() {
  int with_depth = 0;
  for (std::size_t i = 0; i < current_.size(); ++i) with_depth += current_.f->has_depth(i);
  // ORB-SLAM2 asks for 500 keypoints, not 500 with depth: looking down a long corridor most
  // corners are beyond the sensor's range, and the map must still start there.
  if (static_cast<int>(current_.size()) < opt_.min_init_points || with_depth < opt_.min_init_depth_points) return false;
  current_.set_pose(SE3());
  auto kf = std::make_shared<KeyFrame>(map_.next_keyframe_id(), current_);
  kf->keep = true;
  map_.add_keyframe(kf);
  for (std::size_t i = 0; i < current_.size(); ++i) {
    if (!current_.f->has_depth(i)) continue;
    auto p = std::make_shared<MapPoint>(map_.next_point_id(), kf->pose_inverse() * current_.f->unproject(i), kf.get(), kf->id);
    p->add_observation(kf.get(), static_cast<int>(i));
    kf->add_point(static_cast<int>(i), p);
    p->update_descriptor();
    p->update_normal_and_depth();
    map_.add_point(p);
    current_.points[i] = p;
  }
  reference_ = kf;
  current_.reference = kf;
  last_kf_frame_id_ = current_.id;
  local_keyframes_ = {kf};
  local_points_ = kf->good_points();
  state_ = TrackingState::kOk;
  forget_motion();
  if (sink_) sink_->insert_keyframe(kf);
  return true;
}

void Tracker::update_last_frame() {
  // The last frame's reference keyframe may have been moved by local BA since.
  const auto& rec = records_.back();
  if (rec.reference && !rec.reference->bad) last_.set_pose(rec.T_cr * rec.reference->pose());
  // Temporary points from the last frame's depth (ORB-SLAM's visual odometry points): close
  // keypoints without a map point get one, so the motion model has enough to match even
  // where the map is thin. They never enter the map.
  if (last_.id == last_kf_frame_id_) return;
  std::vector<std::pair<float, std::size_t>> by_depth;
  for (std::size_t i = 0; i < last_.size(); ++i)
    if (last_.f->has_depth(i)) by_depth.emplace_back(last_.f->depth[i], i);
  std::sort(by_depth.begin(), by_depth.end());
  const SE3 T_wc = last_.T_cw.inverse();
  // While tracking is weak every keypoint with depth helps (far depth is noisier, but the
  // alternative is losing track in a place the map cannot bring the camera back to).
  const int wanted = weak_ ? static_cast<int>(by_depth.size()) : opt_.new_kf_min_points;
  int n = 0;
  for (const auto& [z, i] : by_depth) {
    const auto& p = last_.points[i];
    if (!p || p->observation_count() < 1) {
      auto tmp = std::make_shared<MapPoint>(-1, T_wc * last_.f->unproject(i), nullptr, -1);
      tmp->descriptor = last_.f->descriptors.row(static_cast<int>(i)).clone();
      last_.points[i] = tmp;
      last_.outlier[i] = 0;
    }
    ++n;
    if (z > ctx_->th_depth && n > wanted) break;
  }
}

std::pair<int, int> Tracker::match_counts() const {
  int matches = 0, inliers = 0;
  for (std::size_t i = 0; i < current_.points.size(); ++i) {
    if (!current_.points[i]) continue;
    ++matches;
    if (!current_.outlier[i]) ++inliers;
  }
  return {matches, inliers};
}

int Tracker::discard_outliers() {
  initial_counts_ = match_counts();
  int real = 0;
  for (std::size_t i = 0; i < current_.points.size(); ++i) {
    if (!current_.points[i]) continue;
    if (current_.outlier[i]) {
      current_.points[i] = nullptr;
      current_.outlier[i] = 0;
    } else if (current_.points[i]->observation_count() > 0) {
      ++real;
    }
  }
  return real;
}

PoseOptimizerOptions Tracker::pose_options() const {
  PoseOptimizerOptions o;
  if (opt_.motion_prior && predicted_T_cw_) {
    o.prior_T_cw = predicted_T_cw_;
    o.prior_sigma_m = opt_.motion_prior_sigma_m;
    o.prior_sigma_rad = opt_.motion_prior_sigma_rad;
  }
  return o;
}

bool Tracker::track_motion_model() {
  current_.set_pose(velocity_ * last_.T_cw);
  predicted_T_cw_ = current_.T_cw;
  current_.clear_matches();
  int n = search_by_projection(current_, last_, opt_.motion_model_radius);
  if (n < 20) {
    current_.clear_matches();
    n = search_by_projection(current_, last_, 2 * opt_.motion_model_radius);
  }
  if (n < 20) {
    predicted_T_cw_.reset();
    return false;
  }
  optimize_frame_pose(current_, pose_options());
  const int real = discard_outliers();
  // Localization mode: where the map is thin, matches to the last frame's depth points
  // (visual odometry) carry the pose, as in ORB-SLAM's only-tracking mode.
  if (!keyframe_creation_) return real >= 10 || current_.matched_count() >= 20;
  return real >= 10;
}

bool Tracker::track_reference_keyframe() {
  if (!reference_ || reference_->bad) {
    // The reference was culled: fall back to the newest keyframe in the map.
    const auto kfs = map_.keyframes();
    if (kfs.empty()) return false;
    reference_ = kfs.back();
  }
  current_.clear_matches();
  const int n = search_by_descriptor(*reference_, current_);
  if (n < 15) return false;
  current_.set_pose(has_last_ ? last_.T_cw : reference_->pose());
  optimize_frame_pose(current_);
  return discard_outliers() >= 10;
}

bool Tracker::recover_near_reference() {
  if (track_reference_keyframe()) return true;
  // The reference alone often shares too little with the view that comes back after a
  // blank stretch (a plain wall, a fast turn); its covisible neighbours and the newest
  // keyframes cover the places the camera was just before.
  std::vector<std::shared_ptr<KeyFrame>> candidates;
  auto consider = [&](const std::shared_ptr<KeyFrame>& kf) {
    if (!kf || kf->bad || kf == reference_) return;
    for (const auto& c : candidates)
      if (c == kf) return;
    candidates.push_back(kf);
  };
  if (reference_)
    for (KeyFrame* n : reference_->best_covisibles(opt_.recovery_keyframes)) consider(n->shared_from_this());
  const auto kfs = map_.keyframes();
  for (std::size_t k = 0; k < kfs.size() && k < static_cast<std::size_t>(opt_.recovery_keyframes); ++k)
    consider(kfs[kfs.size() - 1 - k]);
  const auto lost_reference = reference_;
  for (const auto& kf : candidates) {
    reference_ = kf;
    if (track_reference_keyframe()) return true;
  }
  reference_ = lost_reference;
  return false;
}

void Tracker::update_local_map() {
  // Local keyframes: those sharing points with the frame, plus their best neighbours,
  // children and parents (ORB-SLAM's UpdateLocalKeyFrames).
  KeyFrameMap<int> counter;  // by id: the local map's order must not depend on addresses
  for (std::size_t i = 0; i < current_.points.size(); ++i) {
    const auto& p = current_.points[i];
    if (!p) continue;
    if (p->bad) {
      current_.points[i] = nullptr;
      continue;
    }
    for (const auto& [kf, idx] : p->observations) ++counter[kf];
  }
  if (counter.empty()) return;
  local_keyframes_.clear();
  KeyFrame* best = nullptr;
  int best_n = 0;
  for (const auto& [kf, n] : counter) {
    if (kf->bad) continue;
    if (n > best_n || (n == best_n && best && kf->id > best->id)) {
      best = kf;
      best_n = n;
    }
    local_keyframes_.push_back(kf->shared_from_this());
    kf->local_map_mark = current_.id;
  }
  const std::size_t direct = local_keyframes_.size();
  for (std::size_t k = 0; k < direct && local_keyframes_.size() < 80; ++k) {
    auto add = [&](KeyFrame* n) {
      if (!n || n->bad || n->local_map_mark == current_.id) return false;
      n->local_map_mark = current_.id;
      local_keyframes_.push_back(n->shared_from_this());
      return true;
    };
    KeyFrame* kf = local_keyframes_[k].get();
    for (KeyFrame* n : kf->best_covisibles(10))
      if (add(n)) break;
    for (KeyFrame* c : kf->children)
      if (add(c)) break;
    add(kf->parent.get());
  }
  if (best) {
    reference_ = best->shared_from_this();
    current_.reference = reference_;
  }
  collect_local_points();
}

void Tracker::collect_local_points() {
  local_points_.clear();
  for (const auto& kf : local_keyframes_) {
    for (const auto& p : kf->points) {
      if (!p || p->bad || p->local_map_mark == current_.id) continue;
      p->local_map_mark = current_.id;
      local_points_.push_back(p);
    }
  }
}

std::vector<ProjectedPoint> Tracker::project_local_points() {
  const Intrinsics K = intrinsics_of(*ctx_);
  const Eigen::Vector3d O = current_.camera_center();
  std::vector<ProjectedPoint> candidates;
  candidates.reserve(local_points_.size());
  for (const auto& p : local_points_) {
    if (p->track_mark == current_.id || p->bad) continue;
    const Eigen::Vector3d pc = current_.T_cw * p->position;
    if (pc.z() <= 0) continue;
    const double inv_z = 1.0 / pc.z();
    const double u = K.fx * pc.x() * inv_z + K.cx, v = K.fy * pc.y() * inv_z + K.cy;
    if (!ctx_->in_image(u, v)) continue;
    const Eigen::Vector3d po = p->position - O;
    const double dist = po.norm();
    if (dist < 0.8 * p->min_distance || dist > 1.2 * p->max_distance) continue;
    const double view_cos = po.dot(p->normal) / dist;
    if (view_cos < 0.5) continue;
    candidates.push_back({p, static_cast<float>(u), static_cast<float>(v), static_cast<float>(u - K.bf * inv_z),
                          p->predict_level(dist, ctx_->pyramid), static_cast<float>(view_cos)});
  }
  return candidates;
}

bool Tracker::local_map_from_nearby_keyframes() {
  // Keyframes whose camera stood near the frame's and looked the same way, nearest first.
  const Eigen::Vector3d O = current_.camera_center();
  auto optical_axis = [](const SE3& T_cw) { return (T_cw.rotation().conjugate() * Eigen::Vector3d::UnitZ()).eval(); };
  const Eigen::Vector3d axis = optical_axis(current_.T_cw);
  const double cos_max = std::cos(opt_.nearby_keyframe_max_angle_deg * M_PI / 180.0);
  std::vector<std::pair<double, std::shared_ptr<KeyFrame>>> near;
  for (const auto& kf : map_.keyframes()) {
    if (kf->bad) continue;
    const double d = (kf->camera_center() - O).norm();
    if (d > opt_.nearby_keyframe_radius_m) continue;
    if (optical_axis(kf->pose()).dot(axis) < cos_max) continue;
    near.emplace_back(d, kf);
  }
  if (near.empty()) return false;
  std::sort(near.begin(), near.end(), [](const auto& a, const auto& b) {
    return a.first < b.first || (a.first == b.first && a.second->id < b.second->id);
  });
  if (near.size() > opt_.nearby_keyframes) near.resize(opt_.nearby_keyframes);
  local_keyframes_.clear();
  for (const auto& [d, kf] : near) {
    kf->local_map_mark = current_.id;
    local_keyframes_.push_back(kf);
  }
  reference_ = near.front().second;
  current_.reference = reference_;
  collect_local_points();
  return true;
}

bool Tracker::track_local_map(bool count_observations) {
  update_local_map();
  local_map_visible_.clear();
  // Points already matched are visible; do not search them again.
  for (auto& p : current_.points) {
    if (!p) continue;
    if (p->bad) {
      p = nullptr;
      continue;
    }
    local_map_visible_.push_back(p.get());
    p->track_mark = current_.id;  // already matched in this frame
  }
  auto candidates = project_local_points();
  // Localization mode: the local map comes from the keyframes that share the frame's matched
  // map points, so after a stretch on visual odometry alone (a plain wall, a turn) it still
  // holds the keyframes of the place the camera left and nothing of it is in view. No new
  // keyframe will replace them as in SLAM mode: take the keyframes around the frame's pose.
  if (!keyframe_creation_ && static_cast<int>(candidates.size()) < opt_.min_local_map_inliers &&
      local_map_from_nearby_keyframes())
    candidates = project_local_points();
  for (const auto& c : candidates) local_map_visible_.push_back(c.point.get());
  search_local_points(current_, candidates, opt_.local_map_radius);
  PoseOptimizerOptions po = pose_options();
  if (auto prior = depth_prior()) po.priors.push_back(*prior);
  if (opt_.planar.enabled) po.priors.push_back(planar_prior(opt_.planar, current_.T_cw));
  optimize_frame_pose(current_, po);
  local_map_counts_ = match_counts();
  inliers_ = odometry_inliers_ = 0;
  for (std::size_t i = 0; i < current_.points.size(); ++i) {
    const auto& p = current_.points[i];
    if (!p || current_.outlier[i]) continue;
    if (p->observation_count() > 0) ++inliers_;
    else if (current_.f->has_depth(i)) ++odometry_inliers_;
  }
  if (count_observations) count_local_map_observations();
  return inliers_ >= opt_.min_local_map_inliers;
}

void Tracker::count_local_map_observations() {
  // Culling judges a map point by how often it was found where it was predicted visible.
  for (MapPoint* p : local_map_visible_) ++p->visible;
  local_map_visible_.clear();
  for (std::size_t i = 0; i < current_.points.size(); ++i)
    if (current_.points[i] && !current_.outlier[i]) ++current_.points[i]->found;
}

bool Tracker::need_new_keyframe() const {
  if (!reference_) return false;
  if (bridged_) {
    if (!sink_ || sink_->accepts_keyframes()) return true;
    sink_->interrupt_bundle_adjustment();
    return sink_->queue_size() < opt_.max_keyframe_queue_weak;
  }
  const long since = current_.id - last_kf_frame_id_;
  const std::size_t n_kfs = map_.keyframe_count();
  const int min_obs = n_kfs <= 2 ? 2 : 3;
  const int ref_matches = reference_->tracked_points(min_obs);
  const bool mapping_idle = sink_ ? sink_->accepts_keyframes() : true;

  int tracked_close = 0, untracked_close = 0;
  for (std::size_t i = 0; i < current_.size(); ++i) {
    if (!current_.f->is_close(i)) continue;
    if (current_.points[i] && !current_.outlier[i]) ++tracked_close;
    else ++untracked_close;
  }
  const bool need_close = tracked_close < opt_.min_tracked_close && untracked_close > opt_.min_untracked_close;
  const float th_ref_ratio = n_kfs < 2 ? 0.4f : 0.75f;
  const bool c1a = since >= opt_.max_frames_between_kf;
  const bool c1b = since >= opt_.min_frames_between_kf && mapping_idle;
  const bool c1c = inliers_ < ref_matches * 0.25f || need_close;
  const bool c2 = (inliers_ < ref_matches * th_ref_ratio || need_close) && inliers_ > 15;
  if (!((c1a || c1b || c1c) && c2)) return false;
  if (mapping_idle || !sink_) return true;
  // ORB-SLAM2 interrupts local BA for every keyframe; here only when tracking is weak, so
  // that BA still finishes when local mapping gets a fraction of a core.
  if (weak_) sink_->interrupt_bundle_adjustment();
  // While tracking is weak a keyframe matters more than a short queue: local mapping may
  // lag (on a loaded machine) but tracking must not run out of map; the queue stays bounded.
  return sink_->queue_size() < (weak_ ? opt_.max_keyframe_queue_weak : opt_.max_keyframe_queue);
}

void Tracker::create_new_keyframe() {
  auto kf = std::make_shared<KeyFrame>(map_.next_keyframe_id(), current_);
  int shared = 0;
  for (std::size_t i = 0; i < current_.size(); ++i)
    if (current_.points[i] && !current_.outlier[i] && !current_.points[i]->bad) {
      kf->points[i] = current_.points[i];
      ++shared;
    }
  // No map point in common with the map (the depth-odometry bridge carried the pose): the
  // keyframe hangs on the one the bridge carried the pose from.
  if (shared == 0 && reference_) kf->odometry_parent = reference_;
  if (opt_.planes.enabled && !depth_.empty()) {
    const Intrinsics K = intrinsics_of(*ctx_);
    for (const auto& m : extract_depth_planes(depth_, K.fx, K.fy, K.cx, K.cy, opt_.planes.extraction))
      kf->planes.push_back({m, nullptr});
  }
  // New map points from depth: all close keypoints, at least new_kf_min_points nearest ones.
  std::vector<std::pair<float, std::size_t>> by_depth;
  for (std::size_t i = 0; i < current_.size(); ++i)
    if (current_.f->has_depth(i)) by_depth.emplace_back(current_.f->depth[i], i);
  std::sort(by_depth.begin(), by_depth.end());
  const SE3 T_wc = current_.T_cw.inverse();
  const int wanted = weak_ ? static_cast<int>(by_depth.size()) : opt_.new_kf_min_points;
  int n = 0;
  for (const auto& [z, i] : by_depth) {
    if (!kf->points[i]) {
      auto p = std::make_shared<MapPoint>(map_.next_point_id(), T_wc * current_.f->unproject(i), kf.get(), kf->id);
      p->add_observation(kf.get(), static_cast<int>(i));
      kf->add_point(static_cast<int>(i), p);
      p->update_descriptor();
      p->update_normal_and_depth();
      map_.add_point(p);
      current_.points[i] = p;
      current_.outlier[i] = 0;
    }
    ++n;
    if (z > ctx_->th_depth && n > wanted) break;
  }
  if ((opt_.depth_links || opt_.depth_prior_weight > 0) && !depth_.empty()) {
    if (auto prev = last_kf_.lock(); opt_.depth_links && prev && !prev->bad && !last_kf_depth_.empty())
      link_by_depth(*kf, *prev);
    last_kf_depth_ = depth_;
    last_kf_ = kf;
  }
  map_.add_keyframe(kf);
  reference_ = kf;
  current_.reference = kf;
  last_kf_frame_id_ = current_.id;
  if (sink_) sink_->insert_keyframe(kf);
}

}  // namespace builtscene::slam
