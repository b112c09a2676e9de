// Per-stage cost of the barcode pipeline on one generated 1080p warehouse frame: key-frame
// histogram, region detection, direction estimation, crop decoding, and the decoder alone on
// the whole frame. End-to-end numbers: bench/barcodes_scan.sh.
#include <benchmark/benchmark.h>

#include <opencv2/imgproc.hpp>

#include "barcode/decoder.hpp"
#include "barcode/direction_estimator.hpp"
#include "barcode/key_frame_selector.hpp"
#include "barcode/region_detector.hpp"
#include "barcode/scan_pipeline.hpp"
#include "synth/warehouse_scene.hpp"

namespace {
using namespace builtscene;

const cv::Mat& frame() {
  static const cv::Mat gray = [] {
    synth::WarehouseOptions o;
    o.frames = 400;
    const synth::WarehouseScene scene(o);
    cv::Mat g;
    cv::cvtColor(scene.render(200), g, cv::COLOR_BGR2GRAY);
    return g;
  }();
  return gray;
}

void BM_Histogram(benchmark::State& s) {
  cv::Mat small;
  cv::resize(frame(), small, cv::Size(), 0.25, 0.25, cv::INTER_AREA);
  for (auto _ : s) benchmark::DoNotOptimize(barcode::KeyFrameSelector::histogram(small, 1));
}
BENCHMARK(BM_Histogram)->Unit(benchmark::kMillisecond);

void BM_RegionDetection(benchmark::State& s) {
  barcode::RegionOptions o;
  o.threshold = 0.6;
  const barcode::RegionDetector d(o);
  for (auto _ : s) benchmark::DoNotOptimize(d.detect(frame()));
}
BENCHMARK(BM_RegionDetection)->Unit(benchmark::kMillisecond);

void BM_DirectionEstimation(benchmark::State& s) {
  const cv::Mat sym = synth::render_barcode("RM1401A", "Code128", 3, 22);
  cv::Mat canvas(520, 520, CV_8UC1, cv::Scalar(200));
  sym.copyTo(canvas(cv::Rect(20, 200, sym.cols, sym.rows)));
  const barcode::DirectionEstimator e;
  for (auto _ : s) benchmark::DoNotOptimize(e.scan_angle(canvas));
}
BENCHMARK(BM_DirectionEstimation)->Unit(benchmark::kMillisecond);

void BM_WholeFrameDecoder(benchmark::State& s) {
  const barcode::ZXingDecoder d(barcode::ZXingSearch::thorough);
  for (auto _ : s) benchmark::DoNotOptimize(d.decode(frame(), 32));
}
BENCHMARK(BM_WholeFrameDecoder)->Unit(benchmark::kMillisecond);

void BM_PipelineFrame(benchmark::State& s) {
  barcode::StageSettings st;
  st.region.threshold = 0.6;
  using barcode::ZXingSearch;
  const barcode::ZXingDecoder whole(ZXingSearch::thorough), on_frame(ZXingSearch::rotated), crop(ZXingSearch::quick),
      upright(ZXingSearch::quick, 3);
  const barcode::DecoderSet ds{whole, on_frame, crop, upright};
  for (auto _ : s) benchmark::DoNotOptimize(barcode::read_frame(frame(), st, ds, true, false, true, 32));
}
BENCHMARK(BM_PipelineFrame)->Unit(benchmark::kMillisecond);

}  // namespace
