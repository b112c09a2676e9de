#pragma once
// A virtual laser scan cut out of a depth image, with pointcloud_to_laserscan semantics:
// points whose height above the floor lies in [min_height, max_height] are projected onto the
// floor, binned by bearing in the scan frame, and the nearest range per bin is kept. The band
// catches obstacles at any height in it (a desk top and its legs alike), which a 2D lidar at
// one height misses. The scan frame sits on the floor below the camera, x along the camera's
// heading (its optical axis projected on the floor), y to the left.
#include <opencv2/core.hpp>

#include "core/camera.hpp"
#include "core/se3.hpp"
#include "ogm/laser_scan.hpp"

namespace builtscene {

struct VirtualLaserScanOptions {
  double min_height = 0.05;     // metres above the floor
  double max_height = 1.50;
  double range_min = 0.45;      // metres, on the floor plane
  double range_max = 8.0;
  double angle_increment = 0;   // radians; 0 = half a pixel column's angle at the centre x 2
  int pixel_stride = 1;         // use every n-th pixel in both directions
};

class VirtualLaserScanner {
 public:
  VirtualLaserScanner(const PinholeCamera& camera, VirtualLaserScanOptions options);

  // depth: CV_32F metres (0 = none). T_gc: the camera in the ground frame (z up, floor z=0).
  LaserScan scan(const cv::Mat& depth, const SE3& T_gc, double stamp = 0) const;

  const VirtualLaserScanOptions& options() const { return options_; }

 private:
  PinholeCamera camera_;
  VirtualLaserScanOptions options_;
  float angle_min_, angle_max_, angle_increment_;
  cv::Mat rays_;  // CV_32FC2: undistorted normalized (x/z, y/z) per pixel
};

}  // namespace builtscene
