// A* on a 1000 x 1000 grid (50 m x 50 m at 5 cm) with random walls: the issue's "1000 x 1000
// plan in under 50 ms". Costmap inflation is timed separately (done once per map).
#include <benchmark/benchmark.h>

#include <random>

#include "nav/astar_planner.hpp"

namespace {

builtscene::OccupancyGrid random_walls(int n) {
  builtscene::OccupancyGrid g(n, n, 0.05, {0, 0}, 0);
  std::mt19937 rng(42);
  std::uniform_int_distribution<int> pos(0, n - 1), len(20, 200);
  for (int k = 0; k < n / 10; ++k) {
    const int c = pos(rng), r = pos(rng), l = len(rng);
    for (int i = 0; i < l; ++i) {
      const int cc = k % 2 ? std::min(n - 1, c + i) : c, rr = k % 2 ? r : std::min(n - 1, r + i);
      g.at({cc, rr}) = 100;
    }
  }
  for (int i = 0; i < 40; ++i)
    for (int j = 0; j < 40; ++j) g.at({i, j}) = g.at({n - 1 - i, n - 1 - j}) = 0;  // clear start and goal
  return g;
}

void BM_CostmapInflation1000(benchmark::State& state) {
  const auto g = random_walls(1000);
  for (auto _ : state) benchmark::DoNotOptimize(builtscene::Costmap(g, {}));
}
BENCHMARK(BM_CostmapInflation1000)->Unit(benchmark::kMillisecond);

void BM_AStar1000(benchmark::State& state) {
  const auto g = random_walls(1000);
  builtscene::CostmapOptions o;
  o.robot_radius = 0.1;
  o.inflation_radius = 0.3;
  const builtscene::Costmap cm(g, o);
  const builtscene::AStarPlanner p(cm);
  std::size_t expanded = 0;
  double length = 0;
  for (auto _ : state) {
    const auto r = p.plan(builtscene::GridIndex{5, 5}, builtscene::GridIndex{994, 994});
    if (!r.found) state.SkipWithError("no path");
    expanded = r.cells_expanded;
    length = r.length_m;
  }
  state.counters["cells_expanded"] = static_cast<double>(expanded);
  state.counters["length_m"] = length;
}
BENCHMARK(BM_AStar1000)->Unit(benchmark::kMillisecond);

}  // namespace
