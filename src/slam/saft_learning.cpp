#include "slam/saft_learning.hpp"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <algorithm>
#include <random>

#include "core/errors.hpp"
#include "core/logging.hpp"
#include "features/saft_extractor.hpp"
#include "features/saft_patch.hpp"
#include "slam/frame.hpp"
#include "slam/key_frame.hpp"
#include "slam/map_point.hpp"

namespace builtscene::slam {

SaftLearningMode parse_saft_learning_mode(const std::string& name) {
  if (name == "offline") return SaftLearningMode::kOffline;
  if (name == "continuous") return SaftLearningMode::kContinuous;
  if (name == "discrete") return SaftLearningMode::kDiscrete;
  throw InputError("--saft-mode: '" + name + "' is not one of offline, continuous, discrete");
}

std::string to_string(SaftLearningMode mode) {
  switch (mode) {
    case SaftLearningMode::kContinuous: return "continuous";
    case SaftLearningMode::kDiscrete: return "discrete";
    default: return "offline";
  }
}

SaftLearning::SaftLearning(SaftExtractor& extractor, SaftLearningOptions options)
    : extractor_(extractor), options_(options), rng_state_(options.seed) {
  if (options_.positive_pairs < 2 || options_.min_positive_pairs < 1 || options_.patch_keyframes < 1 ||
      options_.max_passes < 1 || !(options_.learning_rate > 0))
    throw InputError("SAFT learning: positive_pairs >= 2, min_positive_pairs >= 1, patch_keyframes >= 1, max_passes >= 1 and "
                     "a positive learning rate are required");
  if (options_.mode == SaftLearningMode::kOffline) return;
  trainer_ = std::make_unique<SaftOnlineTrainer>(
      extractor_.network(), SaftOnlineOptions{.learning_rate = options_.learning_rate, .anchor_weight = options_.anchor_weight, .batch_pairs = 128,
                                            .calibrate_decision = options_.calibrate_decision,
                                            .seed = options_.seed});
  if (!options_.synchronous) thread_ = std::thread([this] { run(); });
}

SaftLearning::~SaftLearning() { finish(); }

void SaftLearning::finish() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void SaftLearning::add_keyframe(long frame_id, const cv::Mat& patches) {
  if (options_.mode == SaftLearningMode::kOffline) return;
  keyframe_patches_.emplace_back(frame_id, patches);
  while (static_cast<int>(keyframe_patches_.size()) > options_.patch_keyframes) keyframe_patches_.pop_front();
}

const cv::Mat* SaftLearning::patches_of(long frame_id) const {
  // Few keyframes, newest last: search from the back.
  for (auto it = keyframe_patches_.rbegin(); it != keyframe_patches_.rend(); ++it)
    if (it->first == frame_id) return &it->second;
  return nullptr;
}

SaftLabelledPairs SaftLearning::make_pairs(const Frame& frame, const cv::Mat& patches) {
  std::mt19937_64 rng(rng_state_++);
  // Observation lists: per map point of the frame, rows of (patch matrix, row index).
  struct Ref {
    const cv::Mat* patches;
    int row;
    SaftLabelledPairs::Source source;
  };
  std::vector<std::vector<Ref>> lists;
  for (std::size_t i = 0; i < frame.points.size(); ++i) {
    const auto& p = frame.points[i];
    if (!p || p->bad || frame.outlier[i] || static_cast<int>(i) >= patches.rows) continue;
    std::vector<Ref> list{{&patches, static_cast<int>(i), {frame.id, static_cast<int>(i), frame.f->keys[i].pt}}};
    for (const auto& [kf, index] : p->observations) {
      if (kf->frame_id == frame.id) continue;
      const cv::Mat* kp = patches_of(kf->frame_id);
      if (kp && index >= 0 && index < kp->rows)
        list.push_back({kp, index, {kf->frame_id, index, kf->f->keys[static_cast<std::size_t>(index)].pt}});
    }
    if (list.size() >= 2) lists.push_back(std::move(list));
  }
  SaftLabelledPairs out;
  const int positives = std::min<int>(options_.positive_pairs, static_cast<int>(lists.size()));
  if (positives < options_.min_positive_pairs || lists.size() < 2) return out;
  std::shuffle(lists.begin(), lists.end(), rng);
  out.first.create(2 * positives, kSaftPatchPixels, CV_8U);
  out.second.create(2 * positives, kSaftPatchPixels, CV_8U);
  out.label.resize(static_cast<std::size_t>(2 * positives));
  out.first_source.resize(out.label.size());
  out.second_source.resize(out.label.size());
  auto put = [&](int row, const Ref& a, const Ref& b, int label) {
    a.patches->row(a.row).copyTo(out.first.row(row));
    b.patches->row(b.row).copyTo(out.second.row(row));
    const auto r = static_cast<std::size_t>(row);
    out.label[r] = label;
    out.first_source[r] = a.source;
    out.second_source[r] = b.source;
  };
  auto pick = [&](const std::vector<Ref>& list) {
    return list[std::uniform_int_distribution<std::size_t>(0, list.size() - 1)(rng)];
  };
  std::uniform_int_distribution<std::size_t> any_list(0, lists.size() - 1);
  for (int k = 0; k < positives; ++k) {
    // Positive: two different patches of one map point.
    const auto& list = lists[static_cast<std::size_t>(k)];
    const std::size_t a = std::uniform_int_distribution<std::size_t>(0, list.size() - 1)(rng);
    std::size_t b = std::uniform_int_distribution<std::size_t>(0, list.size() - 2)(rng);
    if (b >= a) ++b;
    put(2 * k, list[a], list[b], +1);
    // Negative: patches of two different map points.
    std::size_t other = any_list(rng);
    if (other == static_cast<std::size_t>(k)) other = (other + 1) % lists.size();
    put(2 * k + 1, pick(list), pick(lists[other]), -1);
  }
  return out;
}

void SaftLearning::prepare(const Frame& frame, const cv::Mat& patches) {
  if (options_.mode == SaftLearningMode::kOffline) return;
  SaftLabelledPairs pairs = make_pairs(frame, patches);
  if (options_.on_batch && pairs.size() > 0) options_.on_batch(pairs);
  {
    std::lock_guard lock(mutex_);
    ++stats_.frames;
    if (pairs.size() == 0) return;
    ++stats_.batches_prepared;
    if (options_.synchronous) {
      ++stats_.batches_trained;
    } else {
      if (slot_) ++stats_.batches_dropped;
      slot_ = std::move(pairs);
      wake_.notify_one();
      return;
    }
  }
  train(pairs);  // synchronous: in this thread, before the next frame
}

bool SaftLearning::install_weights() {
  std::optional<std::vector<float>> w;
  {
    std::lock_guard lock(mutex_);
    if (!published_) return false;
    w.swap(published_);
    ++stats_.weight_updates;
  }
  extractor_.network().set_weights(*w);
  return true;
}

SaftLearning::Stats SaftLearning::stats() const {
  std::lock_guard lock(mutex_);
  return stats_;
}

void SaftLearning::run() {
  // Below tracking and local mapping: learning takes the CPU they leave.
  setpriority(PRIO_PROCESS, static_cast<id_t>(syscall(SYS_gettid)), 10);
  for (;;) {
    SaftLabelledPairs batch;
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [this] { return stop_ || slot_.has_value(); });
      if (stop_) return;
      batch = std::move(*slot_);
      slot_.reset();
      ++stats_.batches_trained;
    }
    if (!train(batch)) return;
  }
}

