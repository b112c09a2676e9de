#include "core/camera.hpp"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <string>

#include "core/errors.hpp"
#include "core/settings_file.hpp"

namespace builtscene {

Eigen::Vector2d PinholeCamera::distort(const Eigen::Vector2d& xn) const {
  const double x = xn.x(), y = xn.y();
  const double r2 = x * x + y * y;
  const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
  return {x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
          y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y};
}

Eigen::Vector2d PinholeCamera::undistort(const Eigen::Vector2d& xd) const {
  if (!has_distortion()) return xd;
  Eigen::Vector2d x = xd;
  for (int i = 0; i < 50; ++i) {
    const Eigen::Vector2d err = distort(x) - xd;
    x -= err;
    if (err.squaredNorm() < 1e-24) break;
  }
  return x;
}

Eigen::Vector2d PinholeCamera::project(const Eigen::Vector3d& p) const {
  Eigen::Vector2d xn(p.x() / p.z(), p.y() / p.z());
  if (has_distortion()) xn = distort(xn);
  return {fx * xn.x() + cx, fy * xn.y() + cy};
}

Eigen::Vector2d PinholeCamera::undistort_pixel(const Eigen::Vector2d& px) const {
  if (!has_distortion()) return px;
  const Eigen::Vector2d xn = undistort({(px.x() - cx) / fx, (px.y() - cy) / fy});
  return {fx * xn.x() + cx, fy * xn.y() + cy};
}

Eigen::Vector3d PinholeCamera::unproject(const Eigen::Vector2d& px, double depth) const {
  const Eigen::Vector2d xn = undistort({(px.x() - cx) / fx, (px.y() - cy) / fy});
  return {xn.x() * depth, xn.y() * depth, depth};
}

bool PinholeCamera::in_image(const Eigen::Vector2d& px, double border) const {
  return px.x() >= border && px.y() >= border && px.x() < width - border && px.y() < height - border;
}

RgbdCameraSettings load_camera_settings(const std::filesystem::path& path) {
  const SettingsFile f = SettingsFile::load(path);
  RgbdCameraSettings s;
  PinholeCamera& c = s.camera;
  c.fx = f.get_double("Camera.fx");
  c.fy = f.get_double("Camera.fy");
  c.cx = f.get_double("Camera.cx");
  c.cy = f.get_double("Camera.cy");
  c.k1 = f.get_double("Camera.k1", 0.0);
  c.k2 = f.get_double("Camera.k2", 0.0);
  c.p1 = f.get_double("Camera.p1", 0.0);
  c.p2 = f.get_double("Camera.p2", 0.0);
  c.k3 = f.get_double("Camera.k3", 0.0);
  c.width = f.get_int("Camera.width", 640);
  c.height = f.get_int("Camera.height", 480);
  s.fps = f.get_double("Camera.fps", 30.0);
  s.bf = f.get_double("Camera.bf", 40.0);
  s.rgb_order = f.get_int("Camera.RGB", 1) != 0;
  s.th_depth = f.get_double("ThDepth", 40.0);
  s.depth_map_factor = f.get_double("DepthMapFactor", 5000.0);
  s.disparity_sigma = f.get_double("DisparitySigma", s.disparity_sigma);
  s.global_ba_disparity_sigma = f.get_double("GlobalBADisparitySigma", s.global_ba_disparity_sigma);
  s.local_ba_disparity_sigma = f.get_double("LocalBADisparitySigma", s.local_ba_disparity_sigma);
  s.max_depth = f.get_double("MaxDepth", s.max_depth);
  s.far_depth = f.get_double("FarDepth", s.far_depth);
  if (c.fx <= 0 || c.fy <= 0) throw_input_error(path, 0, "Camera.fx and Camera.fy must be positive");
  if (c.width <= 0 || c.height <= 0) throw_input_error(path, 0, "Camera.width and Camera.height must be positive");
  if (s.depth_map_factor <= 0) throw_input_error(path, 0, "DepthMapFactor must be positive");
  if (s.fps <= 0) throw_input_error(path, 0, "Camera.fps must be positive");
  const auto require_finite_non_negative = [&](double value, const std::string& key, const std::string& meaning) {
    if (!(value >= 0) || !std::isfinite(value))
      throw_input_error(path, 0, key + " must be a finite number >= 0 (" + meaning + ")");
  };
  require_finite_non_negative(s.disparity_sigma, "DisparitySigma", "pixels; 0 = ORB-SLAM's weighting");
  require_finite_non_negative(s.global_ba_disparity_sigma, "GlobalBADisparitySigma", "pixels; 0 = DisparitySigma");
  require_finite_non_negative(s.local_ba_disparity_sigma, "LocalBADisparitySigma", "pixels; 0 = DisparitySigma");
  require_finite_non_negative(s.max_depth, "MaxDepth", "metres; 0 = no limit");
  require_finite_non_negative(s.far_depth, "FarDepth", "metres; 0 = every reading is a measurement");
  return s;
}

void save_camera_settings(const std::filesystem::path& path, const RgbdCameraSettings& s) {
  std::ofstream out(path);
  const PinholeCamera& c = s.camera;
  out << std::setprecision(10) << "%YAML:1.0\n"
      << "Camera.fx: " << c.fx << "\nCamera.fy: " << c.fy << "\nCamera.cx: " << c.cx << "\nCamera.cy: " << c.cy
      << "\nCamera.k1: " << c.k1 << "\nCamera.k2: " << c.k2 << "\nCamera.p1: " << c.p1 << "\nCamera.p2: " << c.p2
      << "\nCamera.k3: " << c.k3 << "\nCamera.width: " << c.width << "\nCamera.height: " << c.height
      << "\nCamera.fps: " << s.fps << "\nCamera.bf: " << s.bf << "\nCamera.RGB: " << (s.rgb_order ? 1 : 0)
      << "\nThDepth: " << s.th_depth << "\nDepthMapFactor: " << s.depth_map_factor
      << "\nDisparitySigma: " << s.disparity_sigma << "\nGlobalBADisparitySigma: " << s.global_ba_disparity_sigma
      << "\nLocalBADisparitySigma: " << s.local_ba_disparity_sigma
      << "\nMaxDepth: " << s.max_depth
      << "\nFarDepth: " << s.far_depth << "\n";
  if (!out) throw Failure(located(path, 0, "cannot write camera settings"));
}

}  // namespace builtscene
