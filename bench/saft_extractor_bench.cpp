// SAFT extraction on one 640x480 frame of 7scenes-kitchen (a generated texture when the
// shared data is absent): ORB keypoints + patch sampling + the network, and the network alone
// per batch of 128 patches (one intra-op thread, as in the SLAM).
#include <filesystem>

#include <benchmark/benchmark.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "features/saft_extractor.hpp"
#include "features/saft_patch.hpp"

namespace {

cv::Mat test_frame() {
  const auto file = std::filesystem::path(BUILTSCENE_SOURCE_DIR) / "../shared/data/7scenes-kitchen/rgb/1010.000000.jpg";
  if (std::filesystem::exists(file)) return cv::imread(file.string(), cv::IMREAD_GRAYSCALE);
  cv::Mat img(480, 640, CV_8UC1);
  cv::randu(img, 0, 255);
  cv::GaussianBlur(img, img, cv::Size(9, 9), 3);
  return img;
}

builtscene::SaftNetwork shipped() { return builtscene::SaftNetwork::load(builtscene::SaftNetwork::default_weights_path()); }

void BM_SaftExtractor(benchmark::State& state) {
  const cv::Mat img = test_frame();
  builtscene::SaftExtractor saft({}, shipped());
  std::vector<cv::KeyPoint> k;
  cv::Mat d;
  for (auto _ : state) {
    saft.extract(img, k, d);
    benchmark::DoNotOptimize(d.data);
  }
  state.counters["keypoints"] = static_cast<double>(k.size());
}
BENCHMARK(BM_SaftExtractor)->Unit(benchmark::kMillisecond);

void BM_SaftNetworkBatch128(benchmark::State& state) {
  builtscene::SaftNetwork net = shipped();
  cv::Mat patches(128, builtscene::kSaftPatchPixels, CV_32F), unit;
  cv::randn(patches, 0, 1);
  for (auto _ : state) {
    net.describe(patches, unit);
    benchmark::DoNotOptimize(unit.data);
  }
  state.counters["patches_per_s"] = benchmark::Counter(128.0 * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_SaftNetworkBatch128)->Unit(benchmark::kMillisecond);

}  // namespace
