#include "features/saft_trainer.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <random>

#include <opencv2/core.hpp>

#include "core/errors.hpp"
#include "features/saft_patch.hpp"
#include "features/saft_torch_net.hpp"

namespace builtscene {

SaftLoss parse_saft_loss(const std::string& name) {
  if (name == "hinge") return SaftLoss::kHinge;
  if (name == "triplet") return SaftLoss::kTriplet;
  throw InputError("--loss: '" + name + "' is not one of hinge, triplet");
}

std::string to_string(SaftLoss loss) { return loss == SaftLoss::kHinge ? "hinge" : "triplet"; }

namespace {

torch::Tensor to_tensor(const cv::Mat& normalized_patches) {
  return torch::from_blob(const_cast<float*>(normalized_patches.ptr<float>()),
                          {normalized_patches.rows, 1, kSaftPatchSize, kSaftPatchSize}, torch::kFloat32)
      .clone();
}

cv::Mat gather(const cv::Mat& rows, const std::vector<int>& index) {
  cv::Mat out(static_cast<int>(index.size()), rows.cols, rows.type());
  for (std::size_t i = 0; i < index.size(); ++i) rows.row(index[i]).copyTo(out.row(static_cast<int>(i)));
  return out;
}

bool same_point(const SaftPairPool& pool, int i, int j) {
  const auto ui = static_cast<std::size_t>(i), uj = static_cast<std::size_t>(j);
  if (pool.source[ui] != pool.source[uj]) return false;
  const cv::Point2f d = pool.position[ui] - pool.position[uj];
  return d.dot(d) < 12.0f * 12.0f;
}

}  // namespace

SaftTrainingStep SaftTrainer::train(SaftNetwork& network, const SaftPairPool& pool, const SaftTrainerOptions& o,
                                    const std::function<void(const SaftTrainingStep&)>& on_step) {
  if (pool.size() < 2 * o.batch_pairs) throw InputError("saft train: only " + std::to_string(pool.size()) + " pairs, need at least " +
                                                        std::to_string(2 * o.batch_pairs) + " (more images or keypoints)");
  if (o.steps < 1 || o.batch_pairs < 2) throw InputError("saft train: steps must be >= 1 and batch pairs >= 2");
  torch::set_num_threads(o.threads);
  torch::manual_seed(o.seed);
  std::mt19937_64 rng(o.seed);
  auto& net = network.impl_->net;
  net->train();
  // The hinge loss's decision o = w * (b - d^2): a two-parameter "decision network" on the
  // distance that matching will use.
  torch::Tensor w = torch::full({1}, 2.0, torch::requires_grad());
  torch::Tensor b = torch::full({1}, 1.0, torch::requires_grad());
  std::vector<torch::Tensor> params = net->parameters();
  params.push_back(w);
  params.push_back(b);
  torch::optim::Adam opt(params, torch::optim::AdamOptions(o.learning_rate).weight_decay(o.weight_decay));

  const int B = o.batch_pairs;
  std::uniform_int_distribution<int> pick(0, pool.size() - 1);
  SaftTrainingStep last;
  double tail_loss = 0.0, tail_acc = 0.0;
  int tail_n = 0;
  for (int step = 1; step <= o.steps; ++step) {
    if (step == o.steps * 3 / 4 + 1)
      for (auto& g : opt.param_groups()) static_cast<torch::optim::AdamOptions&>(g.options()).lr(o.learning_rate * 0.1);
    // B distinct keypoints: in-batch negatives must never pair a point with itself.
    std::vector<int> index;
    while (static_cast<int>(index.size()) < B) {
      const int i = pick(rng);
      bool clash = false;
      for (int j : index) clash = clash || same_point(pool, i, j);
      if (!clash) index.push_back(i);
    }
    const torch::Tensor x = torch::cat({to_tensor(normalize_saft_patches(gather(pool.first, index))),
                                        to_tensor(normalize_saft_patches(gather(pool.second, index)))});
    const torch::Tensor d = torch::nn::functional::normalize(net->forward(x), torch::nn::functional::NormalizeFuncOptions().dim(1));
    const torch::Tensor a = d.narrow(0, 0, B), p = d.narrow(0, B, B);
    torch::Tensor loss, correct;
    if (o.loss == SaftLoss::kHinge) {
      // Matching pairs (a_i, p_i) with label +1, non-matching (a_i, p_{i+1}) with label -1.
      const torch::Tensor d2_pos = (a - p).pow(2).sum(1);
      const torch::Tensor d2_neg = (a - p.roll(1, 0)).pow(2).sum(1);
      const torch::Tensor o_pos = w * (b - d2_pos), o_neg = w * (b - d2_neg);
      loss = torch::cat({torch::relu(1 - o_pos), torch::relu(1 + o_neg)}).mean();
      correct = torch::cat({o_pos > 0, o_neg < 0}).to(torch::kFloat32).mean();
    } else {
      // Hardest in batch (HardNet): the closest non-matching descriptor in the anchor's row
      // or the positive's column.
      const torch::Tensor dist = torch::cdist(a, p);
      const torch::Tensor pos = dist.diagonal();
      const torch::Tensor masked = dist + torch::eye(B) * 10.0;
      const torch::Tensor hardest = torch::min(std::get<0>(masked.min(1)), std::get<0>(masked.min(0)));
      loss = torch::relu(o.triplet_margin + pos - hardest).mean();
      correct = (pos < hardest).to(torch::kFloat32).mean();
    }
    opt.zero_grad();
    loss.backward();
    opt.step();
    last.step = step;
    last.loss = loss.item<double>();
    last.accuracy = correct.item<double>();
    if (step > o.steps - std::max(1, o.steps / 10)) {
      tail_loss += last.loss;
      tail_acc += last.accuracy;
      ++tail_n;
    }
    if (on_step) on_step(last);
  }
  net->eval();
  last.loss = tail_loss / tail_n;
  last.accuracy = tail_acc / tail_n;
  return last;
}

cv::Mat augment_saft_patch(const cv::Mat& row, int op) {
  CV_Assert(row.rows == 1 && row.cols == kSaftPatchPixels && row.type() == CV_8U);
  const cv::Mat square = row.reshape(1, kSaftPatchSize);
  cv::Mat out;
  switch (op) {
    case 1: cv::flip(square, out, 1); break;
    case 2: cv::flip(square, out, 0); break;
    case 3: cv::rotate(square, out, cv::ROTATE_90_CLOCKWISE); break;
    case 4: cv::rotate(square, out, cv::ROTATE_180); break;
    case 5: cv::rotate(square, out, cv::ROTATE_90_COUNTERCLOCKWISE); break;
    default: out = square.clone();
  }
  return out.reshape(1, 1);
}

struct SaftOnlineTrainer::Impl {
  Impl(const SaftNetwork& start, const SaftOnlineOptions& o)
      : options(o),
        network(SaftNetworkOptions{.batch_size = 1, .threads = o.threads}),
        reference(SaftNetworkOptions{.batch_size = 1, .threads = o.threads}),
        rng(o.seed) {
    network.set_weights(start.weights());
    reference.set_weights(start.weights());
    // SGD with momentum 0.9 and weight decay 5e-4 (the source's solver) on the network; the
    // two decision parameters learn faster, so the decision follows the descriptor rather
    // than the descriptor being bent to a decision that starts at arbitrary values.
    std::vector<torch::optim::OptimizerParamGroup> groups;
    groups.emplace_back(network.impl_->net->parameters(),
                        std::make_unique<torch::optim::SGDOptions>(
                            torch::optim::SGDOptions(o.learning_rate).momentum(0.9).weight_decay(o.weight_decay)));
    groups.emplace_back(std::vector<torch::Tensor>{w, b},
                        std::make_unique<torch::optim::SGDOptions>(torch::optim::SGDOptions(o.decision_learning_rate).momentum(0.9)));
    optimizer = std::make_unique<torch::optim::SGD>(std::move(groups), torch::optim::SGDOptions(o.learning_rate));
  }
  SaftOnlineOptions options;
  SaftNetwork network;
  SaftNetwork reference;  // the starting weights, frozen: the anchor of the descriptor space
  // The hinge decision o = w (b - d^2), as offline; starts where offline training starts.
  torch::Tensor w = torch::full({1}, 2.0, torch::requires_grad());
  torch::Tensor b = torch::full({1}, 1.0, torch::requires_grad());
  std::unique_ptr<torch::optim::SGD> optimizer;
  std::mt19937_64 rng;
  int steps = 0;
  bool calibrated = false;

