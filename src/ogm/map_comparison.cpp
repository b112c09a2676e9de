#include "ogm/map_comparison.hpp"

namespace builtscene {
namespace {

// Class of `grid` at the cell containing world point p, or -1 outside.
int class_at(const OccupancyGrid& grid, const Eigen::Vector2d& p, MapServerThresholds t) {
  const GridIndex c = grid.cell_of(p);
  return grid.contains(c) ? occupancy_class(grid.at(c), t) : -1;
}

bool any_within(const OccupancyGrid& grid, const Eigen::Vector2d& p, int tol, MapServerThresholds t, int wanted) {
  const double res = grid.resolution();
  for (int dy = -tol; dy <= tol; ++dy)
    for (int dx = -tol; dx <= tol; ++dx) {
      const int cls = class_at(grid, p + res * Eigen::Vector2d(dx, dy), t);
      if (wanted == 2 ? cls != -1 : cls == wanted) return true;
    }
  return false;
}

}  // namespace

bool occupied_within(const OccupancyGrid& grid, const Eigen::Vector2d& p, int tolerance, MapServerThresholds t) {
  return any_within(grid, p, tolerance, t, 1);
}

MapScore compare_maps(const OccupancyGrid& est, const OccupancyGrid& truth, int tol, MapServerThresholds t) {
  MapScore s;
  std::size_t occ_ok = 0, free_ok = 0, recalled = 0;
  for (int r = 0; r < est.height(); ++r)
    for (int c = 0; c < est.width(); ++c) {
      const int cls = occupancy_class(est.at({c, r}), t);
      const Eigen::Vector2d p = est.center_of({c, r});
      if (cls == 1) {
        ++s.estimated_occupied;
        if (any_within(truth, p, tol, t, 1)) ++occ_ok;
      } else if (cls == 0) {
        ++s.estimated_free;
        if (class_at(truth, p, t) == 0) ++free_ok;
      }
    }
  for (int r = 0; r < truth.height(); ++r)
    for (int c = 0; c < truth.width(); ++c) {
      if (occupancy_class(truth.at({c, r}), t) != 1) continue;
      const Eigen::Vector2d p = truth.center_of({c, r});
      if (!any_within(est, p, tol, t, 2)) continue;  // the estimate saw nothing here
      ++s.truth_occupied_observable;
      if (any_within(est, p, tol, t, 1)) ++recalled;
    }
  auto ratio = [](std::size_t a, std::size_t b) { return b == 0 ? 0.0 : static_cast<double>(a) / static_cast<double>(b); };
  s.occupied_precision = ratio(occ_ok, s.estimated_occupied);
  s.occupied_recall = ratio(recalled, s.truth_occupied_observable);
  s.free_agreement = ratio(free_ok, s.estimated_free);
  return s;
}

nlohmann::json to_json(const MapScore& s) {
  return {{"occupied_precision", s.occupied_precision}, {"occupied_recall", s.occupied_recall},
          {"free_agreement", s.free_agreement},         {"estimated_occupied", s.estimated_occupied},
          {"truth_occupied_observable", s.truth_occupied_observable}, {"estimated_free", s.estimated_free}};
}

}  // namespace builtscene
