// `builtscene vocab train`: a bag-of-words vocabulary from the ORB descriptors of datasets
// (TUM layout) and/or image folders. Deterministic: same inputs, options and seed give the
// same file. The shipped default vocabulary is made by scripts/make_vocabulary.
#include <algorithm>
#include <chrono>
#include <fstream>
#include <filesystem>
#include <memory>
#include <string>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "cli_parsing.hpp"
#include "command_registry.hpp"
#include "core/errors.hpp"
#include "core/logging.hpp"
#include "core/progress.hpp"
#include "core/settings_file.hpp"
#include "core/stage_timer.hpp"
#include "features/bow_vocabulary.hpp"
#include "features/feature_extractor.hpp"
#include "features/orb_extractor.hpp"
#include "io/tum_dataset.hpp"

namespace builtscene::app {
namespace {

struct VocabOptions {
  std::vector<std::filesystem::path> datasets;
  std::vector<std::filesystem::path> image_dirs;
  std::filesystem::path out;
  int k = 10;
  int levels = 4;
  long max_frames = 0;  // per dataset or folder, evenly spaced; 0 = all
  int iterations = 10;
  std::uint64_t seed = 1;
  std::string descriptor = "orb";
  std::filesystem::path saft_weights;
};

// Indices 0..n-1, or `max` of them evenly spaced.
std::vector<std::size_t> pick(std::size_t n, long max) {
  std::vector<std::size_t> out;
  if (max <= 0 || static_cast<std::size_t>(max) >= n) {
    for (std::size_t i = 0; i < n; ++i) out.push_back(i);
    return out;
  }
  for (long j = 0; j < max; ++j) out.push_back(static_cast<std::size_t>(static_cast<double>(j) * static_cast<double>(n) / static_cast<double>(max)));
  return out;
}

cv::Mat to_gray(const cv::Mat& img) {
  cv::Mat gray;
  if (img.channels() == 3) cv::cvtColor(img, gray, cv::COLOR_BGR2GRAY);
  else if (img.channels() == 4) cv::cvtColor(img, gray, cv::COLOR_BGRA2GRAY);
  else gray = img;
  if (gray.depth() != CV_8U) gray.convertTo(gray, CV_8U);
  return gray;
}

nlohmann::json run_train(const VocabOptions& opt) {
  if (opt.datasets.empty() && opt.image_dirs.empty()) throw InputError("vocab train: give --dataset or --images");
  if (opt.k < 2 || opt.k > 1000) throw InputError("--k: expected 2..1000, got " + std::to_string(opt.k));
  if (opt.levels < 1 || opt.levels > 8) throw InputError("--levels: expected 1..8, got " + std::to_string(opt.levels));
  if (opt.iterations < 1) throw InputError("--iterations: expected at least 1");
  check_output_file(opt.out);
  StageTimer timer;
  std::vector<cv::Mat> images;
  std::size_t descriptors = 0, skipped = 0;
  const DescriptorChoice choice = parse_descriptor_choice(opt.descriptor);
  if (choice == DescriptorChoice::kOrb && !opt.saft_weights.empty()) throw InputError("--saft-weights needs --descriptor saft");
  auto extract = [&](FeatureExtractor& orb, const cv::Mat& img) {
    const auto start = std::chrono::steady_clock::now();
    std::vector<cv::KeyPoint> keys;
    cv::Mat d;
    orb.extract(to_gray(img), keys, d);
    timer.add("extraction", ms_since(start));
    descriptors += static_cast<std::size_t>(d.rows);
    images.push_back(d);
  };
  for (const auto& dir : opt.datasets) {
    const TumDataset data = TumDataset::open(dir);
    const auto extractor =
        make_feature_extractor(choice, OrbExtractorOptions::from_settings(SettingsFile::load(dir / "camera.yaml")), opt.saft_weights);
    FeatureExtractor& orb = *extractor;
    const auto idx = pick(data.size(), opt.max_frames);
    Progress progress("vocab " + dir.filename().string(), idx.size());
    for (std::size_t j = 0; j < idx.size(); ++j) {
      progress.update(j);
      try {
        extract(orb, data.load_rgb(idx[j]));
      } catch (const InputError& e) {
        ++skipped;
        spdlog::warn("{}; skipped", e.what());
      }
    }
    progress.finish();
  }
  for (const auto& dir : opt.image_dirs) {
    if (!std::filesystem::is_directory(dir)) throw InputError(located(dir, 0, "--images: not a folder"));
    std::vector<std::filesystem::path> files;
    for (const auto& e : std::filesystem::directory_iterator(dir)) {
      auto ext = e.path().extension().string();
      std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
      if (ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".bmp" || ext == ".pgm" || ext == ".ppm") files.push_back(e.path());
    }
    std::sort(files.begin(), files.end());  // directory order is not stable; the result must be
    const auto extractor = make_feature_extractor(choice, OrbExtractorOptions{}, opt.saft_weights);
    FeatureExtractor& orb = *extractor;
    for (std::size_t i : pick(files.size(), opt.max_frames)) {
      const cv::Mat img = cv::imread(files[i].string(), cv::IMREAD_UNCHANGED);
      if (img.empty()) {
        ++skipped;
        spdlog::warn("{}: unreadable image; skipped", files[i].string());
        continue;
      }
      extract(orb, img);
    }
  }
  spdlog::info("vocab: {} images, {} descriptors; clustering k={} levels={}", images.size(), descriptors, opt.k, opt.levels);
  auto start = std::chrono::steady_clock::now();
  const BowVocabulary voc =
      BowVocabulary::train(images, {.k = opt.k, .levels = opt.levels, .max_iterations = opt.iterations, .seed = opt.seed});
  timer.add("clustering", ms_since(start));
  start = std::chrono::steady_clock::now();
  voc.save(opt.out);
  timer.add("writing", ms_since(start));
  const auto bytes = std::filesystem::file_size(opt.out);
  spdlog::info("vocab: {} words, {} nodes, {} bytes -> {}", voc.word_count(), voc.node_count(), bytes, opt.out.string());
  return {{"images", images.size()},
          {"descriptor", opt.descriptor},
          {"skipped_images", skipped},
          {"descriptors", descriptors},
          {"k", opt.k},
          {"levels", opt.levels},
          {"seed", opt.seed},
          {"words", voc.word_count()},
          {"nodes", voc.node_count()},
          {"bytes", bytes},
          {"out", opt.out.string()},
          {"stage_ms", timer.summary()}};
}

const bool group_vocab = register_group("vocab", "Bag-of-words vocabularies for place recognition");

const bool registered_vocab = register_command({
    .path = {"vocab", "train"},
    .description = "Train a bag-of-words vocabulary (hierarchical k-means on ORB or SAFT descriptors)",
    .setup = [](CLI::App& cmd) -> Action {
      auto opt = std::make_shared<VocabOptions>();
      cmd.add_option("--dataset", opt->datasets, "TUM-layout folder(s) (camera.yaml gives the ORB settings)");
      cmd.add_option("--images", opt->image_dirs, "Folder(s) of images (default ORB settings)");
      cmd.add_option("--out", opt->out, "Output vocabulary file (.bsvoc)")->required();
      cmd.add_option("--k", opt->k, "Branching factor")->capture_default_str();
      cmd.add_option("--levels", opt->levels, "Depth of the tree")->capture_default_str();
      cmd.add_option("--max-frames", opt->max_frames, "Per dataset or folder: at most N evenly spaced frames (0 = all)");
      cmd.add_option("--iterations", opt->iterations, "k-means iterations per node")->capture_default_str();
      cmd.add_option("--seed", opt->seed, "Seed of the k-means++ seeding")->capture_default_str();
      cmd.add_option("--descriptor", opt->descriptor, "Descriptor to cluster: orb or saft")->capture_default_str();
      cmd.add_option("--saft-weights", opt->saft_weights, "SAFT weights (default: the shipped data/saft/saft_v1.saft)");
      return [opt] { return run_train(*opt); };
    },
    .order = 45});

}  // namespace
}  // namespace builtscene::app
