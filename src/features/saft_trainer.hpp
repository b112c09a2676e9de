#pragma once
// Offline training of the SAFT network on a pool of generated patch pairs (the source's
// section 3.4.1 scheme: a Siamese network trained with a binary hinge loss on matching and
// non-matching pairs; here the decision is a learned affine function of the squared L2
// distance of the normalized descriptors, the distance the SLAM matches with).
#include <cstdint>
#include <functional>
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

}  // namespace builtscene
