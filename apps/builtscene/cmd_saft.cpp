// `builtscene saft train` and `builtscene saft eval`: the learned SAFT descriptor (issue 8).
#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>
#include <random>

#include <opencv2/imgcodecs.hpp>

#include "command_registry.hpp"
#include "core/errors.hpp"
#include "core/logging.hpp"
#include "core/progress.hpp"
#include "core/stage_timer.hpp"
#include "features/descriptor.hpp"
#include "features/descriptor_roc.hpp"
#include "features/patch_verification.hpp"
#include "features/saft_network.hpp"
#include "features/saft_patch.hpp"
#include "features/saft_trainer.hpp"

namespace builtscene::app {
namespace {

namespace fs = std::filesystem;

struct TrainOptions {
  std::vector<std::string> images;
  std::string out;
  int every = 5;
  double validation = 0.15;
  SaftPairGeneratorOptions pairs;
  SaftTrainerOptions trainer;
  std::string loss = "hinge";
};

bool is_image(const fs::path& p) {
  std::string e = p.extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return e == ".png" || e == ".jpg" || e == ".jpeg";
}

// Every `every`-th image of a folder (or of its rgb/ subfolder: a TUM-layout world), by name.
std::vector<fs::path> training_images(const fs::path& dir, int every) {
  if (!fs::is_directory(dir)) throw InputError(dir.string() + ": --images: not a folder");
  // The HPatches-style sequences are the held-out evaluation set.
  if (fs::exists(dir / "H_1_2")) throw InputError(dir.string() + ": --images: a homography sequence (H_1_2), held out for saft eval");
  const fs::path from = fs::is_directory(dir / "rgb") ? dir / "rgb" : dir;
  std::vector<fs::path> all;
  for (const auto& e : fs::directory_iterator(from))
    if (e.is_regular_file() && is_image(e.path())) all.push_back(e.path());
  std::sort(all.begin(), all.end());
  std::vector<fs::path> out;
  for (std::size_t i = 0; i < all.size(); i += static_cast<std::size_t>(every)) out.push_back(all[i]);
  if (out.empty()) throw InputError(from.string() + ": --images: no .png or .jpg images");
  return out;
}

nlohmann::json roc_json(const std::vector<double>& pos, const std::vector<double>& neg) {
  const RocPoint r = fpr_at_tpr(pos, neg, 0.95);
  return {{"fpr95", r.fpr}, {"threshold95", r.threshold}};
}

nlohmann::json run_train(TrainOptions o) {
  StageTimer timer;
  o.trainer.loss = parse_saft_loss(o.loss);
  if (o.every < 1) throw InputError("--every: must be at least 1");
  if (!(o.validation >= 0.0 && o.validation < 0.9)) throw InputError("--validation: must be in [0, 0.9)");
  std::vector<cv::Mat> images;
  {
    auto t = timer.scope("load_images");
    for (const auto& d : o.images)
      for (const auto& p : training_images(d, o.every)) {
        cv::Mat g = cv::imread(p.string(), cv::IMREAD_GRAYSCALE);
        if (g.empty()) throw InputError(p.string() + ": not a readable image");
        images.push_back(g);
      }
  }
  // Validation images are whole images (every k-th), never warps of a training image.
  std::vector<cv::Mat> train_set, val_set;
  const int val_every = o.validation > 0.0 ? std::max(2, static_cast<int>(std::lround(1.0 / o.validation))) : 0;
  for (std::size_t i = 0; i < images.size(); ++i)
    (val_every > 0 && i % static_cast<std::size_t>(val_every) == static_cast<std::size_t>(val_every - 1) ? val_set : train_set).push_back(images[i]);
  spdlog::info("{} training images, {} validation images", train_set.size(), val_set.size());

  SaftPairPool pool, val_pool;
  {
    auto t = timer.scope("generate_pairs");
    pool = generate_saft_pairs(train_set, o.pairs);
    SaftPairGeneratorOptions vo = o.pairs;
    vo.seed = o.pairs.seed + 1000003;
    if (!val_set.empty()) val_pool = generate_saft_pairs(val_set, vo);
  }
  spdlog::info("{} training pairs, {} validation pairs", pool.size(), val_pool.size());

  SaftNetwork net({}, static_cast<unsigned>(o.trainer.seed));
  SaftTrainingStep final_step;
  {
    auto t = timer.scope("train");
    Progress progress("saft train", static_cast<std::size_t>(o.trainer.steps));
    final_step = SaftTrainer::train(net, pool, o.trainer, [&](const SaftTrainingStep& s) {
      progress.update(static_cast<std::size_t>(s.step));
      if (s.step % 100 == 0 || s.step == 1) spdlog::info("step {:5d}: loss {:.4f}, accuracy {:.3f}", s.step, s.loss, s.accuracy);
    });
    progress.finish();
  }
  net.save(o.out);
  nlohmann::json j = {{"weights", o.out},
                      {"weights_bytes", fs::file_size(o.out)},
                      {"parameters", net.parameter_count()},
                      {"multiply_adds_per_patch", SaftNetwork::multiply_adds_per_patch()},
                      {"dimension", SaftNetwork::kDimension},
                      {"loss", o.loss},
                      {"steps", o.trainer.steps},
                      {"batch_pairs", o.trainer.batch_pairs},
                      {"seed", o.trainer.seed},
                      {"training_images", train_set.size()},
                      {"training_pairs", pool.size()},
                      {"final_loss", final_step.loss},
                      {"final_accuracy", final_step.accuracy}};
  if (val_pool.size() > 2) {
    auto t = timer.scope("validate");
    // Validation pairs: matching (first_i, second_i), non-matching (first_i, second_j).
    cv::Mat u1, u2, r1, r2;
    net.describe(normalize_saft_patches(val_pool.first), u1, &r1);
    net.describe(normalize_saft_patches(val_pool.second), u2, &r2);
    std::mt19937_64 rng(o.trainer.seed + 7);
    const DescriptorMetric l2 = DescriptorMetric::float_l2(SaftNetwork::kDimension);
    std::vector<double> pos, neg, rpos, rneg;
    for (int i = 0; i < val_pool.size(); ++i) {
      const int k = draw_non_matching(val_pool, i, rng);
      pos.push_back(l2.distance(u1, i, u2, i));
      neg.push_back(l2.distance(u1, i, u2, k));
      rpos.push_back(l2.distance(r1, i, r2, i));
      rneg.push_back(l2.distance(r1, i, r2, k));
    }
    const RocPoint at80 = fpr_at_tpr(pos, neg, 0.80);
    j["validation"] = {{"pairs", val_pool.size()},
                       {"saft", roc_json(pos, neg)},
                       {"saft_unnormalized", roc_json(rpos, rneg)},
                       {"threshold_tpr80", at80.threshold},
                       {"fpr_tpr80", at80.fpr}};
    spdlog::info("validation (generated pairs): FPR95 {:.4f} normalized, {:.4f} unnormalized",
                 j["validation"]["saft"]["fpr95"].get<double>(), j["validation"]["saft_unnormalized"]["fpr95"].get<double>());
  }
  spdlog::info("weights written to {} ({} bytes)", o.out, fs::file_size(o.out));
  j["stage_ms"] = timer.summary();
  return j;
}

struct EvalOptions {
  std::vector<std::string> images;
  std::string weights, roc_out;
  PatchVerificationOptions verify;
};

// A sequence folder, or a folder of sequence folders.
std::vector<fs::path> sequence_folders(const fs::path& dir) {
  if (!fs::is_directory(dir)) throw InputError(dir.string() + ": --images: not a folder");
  if (fs::exists(dir / "1.png")) return {dir};
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.is_directory() && fs::exists(e.path() / "1.png")) out.push_back(e.path());
  std::sort(out.begin(), out.end());
  if (out.empty()) throw InputError(dir.string() + ": --images: no 1.png here or in its subfolders (HPatches layout expected)");
  return out;
}

nlohmann::json run_eval(const EvalOptions& o) {
  StageTimer timer;
  const fs::path weights = o.weights.empty() ? SaftNetwork::default_weights_path() : fs::path(o.weights);
  SaftNetwork net = [&] {
    auto t = timer.scope("load_weights");
    return SaftNetwork::load(weights);
  }();
  PatchVerificationDistances all;
  nlohmann::json per_sequence = nlohmann::json::object();
  for (const auto& d : o.images)
    for (const auto& dir : sequence_folders(d)) {
      HomographySequence seq;
      {
        auto t = timer.scope("read");
        seq = read_homography_sequence(dir);
      }
      PatchVerificationDistances dist;
      {
        auto t = timer.scope("describe");
        dist = verify_patches(seq, net, o.verify);
      }
      if (dist.orb_pos.empty() || dist.orb_neg.empty()) throw Failure(dir.string() + ": no keypoint of 1.png maps into the other images");
      per_sequence[seq.name] = {{"pairs", dist.orb_pos.size()},
                                {"fpr95",
                                 {{"orb", fpr_at_tpr(dist.orb_pos, dist.orb_neg).fpr},
                                  {"saft", fpr_at_tpr(dist.saft_pos, dist.saft_neg).fpr},
                                  {"saft_unnormalized", fpr_at_tpr(dist.raw_pos, dist.raw_neg).fpr}}}};
      all.append(dist);
    }
  auto t = timer.scope("roc");
  const RocPoint orb = fpr_at_tpr(all.orb_pos, all.orb_neg), saft = fpr_at_tpr(all.saft_pos, all.saft_neg),
                 raw = fpr_at_tpr(all.raw_pos, all.raw_neg);
  // SAFT thresholds that accept as many true matches as ORB-SLAM's Hamming 50 and 100.
  auto tpr_at = [](std::vector<double> v, double th) {
    return static_cast<double>(std::count_if(v.begin(), v.end(), [th](double x) { return x <= th; })) / static_cast<double>(v.size());
  };
  const double tpr50 = tpr_at(all.orb_pos, 50), tpr100 = tpr_at(all.orb_pos, 100);
  nlohmann::json j = {{"weights", weights.string()},
                      {"pairs", {{"matching", all.orb_pos.size()}, {"non_matching", all.orb_neg.size()}}},
                      {"fpr95", {{"orb", orb.fpr}, {"saft", saft.fpr}, {"saft_unnormalized", raw.fpr}}},
                      {"threshold95", {{"orb", orb.threshold}, {"saft", saft.threshold}, {"saft_unnormalized", raw.threshold}}},
                      {"orb_tpr", {{"hamming50", tpr50}, {"hamming100", tpr100}}},
                      {"saft_threshold_same_tpr",
                       {{"hamming50", tpr50 > 0 ? fpr_at_tpr(all.saft_pos, all.saft_neg, tpr50).threshold : 0.0},
                        {"hamming100", tpr100 > 0 ? fpr_at_tpr(all.saft_pos, all.saft_neg, tpr100).threshold : 0.0}}},
                      {"sequences", per_sequence}};
  if (!o.roc_out.empty()) {
    std::ofstream csv(o.roc_out);
    if (!csv) throw InputError(o.roc_out + ": --roc-out: cannot write");
    csv << "method,tpr,fpr,threshold\n";
    auto write = [&](const char* name, const std::vector<double>& p, const std::vector<double>& n) {
      for (const RocPoint& r : roc_curve(p, n, 100)) csv << name << ',' << r.tpr << ',' << r.fpr << ',' << r.threshold << '\n';
    };
    write("orb", all.orb_pos, all.orb_neg);
    write("saft", all.saft_pos, all.saft_neg);
    write("saft_unnormalized", all.raw_pos, all.raw_neg);
    j["roc_csv"] = o.roc_out;
  }
  spdlog::info("{} matching / {} non-matching pairs: FPR95 ORB {:.4f}, SAFT {:.4f}, SAFT unnormalized {:.4f}", all.orb_pos.size(),
               all.orb_neg.size(), orb.fpr, saft.fpr, raw.fpr);
  j["stage_ms"] = timer.summary();
  return j;
}

const bool group_saft = register_group("saft", "SAFT, the learned patch descriptor: training and evaluation");

const bool train = register_command({
    .path = {"saft", "train"},
    .description = "Train the SAFT network self-supervised from images (random homographies and photometric changes)",
    .setup = [](CLI::App& cmd) -> Action {
      auto o = std::make_shared<TrainOptions>();
      cmd.add_option("--images", o->images, "Image folders (or TUM-layout worlds: their rgb/ is used)")->required();
      cmd.add_option("--out", o->out, "Weights file to write")->required();
      cmd.add_option("--every", o->every, "Use every N-th image of a folder")->capture_default_str();
      cmd.add_option("--validation", o->validation, "Fraction of images held out to validate")->capture_default_str();
      cmd.add_option("--steps", o->trainer.steps, "Training steps")->capture_default_str()->check(CLI::PositiveNumber);
      cmd.add_option("--batch", o->trainer.batch_pairs, "Matching pairs per step")->capture_default_str()->check(CLI::Range(2, 4096));
      cmd.add_option("--lr", o->trainer.learning_rate, "Adam learning rate")->capture_default_str()->check(CLI::PositiveNumber);
      cmd.add_option("--loss", o->loss, "hinge (the source's binary hinge loss) or triplet (hardest in batch)")->capture_default_str();
      cmd.add_option("--warps", o->pairs.warps_per_image, "Random homographies per image")->capture_default_str()->check(CLI::PositiveNumber);
      cmd.add_option("--keypoints", o->pairs.keypoints_per_image, "ORB keypoints per image")->capture_default_str()->check(CLI::PositiveNumber);
      cmd.add_option("--threads", o->trainer.threads, "Intra-op threads while training")->capture_default_str()->check(CLI::Range(1, 64));
      cmd.add_option("--seed", o->trainer.seed, "Seed of the warps, the batches and the initial weights")->capture_default_str();
      return [o] {
        o->pairs.seed = o->trainer.seed;
        return run_train(*o);
      };
    },
    .order = 80});

const bool eval = register_command({
    .path = {"saft", "eval"},
    .description = "FPR95 and ROC of ORB, SAFT and unnormalized SAFT on image sequences with known homographies",
    .setup = [](CLI::App& cmd) -> Action {
      auto o = std::make_shared<EvalOptions>();
      cmd.add_option("--images", o->images, "HPatches-style folders (1.png ... and H_1_k), or folders of them")->required();
      cmd.add_option("--weights", o->weights, "SAFT weights (default: the shipped data/saft/saft_v1.saft)");
      cmd.add_option("--keypoints", o->verify.keypoints, "ORB keypoints in image 1")->capture_default_str()->check(CLI::PositiveNumber);
      cmd.add_option("--seed", o->verify.seed, "Seed of the non-matching pairs")->capture_default_str();
      cmd.add_option("--roc-out", o->roc_out, "CSV of the three ROC curves (method,tpr,fpr,threshold)");
      return [o] { return run_eval(*o); };
    },
    .order = 81});

}  // namespace
}  // namespace builtscene::app
