#pragma once
// ROS map_server maps: a PGM image plus a YAML file with
//   image, resolution, origin [x, y, yaw], negate, occupied_thresh, free_thresh[, mode].
// Row 0 of the image is the top of the map (max y), so image rows are flipped against grid
// rows. Saved in map_saver's trinary style: occupied 0, free 254, unknown 205.
#include <filesystem>
#include <optional>

#include "core/se3.hpp"
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

// A map built beside a SLAM lies in a ground frame of the SLAM's world (ground_frame.hpp).
// Its transform T_gw is kept in the map's YAML under `ground_frame_T_gw: [tx, ty, tz, qx, qy,
// qz, qw]`, a key map_server ignores, so a later localization in that SLAM map can put its
// poses on the grid. Absent key: nullopt (the map is in its world's own z-up frame).
void append_ground_frame(const std::filesystem::path& yaml_path, const SE3& T_gw);
std::optional<SE3> read_ground_frame(const std::filesystem::path& yaml_path);

// nav_msgs value -> trinary class: 1 occupied, 0 free, -1 unknown.
int occupancy_class(std::int8_t value, MapServerThresholds thresholds = {});

}  // namespace builtscene
