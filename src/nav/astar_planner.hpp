#pragma once
// A* on the 8-connected costmap grid with the octile-distance heuristic. A step costs its
// length in metres times (1 + cost_weight * cost / 252), so paths keep away from obstacles
// where that is cheap; the heuristic (length only) stays admissible, so the path found is
// optimal for that cost. Diagonal steps never cut the corner of a non-traversable cell.
// Plan again from a new start whenever the pose changes: the costmap is reused.
#include <vector>

#include <Eigen/Core>

#include "nav/costmap.hpp"

namespace builtscene {

struct PlannerOptions {
  double cost_weight = 3.0;
  bool allow_unknown = false;
};

struct PlanResult {
  bool found = false;
  std::vector<GridIndex> cells;          // start to goal
  std::vector<Eigen::Vector2d> points;   // cell centres, metres
  double length_m = 0;                   // geometric length
  double cost = 0;                       // the objective A* minimised
  std::size_t cells_expanded = 0;
};

class AStarPlanner {
 public:
  AStarPlanner(const Costmap& costmap, PlannerOptions options = {});
  // Throws InputError when start or goal is off the map or not traversable.
  PlanResult plan(const Eigen::Vector2d& start, const Eigen::Vector2d& goal) const;
  PlanResult plan(const GridIndex& start, const GridIndex& goal) const;

  // The cost of stepping from a to its neighbour b (shared with any reference planner).
  double step_cost(const GridIndex& a, const GridIndex& b) const;
  bool can_step(const GridIndex& a, const GridIndex& b) const;

 private:
  const Costmap& costmap_;
  PlannerOptions options_;
};

}  // namespace builtscene
