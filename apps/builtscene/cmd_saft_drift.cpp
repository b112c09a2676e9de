// `builtscene saft drift`: how far online learning moved the descriptor. The same patches
// (ORB keypoints of a sequence's frames) described by two weight files, usually the shipped
// pre-trained ones and the fine-tuned ones a run saved (slam --saft-weights-out): the L2
// distance between the two descriptors of each patch, against the SLAM's match thresholds,
// and the share of patches whose bag-of-words word changes. This is the evidence that map
// points described by an older net and a vocabulary trained with the pre-trained net stay
// valid while the net fine-tunes (docs/saft.md, "Online learning").
#include <algorithm>
#include <filesystem>

#include <opencv2/imgproc.hpp>

#include "command_registry.hpp"
#include "core/errors.hpp"
#include "core/logging.hpp"
#include "core/settings_file.hpp"
#include "core/stage_timer.hpp"
#include "features/bow_vocabulary.hpp"
#include "features/orb_extractor.hpp"
#include "features/saft_extractor.hpp"
#include "features/saft_network.hpp"
#include "features/saft_patch.hpp"
#include "io/tum_dataset.hpp"
#include "slam/system.hpp"

namespace builtscene::app {
namespace {

namespace fs = std::filesystem;

struct DriftOptions {
  fs::path dataset, from, to, vocabulary;
  long every = 10;
};

nlohmann::json run_drift(const DriftOptions& o) {
  StageTimer timer;
  if (o.every < 1) throw InputError("--every: expected at least 1");
  const TumDataset data = TumDataset::open(o.dataset);
  const fs::path from = o.from.empty() ? SaftNetwork::default_weights_path() : o.from;
  SaftNetwork a = SaftNetwork::load(from), b = SaftNetwork::load(o.to);
  const fs::path voc_file = o.vocabulary.empty() ? slam::default_vocabulary_path(DescriptorChoice::kSaft) : o.vocabulary;
  if (voc_file.empty()) throw InputError("--vocabulary: no SAFT vocabulary given and none shipped");
  const BowVocabulary voc = BowVocabulary::load(voc_file);
  if (voc.kind() != DescriptorKind::kFloat || voc.descriptor_cols() != SaftNetwork::kDimension)
    throw InputError(voc_file.string() + ": not a vocabulary of SAFT descriptors");
  OrbExtractor orb(OrbExtractorOptions::from_settings(SettingsFile::load(o.dataset / "camera.yaml")));
  const DescriptorMetric metric = SaftExtractor::saft_metric();
  std::vector<double> dist;
  long words_changed = 0, frames = 0;
  for (std::size_t i = 0; i < data.size(); i += static_cast<std::size_t>(o.every)) {
    auto t = timer.scope("describe");
    cv::Mat gray = data.load_rgb(i), binary, da, db;
    if (gray.channels() == 3) cv::cvtColor(gray, gray, cv::COLOR_BGR2GRAY);
    std::vector<cv::KeyPoint> kps;
    orb.extract(gray, kps, binary);
    if (kps.empty()) continue;
    const cv::Mat patches = normalize_saft_patches(sample_saft_patches(orb.levels(), orb.pyramid(), kps));
    a.describe(patches, da);
    b.describe(patches, db);
    for (int r = 0; r < patches.rows; ++r) {
      dist.push_back(metric.distance(da, r, db, r));
      words_changed += voc.word_of(da, r) != voc.word_of(db, r);
    }
    ++frames;
  }
  if (dist.empty()) throw Failure(o.dataset.string() + ": no keypoints in the sampled frames");
  const auto n = static_cast<double>(dist.size());
  const double over_strict =
      static_cast<double>(std::count_if(dist.begin(), dist.end(), [&](double d) { return d > metric.strict; })) / n;
  nlohmann::json j = {{"from", from.string()},
                      {"to", o.to.string()},
                      {"vocabulary", voc_file.string()},
                      {"frames", frames},
                      {"patches", dist.size()},
                      {"l2", {{"median", quantile(dist, 0.5)}, {"p95", quantile(dist, 0.95)}, {"max", quantile(dist, 1.0)}}},
                      {"match_thresholds", {{"strict", metric.strict}, {"loose", metric.loose}}},
                      {"share_over_strict", over_strict},
                      {"words_changed", static_cast<double>(words_changed) / n},
                      {"stage_ms", timer.summary()}};
  spdlog::info("{} patches of {} frames: L2 between the two nets' descriptors median {:.3f}, p95 {:.3f} (strict match "
               "threshold {:.2f}); {:.1f} % change their word",
               dist.size(), frames, quantile(dist, 0.5), quantile(dist, 0.95), metric.strict, 100.0 * words_changed / n);
  return j;
}

const bool drift = register_command({
    .path = {"saft", "drift"},
    .description = "How far two SAFT weight files (pre-trained, fine-tuned) describe the same patches apart",
    .setup = [](CLI::App& cmd) -> Action {
      auto o = std::make_shared<DriftOptions>();
      cmd.add_option("--dataset", o->dataset, "TUM-layout sequence whose frames give the patches")->required();
      cmd.add_option("--to", o->to, "Weights to compare (e.g. slam --saft-weights-out)")->required();
      cmd.add_option("--from", o->from, "Reference weights (default: the shipped data/saft/saft_v1.saft)");
      cmd.add_option("--vocabulary", o->vocabulary, "SAFT vocabulary (default: the shipped saft_k10_L4.bsvoc)");
      cmd.add_option("--every", o->every, "Every N-th frame")->capture_default_str();
      return [o] { return run_drift(*o); };
    },
    .order = 82});

}  // namespace
}  // namespace builtscene::app
