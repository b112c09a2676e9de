#include "slam/floor_plane.hpp"

#include <cmath>
#include <random>
#include <vector>

#include "slam/depth_planes.hpp"

namespace builtscene::slam {

std::optional<FloorPlane> estimate_floor_plane(const cv::Mat& depth_m, const PinholeCamera& cam,
                                               const Eigen::Vector3d& up_guess_c, const FloorPlaneOptions& opt) {
  if (depth_m.empty() || depth_m.type() != CV_32F || cam.fx <= 0 || cam.fy <= 0) return std::nullopt;
  const Eigen::Vector3d guess = up_guess_c.normalized();
  const double cos_max = std::cos(opt.max_tilt_from_guess_deg * M_PI / 180.0);
  const double cos_local = std::cos(opt.max_local_tilt_deg * M_PI / 180.0);
  auto point_at = [&](int u, int v, Eigen::Vector3d& p) {
    if (u < 0 || v < 0 || u >= depth_m.cols || v >= depth_m.rows) return false;
    const float z = depth_m.at<float>(v, u);
    if (!(z > 0) || !std::isfinite(z) || z > opt.max_depth_m) return false;
    p = Eigen::Vector3d((u - cam.cx) / cam.fx * z, (v - cam.cy) / cam.fy * z, z);
    return true;
  };
  // Candidates: points at least min_height below the camera along the guessed up axis whose
  // own surface (central differences over +-k pixels) faces up. The local test keeps the foot
  // of a wall, within the inlier band of the floor, out of the fit.
  const int k = opt.normal_step_px;
  std::vector<Eigen::Vector3d> pts;
  for (int v = 0; v < depth_m.rows; v += opt.stride_px)
    for (int u = 0; u < depth_m.cols; u += opt.stride_px) {
      Eigen::Vector3d p, l, r, t, b;
      if (!point_at(u, v, p) || p.dot(guess) >= -opt.min_height_m) continue;
      if (!point_at(u - k, v, l) || !point_at(u + k, v, r) || !point_at(u, v - k, t) || !point_at(u, v + k, b)) continue;
      const Eigen::Vector3d n = (r - l).cross(b - t);
      if (n.norm() <= 0 || std::abs(n.normalized().dot(guess)) < cos_local) continue;
      pts.push_back(p);
    }
  if (pts.size() < opt.min_inliers) return std::nullopt;
  std::mt19937 rng(12345);
  std::uniform_int_distribution<std::size_t> pick(0, pts.size() - 1);
  std::size_t best = 0;
  Eigen::Vector3d best_n = guess;
  double best_d = 0;
  for (int it = 0; it < opt.iterations; ++it) {
    const Eigen::Vector3d &a = pts[pick(rng)], &b = pts[pick(rng)], &c = pts[pick(rng)];
    Eigen::Vector3d n = (b - a).cross(c - a);
    if (n.norm() < 1e-6) continue;
    n.normalize();
    if (n.dot(guess) < 0) n = -n;
    if (n.dot(guess) < cos_max) continue;
    const double d = -n.dot(a);  // n.p + d = 0 on the plane; d > 0: the camera is above it
    if (d < opt.min_height_m) continue;
    std::size_t count = 0;
    for (const auto& p : pts) count += std::abs(n.dot(p) + d) < opt.inlier_m;
    if (count > best) best = count, best_n = n, best_d = d;
  }
  if (best < opt.min_inliers) return std::nullopt;
  // Least-squares refit (twice: the refit plane's inliers, then again).
  Eigen::Vector3d n = best_n;
  double d = best_d;
  std::size_t count = 0;
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<Eigen::Vector3d> inliers;
    for (const auto& p : pts)
      if (std::abs(n.dot(p) + d) < opt.inlier_m) inliers.push_back(p);
    count = inliers.size();
    if (count < opt.min_inliers) return std::nullopt;
    fit_plane_least_squares(inliers, guess, n, d);
  }
  if (d < opt.min_height_m || n.dot(guess) < cos_max) return std::nullopt;
  return FloorPlane{n, d, count};
}

}  // namespace builtscene::slam
