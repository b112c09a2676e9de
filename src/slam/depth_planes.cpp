#include "slam/depth_planes.hpp"

#include <cmath>
#include <random>

#include <Eigen/Eigenvalues>

namespace builtscene::slam {

void fit_plane_least_squares(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& orient_like,
                             Eigen::Vector3d& n, double& d) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) mean += p;
  mean /= static_cast<double>(points.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : points) cov += (p - mean) * (p - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(cov);
  Eigen::Vector3d m = es.eigenvectors().col(0).normalized();
  if (m.dot(orient_like) < 0) m = -m;  // (orient_like may be n itself)
  n = m;
  d = -n.dot(mean);
}

std::vector<PlaneMeasurement> extract_depth_planes(const cv::Mat& depth_m, double fx, double fy, double cx, double cy,
                                                   const DepthPlaneOptions& opt) {
  std::vector<PlaneMeasurement> out;
  if (depth_m.empty() || depth_m.type() != CV_32F || !(fx > 0) || !(fy > 0) || opt.stride_px < 1) return out;
  auto point_at = [&](int u, int v, Eigen::Vector3d& p) {
    if (u < 0 || v < 0 || u >= depth_m.cols || v >= depth_m.rows) return false;
    const float z = depth_m.at<float>(v, u);
    if (!(z > 0) || !std::isfinite(z) || z > opt.max_depth_m) return false;
    p = Eigen::Vector3d((u - cx) / fx * z, (v - cy) / fy * z, z);
    return true;
  };
  // Points with their own surface normal (central differences over +-k pixels): the normal
  // test keeps a wall's foot, within the floor's inlier band, out of the floor.
  const int k = opt.normal_step_px;
  std::vector<Eigen::Vector3d> pts, normals;
  for (int v = 0; v < depth_m.rows; v += opt.stride_px)
    for (int u = 0; u < depth_m.cols; u += opt.stride_px) {
      Eigen::Vector3d p, l, r, t, b;
      if (!point_at(u, v, p)) continue;
      if (!point_at(u - k, v, l) || !point_at(u + k, v, r) || !point_at(u, v - k, t) || !point_at(u, v + k, b)) continue;
      const Eigen::Vector3d n = (r - l).cross(b - t);
      if (!(n.norm() > 0)) continue;
      pts.push_back(p);
      normals.push_back(n.normalized());
    }
  const double cos_dev = std::cos(opt.max_normal_dev_deg * M_PI / 180.0);
  std::vector<char> used(pts.size(), 0);
  // (Only ever asked of points not yet taken by an earlier plane.)
  auto is_inlier = [&](std::size_t i, const Eigen::Vector3d& n, double d) {
    return std::abs(n.dot(pts[i]) + d) < opt.inlier_m && std::abs(n.dot(normals[i])) >= cos_dev;
  };
  std::mt19937 rng(12345);
  for (int plane = 0; plane < opt.max_planes; ++plane) {
    std::vector<std::size_t> free;
    for (std::size_t i = 0; i < pts.size(); ++i)
      if (!used[i]) free.push_back(i);
    if (free.size() < opt.min_inliers) break;
    std::uniform_int_distribution<std::size_t> pick(0, free.size() - 1);
    std::size_t best = 0;
    Eigen::Vector3d best_n = Eigen::Vector3d::UnitZ();
    double best_d = 0;
    for (int it = 0; it < opt.iterations; ++it) {
      const Eigen::Vector3d &a = pts[free[pick(rng)]], &b = pts[free[pick(rng)]], &c = pts[free[pick(rng)]];
      Eigen::Vector3d n = (b - a).cross(c - a);
      if (n.norm() < 1e-6) continue;
      n.normalize();
      const double d = -n.dot(a);
      std::size_t count = 0;
      for (const std::size_t i : free) count += is_inlier(i, n, d);
      if (count > best) best = count, best_n = n, best_d = d;
    }
    if (best < opt.min_inliers) break;
    // Least-squares refit, twice (the refit plane's inliers, then again).
    Eigen::Vector3d n = best_n;
    double d = best_d;
    std::size_t count = 0;
    for (int pass = 0; pass < 2; ++pass) {
      std::vector<Eigen::Vector3d> inliers;
      for (const std::size_t i : free)
        if (is_inlier(i, n, d)) inliers.push_back(pts[i]);
      count = inliers.size();
      if (count < 3) break;
      fit_plane_least_squares(inliers, n, n, d);
    }
    if (count < opt.min_inliers) break;
    for (const std::size_t i : free)
      if (is_inlier(i, n, d)) used[i] = 1;
    if (d < 0) n = -n, d = -d;
    if (d < 1e-3) continue;  // through the camera: not a surface it sees
    out.push_back({n, d, count});
  }
  return out;
}

}  // namespace builtscene::slam
