#include "nav/costmap.hpp"

#include <cmath>

#include <opencv2/imgproc.hpp>

#include "core/errors.hpp"
#include "ogm/map_server_io.hpp"

namespace builtscene {

Costmap::Costmap(const OccupancyGrid& grid, CostmapOptions options) : grid_(grid), options_(options) {
  if (options_.robot_radius < 0 || options_.inflation_radius < options_.robot_radius)
    throw InputError("costmap: need 0 <= robot radius <= inflation radius");
  const int w = grid.width(), h = grid.height();
  const std::size_t n = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  costs_.assign(n, 0);
  distance_.assign(n, std::numeric_limits<float>::infinity());
  if (n == 0) return;
  // Obstacle cells are the zeros of the distance transform's input.
  cv::Mat free_mask(h, w, CV_8UC1);
  bool any_obstacle = false;
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) {
      const int cls = occupancy_class(grid.at({c, r}));
      const bool obstacle = cls == 1 || (cls == -1 && options_.unknown_is_obstacle);
      free_mask.at<std::uint8_t>(r, c) = obstacle ? 0 : 255;
      any_obstacle |= obstacle;
    }
  cv::Mat dist;
  if (any_obstacle) cv::distanceTransform(free_mask, dist, cv::DIST_L2, cv::DIST_MASK_PRECISE, CV_32F);
  const double res = grid.resolution();
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) {
      const std::size_t i = static_cast<std::size_t>(r) * static_cast<std::size_t>(w) + static_cast<std::size_t>(c);
      const int cls = occupancy_class(grid.at({c, r}));
      if (cls == 1 || (cls == -1 && options_.unknown_is_obstacle)) {
        costs_[i] = kLethal;
        distance_[i] = 0;
        continue;
      }
      const double d = any_obstacle ? dist.at<float>(r, c) * res : std::numeric_limits<double>::infinity();
      distance_[i] = static_cast<float>(d);
      std::uint8_t v = 0;
      if (d <= options_.robot_radius) v = kInscribed;
      else if (d <= options_.inflation_radius)
        v = static_cast<std::uint8_t>(std::lround(kMaxFree * std::exp(-options_.cost_scaling * (d - options_.robot_radius))));
      if (cls == -1 && v < kInscribed) v = kUnknown;
      costs_[i] = v;
    }
}

double Costmap::obstacle_distance(const GridIndex& c) const {
  return distance_[static_cast<std::size_t>(c.row) * static_cast<std::size_t>(grid_.width()) + static_cast<std::size_t>(c.col)];
}

}  // namespace builtscene
