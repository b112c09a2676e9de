#pragma once
// Offline training of the SAFT network on a pool of generated patch pairs (the source's
// section 3.4.1 scheme: a Siamese network trained with a binary hinge loss on matching and
// non-matching pairs; here the decision is a learned affine function of the squared L2
// distance of the normalized descriptors, the distance the SLAM matches with).
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "features/saft_network.hpp"
#include "features/saft_pair_generator.hpp"

namespace builtscene {

enum class SaftLoss { kHinge, kTriplet };
SaftLoss parse_saft_loss(const std::string& name);  // "hinge" | "triplet"; InputError otherwise
std::string to_string(SaftLoss loss);

struct SaftTrainerOptions {
  int steps = 1500;
  int batch_pairs = 128;        // matching pairs per step (and as many non-matching ones)
  double learning_rate = 1e-3;  // Adam; divided by 10 for the last quarter of the steps
  double weight_decay = 5e-4;   // the source's L2 regularization
  SaftLoss loss = SaftLoss::kHinge;
  double triplet_margin = 1.0;
  std::uint64_t seed = 1;
  int threads = 1;
};

struct SaftTrainingStep {
  int step = 0;
  double loss = 0.0;
  double accuracy = 0.0;  // hinge: pairs on the right side of the decision; triplet: anchors closer to their positive
};

class SaftTrainer {
 public:
  // Trains `net` in place on rows of `pool`; `on_step` sees every step. Returns the last
  // steps' mean loss and accuracy.
  static SaftTrainingStep train(SaftNetwork& net, const SaftPairPool& pool, const SaftTrainerOptions& options,
                                const std::function<void(const SaftTrainingStep&)>& on_step = {});
};

// Online fine-tuning (the source's section 3.4.3): labelled pairs of 8-bit patches from the
// SLAM's verified matches: label +1 for two observations of one map point, -1 for two
// different map points.
struct SaftLabelledPairs {
  cv::Mat first, second;   // one sample_saft_patches row each
  std::vector<int> label;  // +1 / -1
  // Where each patch came from (frame id, keypoint index and pixel), for checks against
  // ground truth; optional for training.
  struct Source {
    long frame = -1;
    int keypoint = -1;
    cv::Point2f pixel;
  };
  std::vector<Source> first_source, second_source;
  int size() const { return first.rows; }
};

struct SaftOnlineOptions {
  double learning_rate = 1e-4;  // fixed, the source's online rate (SGD, momentum 0.9)
  double weight_decay = 5e-4;   // the source's L2 regularization
  double decision_learning_rate = 1e-2;  // the hinge decision's w and b
  // Weight of the anchor term: mean squared L2 distance between each descriptor and the one
  // the starting net gives the same patch. The hinge loss alone does not change when the
  // whole descriptor space turns, and without the anchor the descriptors wandered (after a
  // 300-frame run the same patch's descriptor had moved 0.60 in L2, median; 90 % of patches
  // changed their bag-of-words word), which breaks map points described earlier and place
  // recognition. 0 turns it off. docs/saft.md has the measurements.
  double anchor_weight = 1.0;
  int batch_pairs = 128;        // pairs per optimizer step
  // Before the first step, fit the hinge decision (w, b) to the starting net's distances on
  // the first batch (calibrate_decision), so the first steps move the descriptor only where
  // the net is wrong, not towards a decision that starts at arbitrary values (w = 2, b = 1).
  bool calibrate_decision = false;
  std::uint64_t seed = 1;
  int threads = 1;
};

// The hinge decision o = w (b - d^2) on squared descriptor distances d^2.
struct SaftDecision {
  double w = 2.0, b = 1.0;
};
// Mean hinge loss max(0, 1 - y w (b - d^2)) of the decision over labelled squared distances.
double saft_hinge_loss(const SaftDecision& decision, const std::vector<double>& d2, const std::vector<int>& label);
// The decision of least mean hinge loss over w in [0.5, 16] (a log grid, 2^(1/8) apart) and,
// for each w, the exact best b. Only a better loss than the default decision's replaces it;
// ties keep the smaller w. Empty input: the default decision.
SaftDecision fit_saft_decision(const std::vector<double>& d2, const std::vector<int>& label);

// Owns a copy of the network being fine-tuned (the prediction net stays the caller's), a
// frozen copy of the starting weights (the anchor), and the optimizer state across calls. Batch-norm statistics stay frozen at the pre-trained
// ones (the network runs in eval mode while it learns): online batches are small and all of
// one scene, and frozen statistics keep the fine-tuned transform close to the global one.
class SaftOnlineTrainer {
 public:
  SaftOnlineTrainer(const SaftNetwork& start, SaftOnlineOptions options = {});
  ~SaftOnlineTrainer();
  SaftOnlineTrainer(const SaftOnlineTrainer&) = delete;
  SaftOnlineTrainer& operator=(const SaftOnlineTrainer&) = delete;

  // One pass over `pairs`: shuffled, each pair flipped (horizontally or vertically) or
  // rotated (90, 180, 270 degrees) at random, one hinge-loss SGD step per batch_pairs pairs.
  // Returns the pass's mean loss and the accuracy measured before each step's update.
  SaftTrainingStep train(const SaftLabelledPairs& pairs);
  // Accuracy of the current weights on `pairs` (no augmentation, no update).
  double accuracy(const SaftLabelledPairs& pairs);
  // Squared L2 distances of the pairs' normalized descriptors under the current weights.
  std::vector<double> squared_distances(const SaftLabelledPairs& pairs);
  SaftDecision decision() const;
  // Sets the decision to fit_saft_decision on `pairs` with the current weights (the network
  // is not changed). train() does this itself before its first step when
  // SaftOnlineOptions::calibrate_decision is set.
  SaftDecision calibrate_decision(const SaftLabelledPairs& pairs);
  // One pass over `train`, kept only if the accuracy on `held` (pairs it does not train on)
  // did not fall; otherwise the trainer goes back to its state before the pass (restore()).
  struct CheckedStep {
    SaftTrainingStep step;
    double held_before = 0, held_after = 0;  // accuracy on `held`
    bool kept = false;
  };
  CheckedStep train_checked(const SaftLabelledPairs& train, const SaftLabelledPairs& held);
  std::vector<float> weights() const;  // for SaftNetwork::set_weights
  int steps() const;
  // The whole learned state (network weights and the hinge decision), and going back to one:
  // restore() also forgets the optimizer's momentum, so the refused direction is not retaken.
  std::vector<float> snapshot() const;
  void restore(const std::vector<float>& state);  // std::invalid_argument on a wrong size

 private:
  void calibrate_once(const SaftLabelledPairs& pairs);  // the first call's pairs, when the option is set
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// The same random flip or rotation applied to both patches of a pair (a 32 x 32 patch as
// one 8-bit row): op 0 keeps it, 1 flips horizontally, 2 vertically, 3/4/5 rotate by
// 90/180/270 degrees.
cv::Mat augment_saft_patch(const cv::Mat& row, int op);

}  // namespace builtscene
