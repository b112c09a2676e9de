#include "ogm/map_drawing.hpp"

#include <cmath>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/errors.hpp"
#include "ogm/map_server_io.hpp"

namespace builtscene {

MapDrawing::MapDrawing(const OccupancyGrid& grid, int scale) : grid_(grid), scale_(std::max(1, scale)) {
  image_.create(std::max(1, grid.height()) * scale_, std::max(1, grid.width()) * scale_, CV_8UC3);
  image_.setTo(cv::Scalar(205, 205, 205));
  for (int r = 0; r < grid.height(); ++r)
    for (int c = 0; c < grid.width(); ++c) {
      const int cls = occupancy_class(grid.at({c, r}));
      if (cls < 0) continue;
      const cv::Scalar colour = cls == 1 ? cv::Scalar(0, 0, 0) : cv::Scalar(255, 255, 255);
      cv::rectangle(image_, cv::Rect(c * scale_, (grid.height() - 1 - r) * scale_, scale_, scale_), colour, cv::FILLED);
    }
}

cv::Point MapDrawing::to_pixel(const Eigen::Vector2d& p) const {
  const double u = (p.x() - grid_.origin().x()) / grid_.resolution() * scale_;
  const double v = (grid_.height() - (p.y() - grid_.origin().y()) / grid_.resolution()) * scale_;
  return {static_cast<int>(std::lround(u)), static_cast<int>(std::lround(v))};
}

void MapDrawing::trajectory(const std::vector<Pose2D>& poses, const cv::Scalar& bgr) {
  for (std::size_t i = 1; i < poses.size(); ++i)
    cv::line(image_, to_pixel({poses[i - 1].x, poses[i - 1].y}), to_pixel({poses[i].x, poses[i].y}), bgr, 1, cv::LINE_AA);
}

void MapDrawing::path(const std::vector<Eigen::Vector2d>& points, const cv::Scalar& bgr) {
  for (std::size_t i = 1; i < points.size(); ++i) cv::line(image_, to_pixel(points[i - 1]), to_pixel(points[i]), bgr, 2, cv::LINE_AA);
}

void MapDrawing::robot(const Pose2D& p, double len, const cv::Scalar& bgr) {
  const Eigen::Vector2d c(p.x, p.y), f(std::cos(p.theta), std::sin(p.theta)), l(-f.y(), f.x());
  const std::vector<cv::Point> tri{to_pixel(c + f * len * 0.6), to_pixel(c - f * len * 0.4 + l * len * 0.25),
                                   to_pixel(c - f * len * 0.4 - l * len * 0.25)};
  cv::fillConvexPoly(image_, tri, bgr, cv::LINE_AA);
}

void MapDrawing::scan(const Pose2D& p, const LaserScan& s, const cv::Scalar& bgr) {
  const cv::Point origin = to_pixel({p.x, p.y});
  for (std::size_t i = 0; i < s.ranges.size(); i += 4) {
    if (!s.valid(i)) continue;
    const double a = p.theta + s.beam_angle(i);
    cv::line(image_, origin, to_pixel({p.x + s.ranges[i] * std::cos(a), p.y + s.ranges[i] * std::sin(a)}), bgr, 1);
  }
}

void MapDrawing::circle(const Eigen::Vector2d& p, double radius_m, const cv::Scalar& bgr) {
  cv::circle(image_, to_pixel(p), std::max(2, static_cast<int>(radius_m / grid_.resolution() * scale_)), bgr, 2, cv::LINE_AA);
}

void write_track_picture(const std::filesystem::path& png, const OccupancyGrid& grid, const std::vector<Pose2D>& track,
                         const LaserScan* last_scan, int scale) {
  MapDrawing d(grid, scale);
  d.trajectory(track);
  if (!track.empty()) {
    if (last_scan) d.scan(track.back(), *last_scan);
    d.robot(track.back());
  }
  if (!cv::imwrite(png.string(), d.image())) throw Failure(located(png, 0, "cannot write picture"));
}

}  // namespace builtscene
