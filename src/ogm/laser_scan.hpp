#pragma once
// A planar range scan with the fields of sensor_msgs/LaserScan. Beam i points at angle
// angle_min + i * angle_increment in the scan frame (x forward, y left, counter-clockwise).
#include <cstdint>
#include <vector>

namespace builtscene {

struct LaserScan {
  double stamp = 0;
  float angle_min = 0, angle_max = 0, angle_increment = 0;
  float time_increment = 0, scan_time = 0;
  float range_min = 0, range_max = 0;
  std::vector<float> ranges;       // +inf where no return (REP 117), NaN never stored
  std::vector<float> intensities;  // empty: no intensities

  double beam_angle(std::size_t i) const { return angle_min + static_cast<double>(i) * angle_increment; }
  bool valid(std::size_t i) const { return ranges[i] >= range_min && ranges[i] <= range_max; }
};

}  // namespace builtscene