std::pair<SaftLabelledPairs, SaftLabelledPairs> hold_out_pairs(const SaftLabelledPairs& batch, int every) {
  SaftLabelledPairs train, held;
  for (int i = 0; i < batch.size(); ++i) {
    SaftLabelledPairs& to = (i / 2) % every == 0 ? held : train;
    to.first.push_back(batch.first.row(i));
    to.second.push_back(batch.second.row(i));
    to.label.push_back(batch.label[static_cast<std::size_t>(i)]);
  }
  return {std::move(train), std::move(held)};
}

bool SaftLearning::train(const SaftLabelledPairs& batch) {
  // Continuous: one pass, then publish. Discrete: pass over the batch until the target
  // accuracy or max_passes, then publish (both modes publish after every consumed batch;
  // discrete's weights come later and fit an older batch more closely). Continuous with the
  // hand-over check: one pass over three quarters, published only if the held-out quarter's
  // accuracy did not fall (else the trainer is back where it was).
  const bool checked = options_.handover_check && options_.mode == SaftLearningMode::kContinuous && batch.size() >= 8;
  const int passes = options_.mode == SaftLearningMode::kDiscrete ? std::max(1, options_.max_passes) : 1;
  bool publish = true;
  for (int pass = 0; pass < passes; ++pass) {
    SaftTrainingStep step;
    if (checked) {
      const auto [part, held] = hold_out_pairs(batch, 4);
      const auto result = trainer_->train_checked(part, held);
      step = result.step;
      publish = result.kept;
    } else {
      step = trainer_->train(batch);
    }
    std::lock_guard lock(mutex_);
    ++stats_.passes;
    const SaftDecision decision = trainer_->decision();
    if (stats_.passes == 1) stats_.first_accuracy = step.accuracy, stats_.first_decision = decision;
    stats_.last_accuracy = step.accuracy;
    stats_.last_decision = decision;
    if (stop_) return false;
    if (options_.mode == SaftLearningMode::kDiscrete && step.accuracy >= options_.target_accuracy) {
      ++stats_.target_reached;
      break;
    }
  }
  if (!publish) {
    std::lock_guard lock(mutex_);
    ++stats_.handovers_refused;
    return true;
  }
  std::vector<float> w = trainer_->weights();
  std::lock_guard lock(mutex_);
  published_ = std::move(w);
  return true;
}

}  // namespace builtscene::slam
