#pragma once
// A virtual laser scan cut out of a depth image, with pointcloud_to_laserscan semantics:
// points whose height above the floor lies in [min_height, max_height] are projected onto the
// floor, binned by bearing in the scan frame, and the nearest range per bin is kept. The band
// catches obstacles at any height in it (a desk top and its legs alike), which a 2D lidar at
// one height misses. The scan frame sits on the floor below the camera, x along the camera's
// heading (its optical axis projected on the floor), y to the left.
//
// One deviation from pointcloud_to_laserscan, for depth cameras: the plain minimum over a bin
// is biased towards the camera by the depth noise (the least of many noisy samples), which
// puts walls seen from 4-6 m one to three cells too close. Each bin therefore reports the
// median of its nearest cluster: the samples within cluster_width(r) of the k-th nearest
// sample r, with cluster_width(r) = cluster_base + cluster_quadratic * r^2 (depth noise of
// structured-light and stereo sensors grows with the square of the range).
#include <opencv2/core.hpp>

#include "core/camera.hpp"
#include "core/se3.hpp"
#include "ogm/laser_scan.hpp"

namespace builtscene {

struct VirtualLaserScanOptions {
  double min_height = 0.05;     // metres above the floor
  double max_height = 1.30;     // the generated worlds' robot band is [0.05, 1.3]
  double range_min = 0.45;      // metres, on the floor plane
  double range_max = 4.0;       // Kinect-class depth is too noisy for mapping beyond ~4 m
  double angle_increment = 0;   // radians; 0 = half a pixel column's angle at the centre x 2
  int pixel_stride = 2;         // use every n-th pixel in both directions
  int nearest_rank = 3;         // k: rank of the sample that anchors the nearest cluster (1 = plain minimum)
  double cluster_base = 0.03;   // metres
  double cluster_quadratic = 0.006;  // 1/metres
  bool robust_nearest = true;   // false: plain minimum (pointcloud_to_laserscan)
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
