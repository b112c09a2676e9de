#include "nav/astar_planner.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <sstream>

#include "core/errors.hpp"

namespace builtscene {
namespace {

std::string describe(const Eigen::Vector2d& p) {
  std::ostringstream s;
  s << p.x() << "," << p.y();
  return s.str();
}

}  // namespace

AStarPlanner::AStarPlanner(const Costmap& costmap, PlannerOptions options) : costmap_(costmap), options_(options) {}

bool AStarPlanner::can_step(const GridIndex& a, const GridIndex& b) const {
  const OccupancyGrid& g = costmap_.grid();
  if (!g.contains(b) || !costmap_.traversable(b, options_.allow_unknown)) return false;
  if (a.col != b.col && a.row != b.row)  // diagonal: both side cells must be passable
    return costmap_.traversable({b.col, a.row}, options_.allow_unknown) &&
           costmap_.traversable({a.col, b.row}, options_.allow_unknown);
  return true;
}

double AStarPlanner::step_cost(const GridIndex& a, const GridIndex& b) const {
  const double len = (a.col != b.col && a.row != b.row ? std::sqrt(2.0) : 1.0) * costmap_.grid().resolution();
  const std::uint8_t c = costmap_.cost(b);
  const double cell_cost = c == Costmap::kUnknown ? Costmap::kMaxFree : c;
  return len * (1.0 + options_.cost_weight * cell_cost / Costmap::kMaxFree);
}

PlanResult AStarPlanner::plan(const Eigen::Vector2d& start, const Eigen::Vector2d& goal) const {
  const OccupancyGrid& g = costmap_.grid();
  const GridIndex s = g.cell_of(start), t = g.cell_of(goal);
  auto extent = [&] {
    std::ostringstream o;
    o << "x in [" << g.origin().x() << ", " << g.origin().x() + g.width() * g.resolution() << "], y in ["
      << g.origin().y() << ", " << g.origin().y() + g.height() * g.resolution() << "]";
    return o.str();
  };
  if (!g.contains(s)) throw InputError("--start " + describe(start) + " is off the map (" + extent() + ")");
  if (!g.contains(t)) throw InputError("--goal " + describe(goal) + " is off the map (" + extent() + ")");
  auto check = [&](const GridIndex& c, const char* what, const Eigen::Vector2d& p) {
    if (costmap_.traversable(c, options_.allow_unknown)) return;
    const std::uint8_t v = costmap_.cost(c);
    const std::string why = v == Costmap::kLethal ? "inside an obstacle"
                            : v == Costmap::kUnknown ? "in unknown space"
                                                     : "within the robot radius of an obstacle";
    throw InputError(std::string(what) + " " + describe(p) + " is " + why);
  };
  check(s, "--start", start);
  check(t, "--goal", goal);
  return plan(s, t);
}

PlanResult AStarPlanner::plan(const GridIndex& s, const GridIndex& t) const {
  const OccupancyGrid& g = costmap_.grid();
  const int w = g.width();
  const std::size_t n = static_cast<std::size_t>(w) * static_cast<std::size_t>(g.height());
  auto idx = [w](const GridIndex& c) { return static_cast<std::size_t>(c.row) * static_cast<std::size_t>(w) + static_cast<std::size_t>(c.col); };
  const double res = g.resolution();
  auto heuristic = [&](const GridIndex& c) {
    const double dx = std::abs(c.col - t.col), dy = std::abs(c.row - t.row);
    return res * ((dx + dy) + (std::sqrt(2.0) - 2.0) * std::min(dx, dy));
  };
  std::vector<double> gcost(n, std::numeric_limits<double>::infinity());
  std::vector<std::int32_t> parent(n, -1);
  std::vector<std::uint8_t> closed(n, 0);
  using Entry = std::pair<double, std::size_t>;  // (f, index)
  std::priority_queue<Entry, std::vector<Entry>, std::greater<>> open;
  gcost[idx(s)] = 0;
  open.push({heuristic(s), idx(s)});
  PlanResult r;
  while (!open.empty()) {
    const auto [f, i] = open.top();
    open.pop();
    if (closed[i]) continue;
    closed[i] = 1;
    ++r.cells_expanded;
    const GridIndex c{static_cast<int>(i % static_cast<std::size_t>(w)), static_cast<int>(i / static_cast<std::size_t>(w))};
    if (c == t) {
      r.found = true;
      break;
    }
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        if (!dx && !dy) continue;
        const GridIndex nb{c.col + dx, c.row + dy};
        if (!can_step(c, nb)) continue;
        const std::size_t j = idx(nb);
        if (closed[j]) continue;
        const double ng = gcost[i] + step_cost(c, nb);
        if (ng < gcost[j]) {
          gcost[j] = ng;
          parent[j] = static_cast<std::int32_t>(i);
          open.push({ng + heuristic(nb), j});
        }
      }
  }
  if (!r.found) return r;
  r.cost = gcost[idx(t)];
  for (std::int64_t i = static_cast<std::int64_t>(idx(t)); i >= 0; i = parent[static_cast<std::size_t>(i)]) {
    const auto u = static_cast<std::size_t>(i);
    r.cells.push_back({static_cast<int>(u % static_cast<std::size_t>(w)), static_cast<int>(u / static_cast<std::size_t>(w))});
  }
  std::reverse(r.cells.begin(), r.cells.end());
  for (const auto& c : r.cells) r.points.push_back(g.center_of(c));
  for (std::size_t k = 1; k < r.points.size(); ++k) r.length_m += (r.points[k] - r.points[k - 1]).norm();
  return r;
}

}  // namespace builtscene