  // Hinge loss and accuracy of pairs [index] (first / second already augmented rows).
  // Plus, when anchored, anchor_weight times the mean squared distance of each descriptor to
  // the reference net's descriptor of the same patch.
  // The pairs' patches as one input batch (first rows, then second rows), their normalized
  // descriptors under the current weights, and each pair's squared distance.
  struct DescribedPairs {
    torch::Tensor x, d, d2;
  };
  DescribedPairs describe_pairs(const cv::Mat& first, const cv::Mat& second) {
    const int n = first.rows;
    DescribedPairs out;
    out.x = torch::cat({to_tensor(normalize_saft_patches(first)), to_tensor(normalize_saft_patches(second))});
    out.d = torch::nn::functional::normalize(network.impl_->net->forward(out.x), kUnitRows);
    out.d2 = (out.d.narrow(0, 0, n) - out.d.narrow(0, n, n)).pow(2).sum(1);
    return out;
  }
  static inline const auto kUnitRows = torch::nn::functional::NormalizeFuncOptions().dim(1);

  std::pair<torch::Tensor, double> loss_of(const cv::Mat& first, const cv::Mat& second, const std::vector<int>& labels,
                                           bool anchored) {
    const int n = first.rows;
    const auto [x, d, d2] = describe_pairs(first, second);
    std::vector<float> y(labels.begin(), labels.end());
    const torch::Tensor yt = torch::from_blob(y.data(), {n}, torch::kFloat32).clone();
    const torch::Tensor o = w * (b - d2);
    torch::Tensor loss = torch::relu(1 - yt * o).mean();
    if (anchored && options.anchor_weight > 0) {
      torch::Tensor r;
      {
        torch::NoGradGuard no_grad;
        reference.impl_->net->eval();
        r = torch::nn::functional::normalize(reference.impl_->net->forward(x), kUnitRows);
      }
      loss = loss + options.anchor_weight * (d - r).pow(2).sum(1).mean();
    }
    const double acc = (yt * o > 0).to(torch::kFloat32).mean().item<double>();
    return {loss, acc};
  }
};

SaftOnlineTrainer::SaftOnlineTrainer(const SaftNetwork& start, SaftOnlineOptions options)
    : impl_(std::make_unique<Impl>(start, options)) {
  if (options.batch_pairs < 2) throw InputError("SAFT online learning: batch pairs must be at least 2");
}

SaftOnlineTrainer::~SaftOnlineTrainer() = default;

double saft_hinge_loss(const SaftDecision& decision, const std::vector<double>& d2, const std::vector<int>& label) {
  CV_Assert(d2.size() == label.size());
  if (d2.empty()) return 0.0;
  double sum = 0;
  for (std::size_t i = 0; i < d2.size(); ++i) sum += std::max(0.0, 1.0 - label[i] * decision.w * (decision.b - d2[i]));
  return sum / static_cast<double>(d2.size());
}

SaftDecision fit_saft_decision(const std::vector<double>& d2, const std::vector<int>& label) {
  CV_Assert(d2.size() == label.size());
  SaftDecision best;
  if (d2.empty()) return best;
  double best_loss = saft_hinge_loss(best, d2, label);
  for (int k = -8; k <= 32; ++k) {  // w = 2^(k/8): 0.5 ... 16
    const double w = std::pow(2.0, k / 8.0);
    // For a fixed w the mean hinge is convex and piecewise linear in b, with its kinks where a
    // pair sits exactly on its margin (b = d^2 +- 1/w): its least value is at one of them.
    for (const double d : d2)
      for (const double b : {d - 1.0 / w, d + 1.0 / w}) {
        const double loss = saft_hinge_loss({w, b}, d2, label);
        if (loss < best_loss - 1e-12) best_loss = loss, best = {w, b};
      }
  }
  return best;
}

std::vector<double> SaftOnlineTrainer::squared_distances(const SaftLabelledPairs& pairs) {
  std::vector<double> out;
  const int n = pairs.size();
  if (n == 0) return out;
  torch::set_num_threads(impl_->options.threads);
  c10::InferenceMode guard;
  impl_->network.impl_->net->eval();
  const torch::Tensor d2 = impl_->describe_pairs(pairs.first, pairs.second).d2.contiguous();
  out.assign(d2.data_ptr<float>(), d2.data_ptr<float>() + n);
  return out;
}

SaftDecision SaftOnlineTrainer::decision() const { return {impl_->w.item<double>(), impl_->b.item<double>()}; }

SaftDecision SaftOnlineTrainer::calibrate_decision(const SaftLabelledPairs& pairs) {
  const SaftDecision fit = fit_saft_decision(squared_distances(pairs), pairs.label);
  torch::NoGradGuard no_grad;
  impl_->w.fill_(fit.w);
  impl_->b.fill_(fit.b);
  return fit;
}

void SaftOnlineTrainer::calibrate_once(const SaftLabelledPairs& pairs) {
  if (!impl_->options.calibrate_decision || impl_->calibrated || pairs.size() == 0) return;
  calibrate_decision(pairs);
  impl_->calibrated = true;
}

SaftTrainingStep SaftOnlineTrainer::train(const SaftLabelledPairs& pairs) {
  SaftTrainingStep result;
  const int n = pairs.size();
  if (n == 0) return result;
  CV_Assert(pairs.second.rows == n && static_cast<int>(pairs.label.size()) == n);
  calibrate_once(pairs);
  torch::set_num_threads(impl_->options.threads);
  auto& net = impl_->network.impl_->net;
  net->eval();  // frozen batch-norm statistics, see the header
  std::vector<int> order(static_cast<std::size_t>(n));
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), impl_->rng);
  std::uniform_int_distribution<int> pick_op(0, 5);
  double loss_sum = 0, acc_sum = 0;
  int batches = 0;
  for (int start = 0; start < n; start += impl_->options.batch_pairs) {
    const int m = std::min(impl_->options.batch_pairs, n - start);
    cv::Mat first(m, kSaftPatchPixels, CV_8U), second(m, kSaftPatchPixels, CV_8U);
    std::vector<int> labels(static_cast<std::size_t>(m));
    for (int k = 0; k < m; ++k) {
      const int i = order[static_cast<std::size_t>(start + k)];
      const int op = pick_op(impl_->rng);
      augment_saft_patch(pairs.first.row(i), op).copyTo(first.row(k));
      augment_saft_patch(pairs.second.row(i), op).copyTo(second.row(k));
      labels[static_cast<std::size_t>(k)] = pairs.label[static_cast<std::size_t>(i)];
    }
    auto [loss, acc] = impl_->loss_of(first, second, labels, /*anchored=*/true);
    impl_->optimizer->zero_grad();
    loss.backward();
    impl_->optimizer->step();
    ++impl_->steps;
    loss_sum += loss.item<double>();
    acc_sum += acc;
    ++batches;
  }
  result.step = impl_->steps;
  result.loss = loss_sum / batches;
  result.accuracy = acc_sum / batches;
  return result;
}

