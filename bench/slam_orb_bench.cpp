// ORB extraction, ours against OpenCV's cv::ORB, 1000 features on a 640x480 frame of
// 7scenes-kitchen (or a generated texture when the shared data is absent). Counters report the
// spread (fraction of a 32x24 grid covered) next to the time.
#include <filesystem>

#include <benchmark/benchmark.h>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "features/brief_smoothing.hpp"
#include "features/keypoint_distribution.hpp"
#include "features/orb_extractor.hpp"

namespace {

cv::Mat test_frame() {
  const auto dir = std::filesystem::path(BUILTSCENE_SOURCE_DIR) / "../shared/data/7scenes-kitchen/rgb";
  const auto file = dir / "1010.000000.jpg";
  if (std::filesystem::exists(file)) return cv::imread(file.string(), cv::IMREAD_GRAYSCALE);
  if (std::filesystem::exists(dir)) {
    for (const auto& e : std::filesystem::directory_iterator(dir)) return cv::imread(e.path().string(), cv::IMREAD_GRAYSCALE);
  }
  cv::Mat img(480, 640, CV_8UC1);
  cv::randu(img, 0, 255);
  cv::GaussianBlur(img, img, cv::Size(9, 9), 3);
  return img;
}

void run_extractor(benchmark::State& state, const builtscene::OrbExtractorOptions& options) {
  const cv::Mat img = test_frame();
  builtscene::OrbExtractor orb(options);
  std::vector<cv::KeyPoint> k;
  cv::Mat d;
  for (auto _ : state) {
    orb.extract(img, k, d);
    benchmark::DoNotOptimize(d.data);
  }
  state.counters["keypoints"] = static_cast<double>(k.size());
  state.counters["grid_coverage"] = builtscene::grid_coverage(k, img.size(), 32, 24);
}
void BM_OrbExtractor(benchmark::State& state) { run_extractor(state, {}); }
BENCHMARK(BM_OrbExtractor)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime();

void BM_OpenCvOrb(benchmark::State& state) {
  const cv::Mat img = test_frame();
  auto orb = cv::ORB::create(1000, 1.2f, 8);
  std::vector<cv::KeyPoint> k;
  cv::Mat d;
  for (auto _ : state) {
    orb->detectAndCompute(img, cv::noArray(), k, d);
    benchmark::DoNotOptimize(d.data);
  }
  state.counters["keypoints"] = static_cast<double>(k.size());
  state.counters["grid_coverage"] = builtscene::grid_coverage(k, img.size(), 32, 24);
}
BENCHMARK(BM_OpenCvOrb)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime();

// The cost of the fallback threshold: the same extractor with FAST at 20 only (fewer
// keypoints in low-contrast cells, so a narrower spread).
void BM_OrbExtractorWithoutFallback(benchmark::State& state) {
  builtscene::OrbExtractorOptions o;
  o.min_th_fast = o.ini_th_fast;
  o.noise_factor = 0;
  run_extractor(state, o);
}
BENCHMARK(BM_OrbExtractorWithoutFallback)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime();

// The smoothing BRIEF is computed on, ours against the cv::GaussianBlur call it replaces
// (same bytes out, tests/features/brief_smoothing_test.cpp), on the full-size frame.
void BM_BriefSmoothing(benchmark::State& state) {
  const cv::Mat img = test_frame();
  cv::Mat out;
  std::vector<std::uint16_t> scratch;
  for (auto _ : state) {
    builtscene::smooth_for_brief(img, out, scratch);
    benchmark::DoNotOptimize(out.data);
  }
}
BENCHMARK(BM_BriefSmoothing)->Unit(benchmark::kMicrosecond)->MeasureProcessCPUTime();

void BM_OpenCvGaussianBlur7x7(benchmark::State& state) {
  const cv::Mat img = test_frame();
  cv::Mat out;
  for (auto _ : state) {
    cv::GaussianBlur(img, out, cv::Size(7, 7), 2, 2, cv::BORDER_REFLECT_101);
    benchmark::DoNotOptimize(out.data);
  }
}
BENCHMARK(BM_OpenCvGaussianBlur7x7)->Unit(benchmark::kMicrosecond)->MeasureProcessCPUTime();

}  // namespace
