// Generated RGB-D worlds (issue 3): rendering, sensor noise and PNG encoding measured
// separately at 640 x 480, plus the whole frame as `builtscene synth rgbd` makes it.
#include <benchmark/benchmark.h>

#include <filesystem>

#include <opencv2/imgcodecs.hpp>

#include "synth/camera_motion.hpp"
#include "synth/png_writer.hpp"
#include "synth/renderer.hpp"
#include "synth/rgbd_sequence_writer.hpp"
#include "synth/scene_library.hpp"
#include "synth/sensor_noise.hpp"

namespace synth = builtscene::synth;

namespace {

struct Fixture {
  synth::Scene scene;
  builtscene::RgbdCameraSettings settings = synth::kinect_settings(640, 480);
  std::unique_ptr<synth::Renderer> renderer;
  std::vector<builtscene::SE3> poses;
  explicit Fixture(const std::string& name, synth::MotionKind kind) : scene(synth::build_scene(name)) {
    renderer = std::make_unique<synth::Renderer>(scene, settings.camera);
    synth::MotionOptions mo;
    mo.kind = kind;
    mo.frames = 300;
    poses = synth::generate_motion(scene, mo).poses;
  }
};

Fixture& lab() {
  static Fixture f("lab-room", synth::MotionKind::Handheld);
  return f;
}
Fixture& corridor() {
  static Fixture f("corridor-loop", synth::MotionKind::Robot);
  return f;
}

void render(benchmark::State& state, Fixture& f) {
  synth::RenderOutput out;
  std::size_t i = 0;
  for (auto _ : state) {
    f.renderer->render(f.poses[i++ % f.poses.size()], out, static_cast<int>(state.range(0)));
    benchmark::DoNotOptimize(out.depth.data);
  }
  state.counters["fps"] = benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
void BM_RenderLabRoom(benchmark::State& state) { render(state, lab()); }
void BM_RenderCorridor(benchmark::State& state) { render(state, corridor()); }
BENCHMARK(BM_RenderLabRoom)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(BM_RenderCorridor)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_KinectDepthNoise(benchmark::State& state) {
  synth::RenderOutput out;
  lab().renderer->render(lab().poses[50], out);
  synth::KinectNoiseModel m;
  std::uint64_t k = 0;
  for (auto _ : state) {
    synth::FrameRng rng(1, k++, 2);
    benchmark::DoNotOptimize(synth::apply_kinect_noise(out.depth, out.incidence, m, rng).data);
  }
}
BENCHMARK(BM_KinectDepthNoise)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ColorCamera(benchmark::State& state) {
  synth::RenderOutput out;
  lab().renderer->render(lab().poses[50], out);
  synth::ColorCameraModel m;
  std::uint64_t k = 0;
  for (auto _ : state) {
    synth::FrameRng rng(1, k++, 1);
    benchmark::DoNotOptimize(synth::apply_color_camera(out.bgr, m, rng).data);
  }
}
BENCHMARK(BM_ColorCamera)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_EncodePngPair(benchmark::State& state) {
  synth::RenderOutput out;
  lab().renderer->render(lab().poses[50], out);
  synth::ColorCameraModel m;
  synth::FrameRng rng(1, 0, 1);
  const cv::Mat rgb = synth::apply_color_camera(out.bgr, m, rng);
  synth::FrameRng rng2(1, 0, 2);
  const cv::Mat depth = synth::depth_to_u16(synth::apply_kinect_noise(out.depth, out.incidence, synth::KinectNoiseModel{}, rng2));
  const std::vector<int> params = {cv::IMWRITE_PNG_COMPRESSION, static_cast<int>(state.range(0)), cv::IMWRITE_PNG_STRATEGY,
                                   static_cast<int>(state.range(1))};
  std::size_t bytes = 0;
  for (auto _ : state) {
    std::vector<uchar> a, b;
    cv::imencode(".png", rgb, a, params);
    cv::imencode(".png", depth, b, params);
    bytes = a.size() + b.size();
  }
  state.counters["kB_per_frame"] = static_cast<double>(bytes) / 1000.0;
}

// What the generator uses: Sub filter + run-length deflate (src/synth/png_writer).
void BM_EncodePngPairFast(benchmark::State& state) {
  synth::RenderOutput out;
  lab().renderer->render(lab().poses[50], out);
  synth::ColorCameraModel m;
  synth::FrameRng rng(1, 0, 1);
  const cv::Mat rgb = synth::apply_color_camera(out.bgr, m, rng);
  synth::FrameRng rng2(1, 0, 2);
  const cv::Mat depth = synth::depth_to_u16(synth::apply_kinect_noise(out.depth, out.incidence, synth::KinectNoiseModel{}, rng2));
  std::size_t bytes = 0;
  for (auto _ : state) bytes = synth::encode_png_fast(rgb).size() + synth::encode_png_fast(depth).size();
  state.counters["kB_per_frame"] = static_cast<double>(bytes) / 1000.0;
}
BENCHMARK(BM_EncodePngPairFast)->Unit(benchmark::kMillisecond)->UseRealTime();
// Args: zlib level, strategy (0 default, 2 Huffman only, 3 RLE).
BENCHMARK(BM_EncodePngPair)->Args({0, 0})->Args({1, 0})->Args({1, 2})->Args({1, 3})->Args({3, 0})->Unit(benchmark::kMillisecond)->UseRealTime();

// The whole command on 60 frames (render + noise on the main thread, PNGs on a worker).
void BM_SynthRgbdEndToEnd(benchmark::State& state) {
  const auto dir = std::filesystem::temp_directory_path() / "builtscene_synth_bench";
  double fps = 0;
  for (auto _ : state) {
    synth::RgbdSequenceOptions o;
    o.scene = "lab-room";
    o.out = dir;
    o.frames = 60;
    o.render_threads = static_cast<int>(state.range(0));
    const auto j = synth::generate_rgbd_sequence(o);
    fps = j["frames"].get<double>() / (j["seconds"].get<double>() - j["stage_ms"]["setup"]["total"].get<double>() / 1000.0);
  }
  state.counters["frames_per_s_after_setup"] = fps;
  std::filesystem::remove_all(dir);
}
BENCHMARK(BM_SynthRgbdEndToEnd)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

}  // namespace