double SaftOnlineTrainer::accuracy(const SaftLabelledPairs& pairs) {
  if (pairs.size() == 0) return 0.0;
  torch::set_num_threads(impl_->options.threads);
  c10::InferenceMode guard;
  impl_->network.impl_->net->eval();
  return impl_->loss_of(pairs.first, pairs.second, pairs.label, /*anchored=*/false).second;
}

SaftOnlineTrainer::CheckedStep SaftOnlineTrainer::train_checked(const SaftLabelledPairs& train,
                                                                const SaftLabelledPairs& held) {
  CheckedStep out;
  calibrate_once(train);  // before the snapshot: a refused first pass keeps the calibration
  const std::vector<float> before = snapshot();
  out.held_before = accuracy(held);
  out.step = this->train(train);
  out.held_after = accuracy(held);
  out.kept = out.held_after >= out.held_before;
  if (!out.kept) restore(before);
  return out;
}

std::vector<float> SaftOnlineTrainer::weights() const { return impl_->network.weights(); }

int SaftOnlineTrainer::steps() const { return impl_->steps; }

std::vector<float> SaftOnlineTrainer::snapshot() const {
  std::vector<float> state = impl_->network.weights();
  state.push_back(impl_->w.item<float>());
  state.push_back(impl_->b.item<float>());
  return state;
}

void SaftOnlineTrainer::restore(const std::vector<float>& state) {
  if (state.size() < 2) throw std::invalid_argument("SAFT online trainer: state too short");
  impl_->network.set_weights(std::vector<float>(state.begin(), state.end() - 2));
  {
    torch::NoGradGuard no_grad;
    impl_->w.fill_(state[state.size() - 2]);
    impl_->b.fill_(state[state.size() - 1]);
  }
  impl_->optimizer->state().clear();  // momentum buffers start again from zero
}

}  // namespace builtscene
