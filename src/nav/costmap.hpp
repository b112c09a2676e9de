#pragma once
// A navigation costmap over an occupancy grid with nav2's inflation semantics:
//   254 lethal (an occupied cell), 253 inscribed (the robot's centre would be within
//   robot_radius of an obstacle), 1..252 decaying as 252 * exp(-cost_scaling * (d - robot_radius))
//   up to inflation_radius, 0 free, 255 unknown. Distances come from OpenCV's exact Euclidean
//   distance transform between cell centres.
#include <cstdint>
#include <vector>

#include "ogm/occupancy_grid.hpp"

namespace builtscene {

struct CostmapOptions {
  double robot_radius = 0.30;      // metres (inscribed radius)
  double inflation_radius = 0.80;  // metres; beyond it the cost is 0
  double cost_scaling = 3.0;       // 1/metres
  bool unknown_is_obstacle = true; // unknown cells are lethal (else 255, traversable if allowed)
};

class Costmap {
 public:
  static constexpr std::uint8_t kLethal = 254, kInscribed = 253, kUnknown = 255, kMaxFree = 252;

  Costmap(const OccupancyGrid& grid, CostmapOptions options);

  int width() const { return grid_.width(); }
  int height() const { return grid_.height(); }
  const OccupancyGrid& grid() const { return grid_; }
  const CostmapOptions& options() const { return options_; }
  std::uint8_t cost(const GridIndex& c) const {
    return costs_[static_cast<std::size_t>(c.row) * static_cast<std::size_t>(grid_.width()) + static_cast<std::size_t>(c.col)];
  }
  // The robot's centre may stand here.
  bool traversable(const GridIndex& c, bool allow_unknown) const {
    const std::uint8_t v = cost(c);
    return v < kInscribed || (allow_unknown && v == kUnknown);
  }
  double obstacle_distance(const GridIndex& c) const;  // metres to the nearest obstacle cell centre

 private:
  OccupancyGrid grid_;
  CostmapOptions options_;
  std::vector<std::uint8_t> costs_;
  std::vector<float> distance_;  // metres
};

}  // namespace builtscene
