#include "ogm/occupancy_grid.hpp"

#include <cmath>
#include <cstdlib>

namespace builtscene {

OccupancyGrid::OccupancyGrid(int width, int height, double resolution, Eigen::Vector2d origin, std::int8_t fill)
    : width_(width),
      height_(height),
      resolution_(resolution),
      origin_(origin),
      data_(static_cast<std::size_t>(width) * static_cast<std::size_t>(height), fill) {}

GridIndex OccupancyGrid::cell_of(const Eigen::Vector2d& p) const {
  return {static_cast<int>(std::floor((p.x() - origin_.x()) / resolution_)),
          static_cast<int>(std::floor((p.y() - origin_.y()) / resolution_))};
}

Eigen::Vector2d OccupancyGrid::center_of(const GridIndex& c) const {
  return origin_ + resolution_ * Eigen::Vector2d(c.col + 0.5, c.row + 0.5);
}

std::int8_t OccupancyGrid::value_at(const Eigen::Vector2d& p) const {
  const GridIndex c = cell_of(p);
  return contains(c) ? at(c) : std::int8_t{-1};
}

std::vector<GridIndex> bresenham_line(GridIndex a, GridIndex b) {
  std::vector<GridIndex> out;
  const int dx = std::abs(b.col - a.col), dy = -std::abs(b.row - a.row);
  const int sx = a.col < b.col ? 1 : -1, sy = a.row < b.row ? 1 : -1;
  int err = dx + dy;
  out.reserve(static_cast<std::size_t>(std::max(dx, -dy) + 1));
  while (true) {
    out.push_back(a);
    if (a == b) break;
    const int e2 = 2 * err;
    if (e2 >= dy) {
      err += dy;
      a.col += sx;
    }
    if (e2 <= dx) {
      err += dx;
      a.row += sy;
    }
  }
  return out;
}

}  // namespace builtscene
