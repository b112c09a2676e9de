#pragma once
// Ground-truth occupancy of a height band, computed from the scene geometry (never from
// renders): a cell is occupied when a solid box whose height range overlaps the band
// overlaps the cell's square; free when its centre is on a floor region and it is not
// occupied; unknown otherwise. Saved in ROS map_server format.
#include <filesystem>
#include <vector>

#include <opencv2/core.hpp>

#include "synth/scene.hpp"

namespace builtscene::synth {

struct OccupancyTruth {
  double resolution = 0.05;
  double origin_x = 0, origin_y = 0;  // world coordinates of the lower-left corner of cell (0, 0)
  int width = 0, height = 0;
  std::vector<signed char> cells;     // row-major, row 0 = lowest y; -1 unknown, 0 free, 100 occupied

  signed char at(int col, int row) const { return cells[static_cast<std::size_t>(row) * width + col]; }
  // Cell containing world point (x, y); false outside the grid.
  bool cell_of(double x, double y, int& col, int& row) const;
  // Value at a world point; -1 outside the grid.
  int value_at(double x, double y) const;
};

OccupancyTruth compute_truth_map(const Scene& scene, double band_min, double band_max, double resolution = 0.05);

// Writes NAME.pgm (row 0 = top = max y; free 254, occupied 0, unknown 205) and NAME.yaml.
void write_truth_map(const OccupancyTruth& map, const std::filesystem::path& pgm, const std::filesystem::path& yaml,
                     double band_min, double band_max);

// Distance in metres from each cell centre to the nearest cell that is not free (CV_32F,
// rows as OccupancyTruth: row 0 = lowest y).
cv::Mat clearance_map(const OccupancyTruth& map);

}  // namespace builtscene::synth
