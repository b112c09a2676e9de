#pragma once
// Scores an occupancy grid against a ground-truth grid (both in the same ground frame; their
// extents and origins may differ, cells are compared by their centres):
//   occupied precision: estimated-occupied cells with a truth-occupied cell within `tolerance` cells;
//   occupied recall: truth-occupied cells with an estimated-occupied cell within `tolerance`,
//     counted only where the estimate observed something within `tolerance` (an unobserved
//     wall cannot be recalled by any map);
//   free agreement: estimated-free cells that are free in the truth (observed cells only).
#include <nlohmann/json.hpp>

#include "ogm/map_server_io.hpp"
#include "ogm/occupancy_grid.hpp"

namespace builtscene {

struct MapScore {
  double occupied_precision = 0, occupied_recall = 0, free_agreement = 0;
  std::size_t estimated_occupied = 0, truth_occupied_observable = 0, estimated_free = 0;
};

MapScore compare_maps(const OccupancyGrid& estimate, const OccupancyGrid& truth, int tolerance = 1,
                      MapServerThresholds thresholds = {});
nlohmann::json to_json(const MapScore& s);

// Whether an occupied cell (by the map_server thresholds) lies within `tolerance` cells of the
// cell holding world point p: the mapping tolerance used by the scores above and by the check
// of live scans against a map.
bool occupied_within(const OccupancyGrid& grid, const Eigen::Vector2d& p, int tolerance,
                     MapServerThresholds thresholds = {});

}  // namespace builtscene
