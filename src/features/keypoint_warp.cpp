#include "features/keypoint_warp.hpp"

#include <cmath>

#include "features/orb_extractor.hpp"

namespace builtscene {

double homography_local_scale(const cv::Matx33d& h, cv::Point2d p) {
  const double w = h(2, 0) * p.x + h(2, 1) * p.y + h(2, 2);
  const double x = (h(0, 0) * p.x + h(0, 1) * p.y + h(0, 2)) / w;
  const double y = (h(1, 0) * p.x + h(1, 1) * p.y + h(1, 2)) / w;
  const double j00 = (h(0, 0) - x * h(2, 0)) / w, j01 = (h(0, 1) - x * h(2, 1)) / w;
  const double j10 = (h(1, 0) - y * h(2, 0)) / w, j11 = (h(1, 1) - y * h(2, 1)) / w;
  return std::sqrt(std::abs(j00 * j11 - j01 * j10));
}

std::optional<cv::KeyPoint> warp_keypoint(const cv::Matx33d& h, const cv::KeyPoint& kp, const ScalePyramid& pyramid,
                                          cv::Size size2, int border) {
  const cv::Point2d p(kp.pt.x, kp.pt.y);
  const double w = h(2, 0) * p.x + h(2, 1) * p.y + h(2, 2);
  if (!(w > 1e-9)) return std::nullopt;
  const cv::Point2d q((h(0, 0) * p.x + h(0, 1) * p.y + h(0, 2)) / w, (h(1, 0) * p.x + h(1, 1) * p.y + h(1, 2)) / w);
  const double s = homography_local_scale(h, p);
  if (!(s > 1e-6) || !std::isfinite(q.x) || !std::isfinite(q.y)) return std::nullopt;
  // Seen s times larger in image 2, the same structure is found log_f(s) levels higher.
  const int level = kp.octave + static_cast<int>(std::lround(std::log(s) / std::log(static_cast<double>(pyramid.scale_factor))));
  if (level < 0 || level >= pyramid.levels()) return std::nullopt;
  const cv::Size ls = pyramid.level_size(size2, level);
  const cv::Point2f at_level = pyramid.to_level(cv::Point2f(static_cast<float>(q.x), static_cast<float>(q.y)), level, size2);
  const int x = cvRound(at_level.x), y = cvRound(at_level.y);
  if (x < border || y < border || x >= ls.width - border || y >= ls.height - border) return std::nullopt;
  cv::KeyPoint out = kp;
  out.pt = cv::Point2f(static_cast<float>(q.x), static_cast<float>(q.y));
  out.octave = level;
  return out;
}

}  // namespace builtscene
