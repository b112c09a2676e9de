#pragma once
// Online SAFT learning inside the SLAM (the source's section 3.4.3).
//
// Tracking thread, after each tracked frame (map lock held): prepare() turns the frame's
// inlier map points into labelled patch pairs. For every map point the frame matched, its
// observation list is the frame's patch plus the patches of the recent keyframes that observe
// it; a positive pair is two patches of one list, a negative pair patches of two lists, as
// many negatives as positives. The batch goes into a one-slot LIFO: the newest batch
// replaces one the learning thread has not taken yet (counted as dropped).
//
// Learning thread: takes the newest batch, fine-tunes its own copy of the network
// (SaftOnlineTrainer: flips and rotations, fixed learning rate), and publishes weights:
//   continuous  after every consumed batch (one pass over it);
//   discrete    after passing over one batch until a pass reaches `target_accuracy` or
//               `max_passes` passes are done, whichever comes first: the source's "delayed
//               overfitting" (it waits for accuracy 1.00; with the anchor below a batch rarely
//               passes 0.9, so a target alone would never release any weights);
//   offline     no learning thread; the pre-trained net stays.
// Tracking thread, before extracting the next frame: install_weights() copies published
// weights into the prediction net (a copy of ~90k floats: tracking never waits for training).
// The thread runs at a lower scheduling priority (nice +10), so it uses what tracking and
// local mapping leave of the CPU.
//
// Map-point descriptors are not re-computed when the net changes, and the bag of words keeps
// the vocabulary trained with the pre-trained net. That stays valid because the fine-tuning
// is anchored: its loss includes the distance of every descriptor to the one the pre-trained
// net gives the same patch (SaftOnlineOptions::anchor_weight), so the net adapts to the scene
// without turning its descriptor space away. `builtscene saft drift` measures how far the
// descriptors of a run's final weights are from the pre-trained ones (docs/saft.md).
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "features/saft_trainer.hpp"

namespace builtscene {
class SaftExtractor;
}

namespace builtscene::slam {

class Frame;

enum class SaftLearningMode { kOffline, kContinuous, kDiscrete };
SaftLearningMode parse_saft_learning_mode(const std::string& name);  // offline|continuous|discrete; InputError
std::string to_string(SaftLearningMode mode);

struct SaftLearningOptions {
  SaftLearningMode mode = SaftLearningMode::kOffline;
  double learning_rate = 1e-4;
  double anchor_weight = 1.0;     // see SaftOnlineOptions::anchor_weight
  int positive_pairs = 128;       // per prepared batch (and as many negatives)
  int min_positive_pairs = 16;    // fewer: no batch from this frame
  double target_accuracy = 0.98;  // discrete mode: a pass this accurate releases the weights
  int max_passes = 20;            // discrete mode: ... and so does the last pass over one batch
  int patch_keyframes = 30;       // newest keyframes whose patches are kept (1 KB per keypoint)
  // Continuous mode: a quarter of a batch's pairs (balanced) is held out; after the pass over the others the
  // weights are handed over only if the accuracy on the held-out pairs did not fall,
  // else the learner goes back to the weights it had (and drops its momentum). Off: the source's hand-over after
  // every batch.
  bool handover_check = false;
  // See SaftOnlineOptions::calibrate_decision: fit the hinge decision to the pre-trained net on the first batch.
  bool calibrate_decision = false;
  // No learning thread: prepare() trains on each batch itself, so the weights a frame is
  // described with depend on the frames alone (reproducible runs: `--sync-mapping`; tests).
  // Much slower, and no batch is ever dropped.
  bool synchronous = false;
  std::uint64_t seed = 1;
  // Sees every prepared batch in the tracking thread (tests check pairs against ground truth).
  std::function<void(const SaftLabelledPairs&)> on_batch;
};

// The hand-over check's split: every `every`-th couple of rows held out (second), the others
// to train on (first). make_pairs() writes a map point's positive pair in row 2k and a negative
// pair from the same point in row 2k + 1, so couples keep the held-out part balanced (a first
// version held out every 4th row: only positive pairs). Pair sources are left out.
std::pair<SaftLabelledPairs, SaftLabelledPairs> hold_out_pairs(const SaftLabelledPairs& batch, int every);

class SaftLearning {
 public:
  struct Stats {
    long frames = 0;            // frames prepare() saw
    long batches_prepared = 0;
    long batches_dropped = 0;   // replaced in the LIFO before the learner took them
    long batches_trained = 0;   // taken by the learner
    long passes = 0;            // training passes (discrete: several per batch)
    long weight_updates = 0;    // weights installed in the prediction net
    long target_reached = 0;    // discrete: batches released by target_accuracy (the others by max_passes)
    long handovers_refused = 0; // handover_check: batches whose held-out accuracy fell (weights kept back)
    double last_accuracy = 0;   // of the last pass
    SaftDecision first_decision, last_decision;  // the hinge decision after the first and the last pass
    double first_accuracy = 0;  // of the first pass (the pre-trained net on this scene)
  };

  // `extractor` is the SLAM's prediction net; it must outlive this object.
  SaftLearning(SaftExtractor& extractor, SaftLearningOptions options);
  ~SaftLearning();
  SaftLearning(const SaftLearning&) = delete;
  SaftLearning& operator=(const SaftLearning&) = delete;

  const SaftLearningOptions& options() const { return options_; }

  // Tracking thread. The patches of the frame just extracted (SaftExtractor::last_patches).
  void add_keyframe(long frame_id, const cv::Mat& patches);
  // Tracking thread, map lock held, `frame` tracked: prepares and queues a batch (synchronous:
  // trains on it).
  void prepare(const Frame& frame, const cv::Mat& patches);
  // Tracking thread, before extraction: installs weights published since the last call.
  bool install_weights();
  // Stops the learning thread (idempotent).
  void finish();
  Stats stats() const;

  // Labelled pairs prepare() would queue for this frame (exposed for tests).
  SaftLabelledPairs make_pairs(const Frame& frame, const cv::Mat& patches);

 private:
  SaftExtractor& extractor_;
  SaftLearningOptions options_;
  std::deque<std::pair<long, cv::Mat>> keyframe_patches_;  // (frame id, patches), newest last
  const cv::Mat* patches_of(long frame_id) const;
  std::uint64_t rng_state_;

  mutable std::mutex mutex_;  // guards everything below
  std::condition_variable wake_;
  std::optional<SaftLabelledPairs> slot_;
  std::optional<std::vector<float>> published_;
  bool stop_ = false;
  Stats stats_;
  std::unique_ptr<SaftOnlineTrainer> trainer_;  // learning thread only, or prepare() when synchronous
  std::thread thread_;
  void run();
  // One batch: its passes, then the weights go to the hand-over slot. False when stopped.
  bool train(const SaftLabelledPairs& batch);
};

}  // namespace builtscene::slam
