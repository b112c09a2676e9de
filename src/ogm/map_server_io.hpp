#pragma once
// ROS map_server maps: a PGM image plus a YAML file with
//   image, resolution, origin [x, y, yaw], negate, occupied_thresh, free_thresh[, mode].
// Row 0 of the image is the top of the map (max y), so image rows are flipped against grid
// rows. Saved in map_saver's trinary style: occupied 0, free 254, unknown 205.
#include <filesystem>

#include "ogm/occupancy_grid.hpp"

namespace builtscene {

struct MapServerThresholds {
  double occupied = 0.65;
  double free = 0.196;
};

// `yaml_path` ends in .yaml; the PGM is written beside it with the same stem.
void save_map_server(const OccupancyGrid& grid, const std::filesystem::path& yaml_path,
                     MapServerThresholds thresholds = {});

// Loads trinary and scale modes (raw is read as scale); a non-zero origin yaw is rejected.
// Errors name the file and the field.
OccupancyGrid load_map_server(const std::filesystem::path& yaml_path);

// nav_msgs value -> trinary class: 1 occupied, 0 free, -1 unknown.
int occupancy_class(std::int8_t value, MapServerThresholds thresholds = {});

}  // namespace builtscene
