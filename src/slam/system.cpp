#include "slam/system.hpp"

#include <chrono>
#include <thread>

#include <opencv2/imgproc.hpp>

#include "core/errors.hpp"
#include "core/logging.hpp"
#include "features/bow_vocabulary.hpp"
#include "slam/floor_plane.hpp"
#include "slam/key_frame.hpp"
#include "slam/keyframe_database.hpp"
#include "slam/relocalizer.hpp"
#include "features/saft_extractor.hpp"

namespace builtscene::slam {

std::filesystem::path default_vocabulary_path(DescriptorChoice descriptor) {
  const char* name = descriptor == DescriptorChoice::kOrb ? "orb_k10_L4.bsvoc" : "saft_k10_L4.bsvoc";
  for (const char* dir : {BUILTSCENE_SOURCE_VOCABULARY_DIR, BUILTSCENE_INSTALLED_VOCABULARY_DIR}) {
    const auto p = std::filesystem::path(dir) / name;
    if (std::filesystem::is_regular_file(p)) return p;
  }
  return {};
}

System::System(const RgbdCameraSettings& settings, SystemOptions options)
    : settings_(settings), options_(options),
      extractor_(make_feature_extractor(options.descriptor, options.orb, options.saft_weights)) {
  ctx_ = FrameContext::make(settings_, extractor_->pyramid(), extractor_->metric());
  if (options_.descriptor == DescriptorChoice::kSaft) {
    saft_ = static_cast<SaftExtractor*>(extractor_.get());
    learning_ = std::make_unique<SaftLearning>(*saft_, options_.saft_learning);
  }
  options_.tracking.planar = options_.mapping.planar = options_.loop.planar = options_.planar;
  options_.tracking.planes = options_.mapping.planes = options_.loop.planes = options_.planes;
  planar_guess_ = options_.planar.up_c;
  // Planar motion's priors leave the corridor's plain start a few inliers short of the map,
  // and without the local map searched from the depth bridge's pose it never gets back
  // (docs/slam.md, "Planar motion").
  // Plane landmarks likewise (measured: the 600-frame corridor start stays on the bridge from
  // frame 34 to 200 without it, 1 bridged frame with it).
  if (options_.tracking.bridge_local_map_inliers < 0)
    options_.tracking.bridge_local_map_inliers = options_.planar.enabled || options_.planes.enabled ? 10 : 0;
  options_.tracking.max_frames_between_kf = std::max(1, static_cast<int>(std::lround(settings_.fps)));
  mapping_ = std::make_unique<LocalMapping>(map_, options_.mapping, &timer_);
  tracker_ = std::make_unique<Tracker>(ctx_, map_, mapping_.get(), options_.tracking, &timer_);
  const auto vocabulary_file = options_.vocabulary.empty() ? default_vocabulary_path(options_.descriptor) : options_.vocabulary;
  if (vocabulary_file.empty()) {
    spdlog::warn("no bag-of-words vocabulary for {} descriptors (looked in {}): relocalization off", to_string(options_.descriptor),
                 BUILTSCENE_SOURCE_VOCABULARY_DIR);
  } else {
    auto voc = std::make_shared<BowVocabulary>(BowVocabulary::load(vocabulary_file));
    if (voc->kind() != ctx_->metric.kind)
      throw InputError(located(vocabulary_file, 0, "vocabulary is for another descriptor kind than the SLAM's"));
    vocabulary_ = voc;
    database_ = std::make_unique<KeyFrameDatabase>(vocabulary_);
    if (options_.relocalization) {
      relocalizer_ = std::make_unique<Relocalizer>(*database_);
      tracker_->set_relocalizer(relocalizer_.get());
    }
    if (options_.loop_closing) {
      loop_closer_ = std::make_unique<LoopCloser>(map_, *database_, mapping_.get(), options_.loop, options_.mapping_thread,
                                                  &timer_);
      loop_closer_->set_event_sink([this](const LoopEvent& e) { on_loop_event(e); });
      mapping_->set_keyframe_output([this](std::shared_ptr<KeyFrame> kf) { loop_closer_->insert_keyframe(std::move(kf)); });
    }
  }
  if (options_.loop_closing && !loop_closer_) spdlog::warn("no vocabulary: loop closing off");
  if (options_.mapping_thread) {
    mapping_->start();
    if (loop_closer_) loop_closer_->start();
  }
}

System::~System() {
  shutdown();
  loop_closer_.reset();
  std::lock_guard lock(map_.mutex());
  if (database_) database_->clear();
  map_.clear();
}

TrackingOutcome System::track_rgbd(const cv::Mat& image, const cv::Mat& depth_m, double timestamp) {
  const auto start = std::chrono::steady_clock::now();
  cv::Mat gray;
  if (image.channels() == 3) cv::cvtColor(image, gray, settings_.rgb_order ? cv::COLOR_RGB2GRAY : cv::COLOR_BGR2GRAY);
  else if (image.channels() == 4) cv::cvtColor(image, gray, settings_.rgb_order ? cv::COLOR_RGBA2GRAY : cv::COLOR_BGRA2GRAY);
  else gray = image;
  if (gray.depth() != CV_8U) gray.convertTo(gray, CV_8U);
  if (learning_ && learning_->install_weights()) timer_.add("saft_weights", ms_since(start));
  const auto t_extract = std::chrono::steady_clock::now();
  auto features = make_rgbd_features(gray, depth_m, ctx_, *extractor_);
  timer_.add("extraction", ms_since(t_extract));
  const auto t0 = std::chrono::steady_clock::now();
  const int keypoints = static_cast<int>(features->size());
  const long frame_id = next_frame_id_++;
  Frame frame(frame_id, timestamp, std::move(features));
  // Planar motion's floor: measured in every frame until one becomes the new map's first
  // keyframe, whose camera is the world (the value set before that frame is the one kept).
  const bool measure_floor = options_.planar.enabled && !floor_settled_;
  if (measure_floor) floor_from_this_frame(depth_m);
  tracker_->set_images(gray, depth_m);
  TrackingOutcome out = tracker_->track(std::move(frame));
  if (measure_floor && !floor_settled_ && out.new_keyframe) {
    floor_settled_ = true;
    if (floor_)
      spdlog::info("planar motion: floor {:.3f} m below the first keyframe's camera, {:.2f} degrees from the given "
                   "pitch ({} points)",
                   floor_->height_m, std::acos(std::clamp(floor_->up_c.dot(planar_guess_), -1.0, 1.0)) * 180 / M_PI,
                   floor_->inliers);
    else
      spdlog::warn("planar motion: no floor in the first keyframe's depth; the plane comes from the given pitch");
  }
  out.keypoints = keypoints;
  last_timestamp_ = timestamp;
  if (database_ && out.new_keyframe) {
    // The new keyframe is the reference of the frame just recorded. Its bag of words (one
    // tree descent per descriptor) measured 1.2 ms median at load 16, once per keyframe:
    // cheap enough for the tracking thread.
    const auto t_bow = std::chrono::steady_clock::now();
    std::lock_guard lock(map_.mutex());
    if (const auto& kf = tracker_->records().back().reference) database_->add(kf);
    timer_.add("keyframe_bow", ms_since(t_bow));
  }
  if (learning_ && learning_->options().mode != SaftLearningMode::kOffline) {
    // Training pairs from this frame's verified matches (saft_learning.hpp).
    const auto t_learn = std::chrono::steady_clock::now();
    if (out.new_keyframe) learning_->add_keyframe(frame_id, saft_->last_patches());
    if (out.state == TrackingState::kOk) {
      std::lock_guard lock(map_.mutex());
      learning_->prepare(tracker_->last_frame(), saft_->last_patches());
    }
    timer_.add("saft_prepare", ms_since(t_learn));
  }
  if (!options_.mapping_thread) {
    mapping_->run_pending();
    if (loop_closer_) loop_closer_->run_pending();
  }
  // Frame records must not keep culled keyframes (and their features) alive.
  const long culled = mapping_->stats().keyframes_culled;
  if (culled != culled_seen_) {
    culled_seen_ = culled;
    tracker_->compact_records();
    if (database_) {
      std::lock_guard lock(map_.mutex());
      database_->purge_bad();
    }
  }
  timer_.add("tracking", ms_since(t0));
  timer_.add("frame", ms_since(start));
  return out;
}

void System::floor_from_this_frame(const cv::Mat& depth_m) {
  {
    std::lock_guard lock(map_.mutex());
    if (map_.keyframe_count() > 0) {  // a loaded map: its world was fixed by another run
      floor_settled_ = true;
      return;
    }
  }
  // No keyframe exists yet, so neither local mapping nor loop closing reads the options.
  floor_ = estimate_floor_plane(depth_m, settings_.camera, planar_guess_);
  options_.planar.up_c = floor_ ? floor_->up_c : planar_guess_;
  tracker_->set_planar(options_.planar);
  mapping_->set_planar(options_.planar);
  if (loop_closer_) loop_closer_->set_planar(options_.planar);
}

void System::shutdown() {
  if (shut_down_) return;
  shut_down_ = true;
  if (learning_) learning_->finish();
  mapping_->run_pending();
  mapping_->finish();
  // After local mapping: its last keyframes still go through loop detection; then the final
  // bundle adjustment (when a loop was closed) leaves the best map the run can give.
  if (loop_closer_) {
    loop_closer_->finish();
    loop_closer_->refine_map();
  }
}

void System::on_loop_event(const LoopEvent& event) {
  std::vector<LoopEventSubscriber> subscribers;
  {
    std::lock_guard lock(events_mutex_);
    events_.push_back(event);
    subscribers = subscribers_;
  }
  for (const auto& s : subscribers) s(event);
}

void System::subscribe_loop_events(LoopEventSubscriber subscriber) {
  std::lock_guard lock(events_mutex_);
  subscribers_.push_back(std::move(subscriber));
}

std::vector<LoopEvent> System::loop_events() const {
  std::lock_guard lock(events_mutex_);
  return events_;
}

LoopCloser::Stats System::loop_closing_stats() const { return loop_closer_ ? loop_closer_->stats() : LoopCloser::Stats{}; }

SE3 System::record_pose(const Tracker::FrameRecord& r) const {
  // Walk up the spanning tree past culled keyframes (their pose relative to the parent was
  // frozen when they were culled).
  SE3 chain;  // T_cr accumulated through culled keyframes
  const KeyFrame* kf = r.reference.get();
  while (kf->bad && kf->parent) {
    chain = chain * kf->T_cp;
    kf = kf->parent.get();
  }
  return r.T_cr * (chain * kf->pose());
}

Trajectory System::trajectory() const {
  std::lock_guard lock(map_.mutex());
  Trajectory out;
  for (const auto& r : tracker_->records()) {
    if (!r.tracked || !r.reference) continue;
    out.push_back({r.timestamp, record_pose(r).inverse()});
  }
  return out;
}

std::optional<SE3> System::last_pose() const {
  std::lock_guard lock(map_.mutex());
  const auto& records = tracker_->records();
  if (records.empty() || !records.back().tracked || !records.back().reference) return std::nullopt;
  return record_pose(records.back()).inverse();
}

std::uint64_t vocabulary_checksum(const BowVocabulary& voc) {
  // FNV-1a over the tree (shape, word ids, weights, centres): any other vocabulary gives
  // other bag-of-words vectors, so a map must not be used with it.
  std::uint64_t h = 1469598103934665603ull;
  auto mix = [&h](const void* data, std::size_t n) {
    const auto* p = static_cast<const unsigned char*>(data);
    for (std::size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 1099511628211ull;
  };
  const int head[4] = {static_cast<int>(voc.kind()), voc.descriptor_cols(), voc.k(), voc.levels()};
  mix(head, sizeof head);
  for (std::size_t i = 0; i < voc.node_count(); ++i) {
    const auto& n = voc.node(i);
    mix(&n.parent, sizeof n.parent);
    mix(&n.word, sizeof n.word);
    mix(&n.weight, sizeof n.weight);
    const cv::Mat c = voc.centre(i).clone();
    mix(c.data, c.total() * c.elemSize());
  }
  return h == 0 ? 1 : h;  // 0 means "no vocabulary" in a map file
}

MapFileInfo System::load_map(const std::filesystem::path& path) {
  if (next_frame_id_ != 0) throw Failure("load_map: a map can only be loaded before the first frame");
  std::optional<std::uint64_t> checksum;
  if (vocabulary_) checksum = vocabulary_checksum(*vocabulary_);
  MapFileInfo info = read_map_file(path, map_, ctx_, checksum);
  if (database_) {
    // Bag-of-words vectors are not stored; the vocabulary in use recomputes them.
    const auto t0 = std::chrono::steady_clock::now();
    std::lock_guard lock(map_.mutex());
    for (const auto& kf : map_.keyframes()) database_->add(kf);
    timer_.add("map_bow", ms_since(t0));
  }
  // An empty saved map is a fresh start: tracking initializes a new one (in SLAM mode).
  if (info.keyframes > 0) tracker_->start_lost();
  return info;
}

MapFileInfo System::save_map(const std::filesystem::path& path) {
  mapping_->run_pending();
  if (options_.mapping_thread && !shut_down_) {
    // Let the mapping thread drain its queue so the saved map holds every keyframe complete.
    while (mapping_->queue_size() > 0 || !mapping_->accepts_keyframes())
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return write_map_file(path, map_, *ctx_, vocabulary_ ? vocabulary_checksum(*vocabulary_) : 0);
}

void System::set_mode(Mode mode, const std::string& reason) {
  if (mode == mode_) return;
  mode_switches_.push_back({next_frame_id_, last_timestamp_, mode_, mode, reason});
  mode_ = mode;
  tracker_->set_keyframe_creation(mode == Mode::kSlam);
}

Trajectory System::keyframe_trajectory() const {
  std::lock_guard lock(map_.mutex());
  Trajectory out;
  for (const auto& kf : map_.keyframes())
    if (!kf->bad) out.push_back({kf->timestamp, kf->pose_inverse()});
  return out;
}

std::size_t System::keyframe_count() const {
  std::lock_guard lock(map_.mutex());
  return map_.keyframe_count();
}

std::size_t System::map_point_count() const {
  std::lock_guard lock(map_.mutex());
  return map_.point_count();
}

long System::relocalization_attempts() const { return relocalizer_ ? relocalizer_->stats().attempts : 0; }

}  // namespace builtscene::slam
