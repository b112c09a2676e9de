// Saving and loading a 1000-keyframe map (the goal: under 2 s each). The map is built
// directly (tests/slam/map_test_fixture.hpp): 1000 keyframes of 1000 keypoints with ORB-sized
// descriptors, each point seen by up to three keyframes, about as large as a real map of that
// many keyframes. Times are wall clock and include the file write/read (page cache).
#include <filesystem>

#include <benchmark/benchmark.h>
#include <unistd.h>

#include "../tests/slam/map_test_fixture.hpp"
#include "slam/map_serializer.hpp"

namespace {

using namespace builtscene::slam;

struct BigMap {
  std::shared_ptr<const FrameContext> ctx = test::kinect_context();
  Map map;
  std::filesystem::path path = std::filesystem::temp_directory_path() / ("bs_map_bench_" + std::to_string(::getpid()) + ".map");
  BigMap() {
    std::lock_guard lock(map.mutex());
    test::build_random_map(map, ctx, 1000, 1000);
  }
  ~BigMap() { std::filesystem::remove(path); }
};

BigMap& big_map() {
  static BigMap m;
  return m;
}

void SaveMap1000Keyframes(benchmark::State& state) {
  auto& m = big_map();
  MapFileInfo info;
  for (auto _ : state) info = write_map_file(m.path, m.map, *m.ctx);
  state.counters["MB"] = static_cast<double>(info.bytes) / 1e6;
  state.counters["points"] = static_cast<double>(info.points);
}
BENCHMARK(SaveMap1000Keyframes)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

void LoadMap1000Keyframes(benchmark::State& state) {
  auto& m = big_map();
  write_map_file(m.path, m.map, *m.ctx);
  for (auto _ : state) {
    Map loaded;
    const auto info = read_map_file(m.path, loaded, m.ctx);
    benchmark::DoNotOptimize(info.keyframes);
    state.PauseTiming();
    {
      std::lock_guard lock(loaded.mutex());
      loaded.clear();
    }
    state.ResumeTiming();
  }
}
BENCHMARK(LoadMap1000Keyframes)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(3);

}  // namespace
