#pragma once
// Occupancy grid mapping from 2D poses and laser scans (the source's "Occupancy Grid
// Mapping" component). Two update models:
//   - kSource: the source's integer evidence on a 0..100 scale: a cell starts unknown (-1),
//     is set to 50 when first observed, loses l_free (5) for each scan that passes through it
//     and gains l_occ (15) for each scan that ends in it, clamped to [0, 100];
//   - kInverseSensor: probabilistic log-odds with an inverse sensor model (p_occ, p_free),
//     clamped, reported as 100 * p.
// A cell is updated at most once per scan (occupied wins over free within a scan), so the
// many beams that cross the cells next to the robot do not count many times. A batch of one
// (pose, scan) pair updates the map incrementally; a batch of several erases the map and
// rebuilds it from them (the historical keyframes after optimization or a loop closure).
// The grid grows as needed.
#include <cstdint>
#include <filesystem>
#include <vector>

#include "ogm/ground_frame.hpp"
#include "ogm/laser_scan.hpp"
#include "ogm/occupancy_grid.hpp"

namespace builtscene {

struct PoseAndScan {
  Pose2D pose;  // scan origin in the ground frame
  LaserScan scan;
};

struct OccupancyMapperOptions {
  enum class Model { kSource, kInverseSensor };
  Model model = Model::kSource;
  double resolution = 0.05;
  double l_free = 5, l_occ = 15;           // kSource evidence steps on the 0..100 scale
  double p_free = 0.4, p_occ = 0.7;        // kInverseSensor
  double p_clamp = 0.97;                   // kInverseSensor: log-odds clamped to +-logit(p_clamp)
  double grow_margin = 2.0;                // metres added around what a scan needs
};

class OccupancyGridMapper {
 public:
  explicit OccupancyGridMapper(OccupancyMapperOptions options = {});

  // One pair: incremental update. Several: erase and rebuild from all of them.
  void integrate_batch(const std::vector<PoseAndScan>& batch);
  void integrate(const PoseAndScan& pair);
  void clear();

  // nav_msgs/OccupancyGrid values.
  OccupancyGrid grid() const;
  std::size_t scans_integrated() const { return scans_; }
  const OccupancyMapperOptions& options() const { return options_; }

  // Lossless state: options, geometry and the evidence of every cell, so mapping can go on later.
  void save_state(const std::filesystem::path& path) const;
  static OccupancyGridMapper load_state(const std::filesystem::path& path);

 private:
  OccupancyMapperOptions options_;
  int width_ = 0, height_ = 0;
  Eigen::Vector2d origin_ = Eigen::Vector2d::Zero();
  std::vector<float> evidence_;  // NaN = unknown
  std::vector<std::uint32_t> stamp_;  // last scan that touched a cell (once-per-scan rule)
  std::vector<std::uint8_t> hit_;     // whether that touch was a hit
  std::size_t scans_ = 0;

  void ensure_contains(double x0, double y0, double x1, double y1);
  std::size_t index(int col, int row) const {
    return static_cast<std::size_t>(row) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(col);
  }
  void apply(std::size_t i, bool occupied);
};

}  // namespace builtscene
