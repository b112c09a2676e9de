#include "slam/system.hpp"

#include <chrono>

#include <opencv2/imgproc.hpp>

#include "core/errors.hpp"
#include "core/logging.hpp"
#include "features/bow_vocabulary.hpp"
#include "slam/key_frame.hpp"
#include "slam/keyframe_database.hpp"
#include "slam/relocalizer.hpp"

namespace builtscene::slam {

std::filesystem::path default_vocabulary_path() {
  for (const char* p : {BUILTSCENE_SOURCE_VOCABULARY, BUILTSCENE_INSTALLED_VOCABULARY})
    if (std::filesystem::is_regular_file(p)) return p;
  return {};
}

System::System(const RgbdCameraSettings& settings, SystemOptions options)
    : settings_(settings), options_(options), extractor_(options.orb) {
  ctx_ = FrameContext::make(settings_, extractor_.pyramid(), DescriptorMetric::orb());
  options_.tracking.max_frames_between_kf = std::max(1, static_cast<int>(std::lround(settings_.fps)));
  mapping_ = std::make_unique<LocalMapping>(map_, options_.mapping, &timer_);
  tracker_ = std::make_unique<Tracker>(ctx_, map_, mapping_.get(), options_.tracking, &timer_);
  const auto vocabulary_file = options_.vocabulary.empty() ? default_vocabulary_path() : options_.vocabulary;
  if (vocabulary_file.empty()) {
    spdlog::warn("no bag-of-words vocabulary (looked for {}): relocalization off", BUILTSCENE_SOURCE_VOCABULARY);
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
  }
  if (options_.mapping_thread) mapping_->start();
}

System::~System() {
  shutdown();
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
  auto features = make_rgbd_features(gray, depth_m, ctx_, extractor_);
  timer_.add("extraction", ms_since(start));
  const auto t0 = std::chrono::steady_clock::now();
  const int keypoints = static_cast<int>(features->size());
  Frame frame(next_frame_id_++, timestamp, std::move(features));
  TrackingOutcome out = tracker_->track(std::move(frame));
  out.keypoints = keypoints;
  if (database_ && out.new_keyframe) {
    // The new keyframe is the reference of the frame just recorded. Its bag of words (one
    // tree descent per descriptor) measured 1.2 ms median at load 16, once per keyframe:
    // cheap enough for the tracking thread.
    const auto t_bow = std::chrono::steady_clock::now();
    std::lock_guard lock(map_.mutex());
    if (const auto& kf = tracker_->records().back().reference) database_->add(kf);
    timer_.add("keyframe_bow", ms_since(t_bow));
  }
  if (!options_.mapping_thread) mapping_->run_pending();
  timer_.add("tracking", ms_since(t0));
  timer_.add("frame", ms_since(start));
  return out;
}

void System::shutdown() {
  if (shut_down_) return;
  shut_down_ = true;
  mapping_->run_pending();
  mapping_->finish();
}

Trajectory System::trajectory() const {
  std::lock_guard lock(map_.mutex());
  Trajectory out;
  for (const auto& r : tracker_->records()) {
    if (!r.tracked || !r.reference) continue;
    // Walk up the spanning tree past culled keyframes (their pose relative to the parent was
    // frozen when they were culled).
    SE3 T_rw;
    SE3 chain;  // T_cr accumulated through culled keyframes
    const KeyFrame* kf = r.reference.get();
    while (kf->bad && kf->parent) {
      chain = chain * kf->T_cp;
      kf = kf->parent.get();
    }
    T_rw = chain * kf->pose();
    const SE3 T_cw = r.T_cr * T_rw;
    out.push_back({r.timestamp, T_cw.inverse()});
  }
  return out;
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

}  // namespace builtscene::slam
