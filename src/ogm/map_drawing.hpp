#pragma once
// Pictures of an occupancy grid in the style of the source's figures: free white, occupied
// black, unknown grey, the trajectory in blue, the robot as a red isosceles triangle with its
// apex along the heading, and the scan beams in green.
#include <filesystem>
#include <vector>

#include <opencv2/core.hpp>

#include "ogm/ground_frame.hpp"
#include "ogm/laser_scan.hpp"
#include "ogm/occupancy_grid.hpp"

namespace builtscene {

class MapDrawing {
 public:
  // `scale` image pixels per cell; the image's top row is the map's max y.
  MapDrawing(const OccupancyGrid& grid, int scale = 2);

  void trajectory(const std::vector<Pose2D>& poses, const cv::Scalar& bgr = {200, 80, 0});
  void path(const std::vector<Eigen::Vector2d>& points, const cv::Scalar& bgr = {0, 140, 255});
  void robot(const Pose2D& pose, double length_m = 0.4, const cv::Scalar& bgr = {0, 0, 220});
  void scan(const Pose2D& pose, const LaserScan& scan, const cv::Scalar& bgr = {0, 180, 0});
  void circle(const Eigen::Vector2d& p, double radius_m, const cv::Scalar& bgr);

  const cv::Mat& image() const { return image_; }

 private:
  OccupancyGrid grid_;
  int scale_;
  cv::Mat image_;
  cv::Point to_pixel(const Eigen::Vector2d& p) const;
};

// The usual picture of a mapping run: the grid, the track, the last pose as the robot and, when
// given, its scan; written as PNG. Failure naming the file when it cannot be written.
void write_track_picture(const std::filesystem::path& png, const OccupancyGrid& grid, const std::vector<Pose2D>& track,
                         const LaserScan* last_scan = nullptr, int scale = 2);

}  // namespace builtscene
