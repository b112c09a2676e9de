#pragma once
// A 2D occupancy grid in the ground frame with nav_msgs/OccupancyGrid semantics: cell (col,
// row) covers [origin + col*res, origin + (col+1)*res) in x and likewise in y (row 0 at the
// bottom, min y), values -1 unknown or 0..100 (probability of occupancy in percent).
#include <cstdint>
#include <vector>

#include <Eigen/Core>

namespace builtscene {

struct GridIndex {
  int col = 0, row = 0;
  bool operator==(const GridIndex&) const = default;
};

class OccupancyGrid {
 public:
  OccupancyGrid() = default;
  OccupancyGrid(int width, int height, double resolution, Eigen::Vector2d origin, std::int8_t fill = -1);

  int width() const { return width_; }
  int height() const { return height_; }
  double resolution() const { return resolution_; }
  const Eigen::Vector2d& origin() const { return origin_; }

  bool contains(const GridIndex& c) const { return c.col >= 0 && c.row >= 0 && c.col < width_ && c.row < height_; }
  GridIndex cell_of(const Eigen::Vector2d& p) const;
  Eigen::Vector2d center_of(const GridIndex& c) const;

  std::int8_t at(const GridIndex& c) const { return data_[index(c)]; }
  std::int8_t& at(const GridIndex& c) { return data_[index(c)]; }
  // -1 outside the grid.
  std::int8_t value_at(const Eigen::Vector2d& p) const;

  const std::vector<std::int8_t>& data() const { return data_; }
  std::vector<std::int8_t>& data() { return data_; }

 private:
  int width_ = 0, height_ = 0;
  double resolution_ = 0.05;
  Eigen::Vector2d origin_ = Eigen::Vector2d::Zero();
  std::vector<std::int8_t> data_;
  std::size_t index(const GridIndex& c) const {
    return static_cast<std::size_t>(c.row) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(c.col);
  }
};

// Cells on the segment from a to b, both included, in order (Bresenham).
std::vector<GridIndex> bresenham_line(GridIndex a, GridIndex b);

}  // namespace builtscene
