#include "ogm/virtual_laser_scanner.hpp"

#include <cmath>
#include <algorithm>
#include <limits>
#include <numbers>

#include "core/errors.hpp"

namespace builtscene {

VirtualLaserScanner::VirtualLaserScanner(const PinholeCamera& camera, VirtualLaserScanOptions options)
    : camera_(camera), options_(options) {
  if (!(options_.max_height > options_.min_height)) throw InputError("laser scan: max_height must exceed min_height");
  if (!(options_.range_max > options_.range_min) || options_.range_min < 0)
    throw InputError("laser scan: need 0 <= range_min < range_max");
  // Horizontal field of view from the image's left and right edges (plus a margin: a tilted
  // camera sees slightly wider bearings).
  const double half_fov = std::max(std::atan2(camera.cx + 0.5, camera.fx), std::atan2(camera.width - camera.cx - 0.5, camera.fx));
  angle_max_ = static_cast<float>(std::min(std::numbers::pi, half_fov * 1.25));
  angle_min_ = -angle_max_;
  angle_increment_ = static_cast<float>(options_.angle_increment > 0 ? options_.angle_increment : 2.0 / camera.fx);
  rays_.create(camera.height, camera.width, CV_32FC2);
  for (int v = 0; v < camera.height; ++v)
    for (int u = 0; u < camera.width; ++u) {
      const Eigen::Vector3d r = camera.unproject({u, v}, 1.0);
      rays_.at<cv::Vec2f>(v, u) = cv::Vec2f(static_cast<float>(r.x()), static_cast<float>(r.y()));
    }
}

LaserScan VirtualLaserScanner::scan(const cv::Mat& depth, const SE3& T_gc, double stamp) const {
  if (depth.type() != CV_32F || depth.rows != camera_.height || depth.cols != camera_.width)
    throw InputError("laser scan: depth image must be CV_32F of the camera's size");
  LaserScan s;
  s.stamp = stamp;
  s.angle_min = angle_min_;
  s.angle_increment = angle_increment_;
  const auto beams = static_cast<std::size_t>(std::floor((angle_max_ - angle_min_) / angle_increment_)) + 1;
  s.angle_max = angle_min_ + static_cast<float>(beams - 1) * angle_increment_;
  s.range_min = static_cast<float>(options_.range_min);
  s.range_max = static_cast<float>(options_.range_max);
  s.ranges.assign(beams, std::numeric_limits<float>::infinity());

  // Ground-frame point = R * (x, y, 1) * z + t. Express it in the scan frame directly:
  // rotate the ground xy by -heading about the camera's ground position.
  const Eigen::Matrix3d R = T_gc.rotation_matrix();
  const Eigen::Vector3d t = T_gc.translation();
  const Eigen::Vector3d fwd = R.col(2);
  const double heading = std::atan2(fwd.y(), fwd.x());
  const double ch = std::cos(heading), sh = std::sin(heading);
  Eigen::Matrix3d Rs;  // rows: scan x, scan y, up, in ground coordinates, applied to R
  Rs << ch, sh, 0, -sh, ch, 0, 0, 0, 1;
  const Eigen::Matrix3f M = (Rs * R).cast<float>();
  const float tz = static_cast<float>(t.z());
  const float min_h = static_cast<float>(options_.min_height), max_h = static_cast<float>(options_.max_height);
  const float rmin2 = s.range_min * s.range_min, rmax2 = s.range_max * s.range_max;
  const float inv_inc = 1.0f / angle_increment_;
  const int stride = std::max(1, options_.pixel_stride);
  std::vector<std::vector<float>> samples(options_.robust_nearest ? beams : 0);
  for (int v = 0; v < depth.rows; v += stride) {
    const float* drow = depth.ptr<float>(v);
    const cv::Vec2f* rrow = rays_.ptr<cv::Vec2f>(v);
    for (int u = 0; u < depth.cols; u += stride) {
      const float z = drow[u];
      if (!(z > 0.0f) || !std::isfinite(z)) continue;
      const float xc = rrow[u][0] * z, yc = rrow[u][1] * z;
      const float h = M(2, 0) * xc + M(2, 1) * yc + M(2, 2) * z + tz;
      if (h < min_h || h > max_h) continue;
      const float sx = M(0, 0) * xc + M(0, 1) * yc + M(0, 2) * z;
      const float sy = M(1, 0) * xc + M(1, 1) * yc + M(1, 2) * z;
      const float r2 = sx * sx + sy * sy;
      if (r2 < rmin2 || r2 > rmax2) continue;
      const float a = std::atan2(sy, sx);
      const int bin = static_cast<int>(std::lround((a - angle_min_) * inv_inc));
      if (bin < 0 || bin >= static_cast<int>(beams)) continue;
      const float r = std::sqrt(r2);
      if (options_.robust_nearest) {
        samples[static_cast<std::size_t>(bin)].push_back(r);
      } else {
        float& best = s.ranges[static_cast<std::size_t>(bin)];
        if (r < best) best = r;
      }
    }
  }
  if (options_.robust_nearest) {
    const auto k = static_cast<std::size_t>(std::max(1, options_.nearest_rank));
    for (std::size_t b = 0; b < beams; ++b) {
      auto& v = samples[b];
      if (v.size() < k) continue;  // too little support for a return: no reading
      std::sort(v.begin(), v.end());
      const float r0 = v[k - 1];
      const float width = static_cast<float>(options_.cluster_base + options_.cluster_quadratic * r0 * r0);
      const auto end = std::upper_bound(v.begin(), v.end(), r0 + width);
      const auto n = static_cast<std::size_t>(end - v.begin());
      s.ranges[b] = v[n / 2];  // median of the nearest cluster (starting at the nearest sample)
    }
  }
  return s;
}

}  // namespace builtscene
