// `builtscene plan`: A* path on a map_server occupancy grid with an inflated costmap.
#include <chrono>
#include <fstream>
#include <iomanip>
#include <memory>

#include <opencv2/imgcodecs.hpp>

#include "cli_parsing.hpp"
#include "command_registry.hpp"
#include "core/errors.hpp"
#include "core/logging.hpp"
#include "core/stage_timer.hpp"
#include "nav/astar_planner.hpp"
#include "ogm/map_drawing.hpp"
#include "ogm/map_server_io.hpp"

namespace builtscene::app {
namespace {

struct PlanOptions {
  std::string map, start, goal, out, png;
  double robot_radius = 0.3, inflation_radius = -1, cost_scaling = 3.0, cost_weight = 3.0;
  bool allow_unknown = false;
};

nlohmann::json run_plan(const PlanOptions& o) {
  const Eigen::Vector2d start = parse_point2(o.start, "--start"), goal = parse_point2(o.goal, "--goal");
  const OccupancyGrid grid = load_map_server(o.map);
  CostmapOptions co;
  co.robot_radius = o.robot_radius;
  co.inflation_radius = o.inflation_radius < 0 ? o.robot_radius + 0.5 : o.inflation_radius;
  co.cost_scaling = o.cost_scaling;
  co.unknown_is_obstacle = !o.allow_unknown;
  if (co.inflation_radius < co.robot_radius) throw InputError("--inflation-radius must not be below --robot-radius");
  auto t0 = std::chrono::steady_clock::now();
  const Costmap costmap(grid, co);
  const double costmap_ms = ms_since(t0);
  PlannerOptions po;
  po.cost_weight = o.cost_weight;
  po.allow_unknown = o.allow_unknown;
  const AStarPlanner planner(costmap, po);
  t0 = std::chrono::steady_clock::now();
  const PlanResult r = planner.plan(start, goal);
  const double plan_ms = ms_since(t0);
  if (!r.found)
    throw InputError("--goal " + o.goal + " is unreachable from --start " + o.start + " in " + o.map +
                     " (robot radius " + std::to_string(o.robot_radius) + " m; " + std::to_string(r.cells_expanded) +
                     " cells searched)");
  if (!o.out.empty()) {
    std::ofstream csv(o.out);
    csv << "x,y\n" << std::fixed << std::setprecision(4);
    for (const auto& p : r.points) csv << p.x() << ',' << p.y() << '\n';
    if (!csv) throw Failure(located(o.out, 0, "cannot write path"));
  }
  if (!o.png.empty()) {
    MapDrawing d(grid, grid.width() > 800 ? 1 : 2);
    d.path(r.points);
    d.circle(start, 0.15, {0, 160, 0});
    d.circle(goal, 0.15, {0, 0, 220});
    if (!cv::imwrite(o.png, d.image())) throw Failure(located(o.png, 0, "cannot write picture"));
  }
  spdlog::info("path: {:.2f} m, {} waypoints, {} cells expanded, {:.1f} ms", r.length_m, r.points.size(),
               r.cells_expanded, plan_ms);
  return {{"length_m", r.length_m}, {"cost", r.cost}, {"waypoints", r.points.size()},
          {"cells_expanded", r.cells_expanded}, {"ms", plan_ms}, {"costmap_ms", costmap_ms},
          {"map_cells", static_cast<std::size_t>(grid.width()) * static_cast<std::size_t>(grid.height())}};
}

const bool registered_plan = register_command({
    .path = {"plan"},
    .description = "A* path planning on an occupancy grid map (map_server YAML)",
    .setup = [](CLI::App& cmd) -> Action {
      auto o = std::make_shared<PlanOptions>();
      cmd.add_option("--map", o->map, "map_server YAML")->required();
      cmd.add_option("--start", o->start, "Start X,Y in metres (map frame)")->required();
      cmd.add_option("--goal", o->goal, "Goal X,Y in metres")->required();
      cmd.add_option("--robot-radius", o->robot_radius, "Inscribed robot radius, metres")->capture_default_str()->check(CLI::NonNegativeNumber);
      cmd.add_option("--inflation-radius", o->inflation_radius, "Inflation radius, metres (default robot radius + 0.5)");
      cmd.add_option("--cost-scaling", o->cost_scaling, "Inflation decay, 1/m")->capture_default_str()->check(CLI::PositiveNumber);
      cmd.add_option("--cost-weight", o->cost_weight, "Weight of the inflation cost against length")->capture_default_str()->check(CLI::NonNegativeNumber);
      cmd.add_flag("--allow-unknown", o->allow_unknown, "Plan through unknown cells");
      cmd.add_option("--out", o->out, "Path as CSV (x,y)");
      cmd.add_option("--png", o->png, "Picture of the map with the path");
      return [o] { return run_plan(*o); };
    },
    .order = 40});

}  // namespace
}  // namespace builtscene::app
