#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <random>
#include <string>

#include <opencv2/calib3d.hpp>

#include "../common/scratch_dir.hpp"
#include "core/camera.hpp"
#include "core/errors.hpp"

namespace builtscene {
namespace {

PinholeCamera distorted_camera() {
  PinholeCamera c;
  c.fx = 517.3;
  c.fy = 516.5;
  c.cx = 318.6;
  c.cy = 255.3;
  c.k1 = 0.2624;
  c.k2 = -0.9531;
  c.p1 = -0.0054;
  c.p2 = 0.0026;
  c.k3 = 1.1633;  // TUM fr1 calibration
  c.width = 640;
  c.height = 480;
  return c;
}

TEST(PinholeCamera, ProjectionMatchesOpenCv) {
  const PinholeCamera c = distorted_camera();
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.5, 0.5), z(0.5, 6.0);
  std::vector<cv::Point3d> pts;
  for (int i = 0; i < 100; ++i) {
    const double d = z(rng);
    pts.emplace_back(u(rng) * d, u(rng) * d * 0.75, d);
  }
  const cv::Matx33d K(c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1);
  const std::vector<double> dist{c.k1, c.k2, c.p1, c.p2, c.k3};
  std::vector<cv::Point2d> expected;
  cv::projectPoints(pts, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, dist, expected);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Eigen::Vector2d px = c.project({pts[i].x, pts[i].y, pts[i].z});
    EXPECT_NEAR(px.x(), expected[i].x, 1e-6);
    EXPECT_NEAR(px.y(), expected[i].y, 1e-6);
    const Eigen::Vector3d back = c.unproject(px, pts[i].z);
    EXPECT_LT((back - Eigen::Vector3d(pts[i].x, pts[i].y, pts[i].z)).norm(), 1e-6);
  }
}

TEST(PinholeCamera, UndistortPixelMatchesOpenCv) {
  const PinholeCamera c = distorted_camera();
  const cv::Matx33d K(c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1);
  const std::vector<double> dist{c.k1, c.k2, c.p1, c.p2, c.k3};
  std::vector<cv::Point2d> in{{10, 10}, {320, 240}, {600, 450}, {100, 400}}, out;
  cv::undistortPoints(in, out, K, dist, cv::noArray(), K,
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 100, 1e-12));
  for (std::size_t i = 0; i < in.size(); ++i) {
    const Eigen::Vector2d u = c.undistort_pixel({in[i].x, in[i].y});
    EXPECT_NEAR(u.x(), out[i].x, 1e-3);
    EXPECT_NEAR(u.y(), out[i].y, 1e-3);
  }
}

// The files keep their names (the error checks look for them) inside one folder bs_cam_<pid>,
// made once per process (scratch_dir empties it) and removed when the process exits.
const std::filesystem::path& cam_dir() {
  static const std::filesystem::path d = testing::scratch_dir("cam");
  return d;
}

std::filesystem::path write_temp(const std::string& name, const std::string& text) {
  const auto p = cam_dir() / name;
  std::ofstream(p) << text;
  return p;
}

TEST(CameraSettings, ReadsOrbSlamYamlWithOpenCvDirective) {
  const auto p = write_temp("bs_cam_ok.yaml",
                            "%YAML:1.0\nCamera.fx: 500.0\nCamera.fy: 501.0\nCamera.cx: 320\nCamera.cy: 240\n"
                            "Camera.k1: 0.1\nCamera.width: 640\nCamera.height: 480\nCamera.bf: 40.0\n"
                            "DepthMapFactor: 1000.0\nMaxDepth: 4.5\nDisparitySigma: 0.35\nFarDepth: 6.5\n"
                            "GlobalBADisparitySigma: 0.12\nLocalBADisparitySigma: 0.13\n");
  const auto s = load_camera_settings(p);
  EXPECT_DOUBLE_EQ(s.max_depth, 4.5);
  EXPECT_DOUBLE_EQ(s.camera.fx, 500.0);
  EXPECT_DOUBLE_EQ(s.camera.fy, 501.0);
  EXPECT_DOUBLE_EQ(s.camera.k1, 0.1);
  EXPECT_DOUBLE_EQ(s.depth_map_factor, 1000.0);
  EXPECT_DOUBLE_EQ(s.close_depth(), 40.0 * 40.0 / 500.0);
  // Round trip through the writer.
  const auto q = cam_dir() / "bs_cam_rt.yaml";
  save_camera_settings(q, s);
  const auto s2 = load_camera_settings(q);
  EXPECT_DOUBLE_EQ(s2.camera.fy, 501.0);
  EXPECT_DOUBLE_EQ(s2.depth_map_factor, 1000.0);
  EXPECT_DOUBLE_EQ(s2.max_depth, 4.5);
  EXPECT_DOUBLE_EQ(s2.disparity_sigma, 0.35);
  EXPECT_DOUBLE_EQ(s2.far_depth, 6.5);
  EXPECT_DOUBLE_EQ(s2.global_ba_disparity_sigma, 0.12);
  EXPECT_DOUBLE_EQ(s2.local_ba_disparity_sigma, 0.13);
}

// The error of loading `path` names every one of `parts` (file, line, key).
void expect_error_naming(const std::filesystem::path& path, std::initializer_list<const char*> parts) {
  try {
    load_camera_settings(path);
    ADD_FAILURE() << "no error for " << path;
  } catch (const InputError& e) {
    for (const char* part : parts) EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
  }
}

TEST(CameraSettings, BadFilesNameFileAndField) {
  expect_error_naming(write_temp("bs_cam_missing.yaml", "Camera.fx: 500\nCamera.cx: 1\nCamera.cy: 2\n"),
                      {"bs_cam_missing.yaml", "Camera.fy"});
  expect_error_naming(write_temp("bs_cam_text.yaml", "Camera.fx: 500\nCamera.fy: abc\nCamera.cx: 1\nCamera.cy: 2\n"),
                      {":2:", "Camera.fy"});
  expect_error_naming(
      write_temp("bs_cam_sigma.yaml", "Camera.fx: 500\nCamera.fy: 500\nCamera.cx: 1\nCamera.cy: 2\nDisparitySigma: -0.1\n"),
      {"bs_cam_sigma.yaml", "DisparitySigma"});
  expect_error_naming(
      write_temp("bs_cam_basigma.yaml", "Camera.fx: 500\nCamera.fy: 500\nCamera.cx: 1\nCamera.cy: 2\nGlobalBADisparitySigma: -1\n"),
      {"bs_cam_basigma.yaml", "GlobalBADisparitySigma"});
  expect_error_naming(
      write_temp("bs_cam_lbasigma.yaml", "Camera.fx: 500\nCamera.fy: 500\nCamera.cx: 1\nCamera.cy: 2\nLocalBADisparitySigma: -1\n"),
      {"bs_cam_lbasigma.yaml", "LocalBADisparitySigma"});
  expect_error_naming(
      write_temp("bs_cam_maxdepth.yaml", "Camera.fx: 500\nCamera.fy: 500\nCamera.cx: 1\nCamera.cy: 2\nMaxDepth: -1\n"),
      {"bs_cam_maxdepth.yaml", "MaxDepth"});
  expect_error_naming(
      write_temp("bs_cam_fardepth.yaml", "Camera.fx: 500\nCamera.fy: 500\nCamera.cx: 1\nCamera.cy: 2\nFarDepth: -2\n"),
      {"bs_cam_fardepth.yaml", "FarDepth"});
  EXPECT_THROW(load_camera_settings(write_temp("bs_cam_bad.yaml", "Camera.fx: [1, 2\n")), InputError);
  EXPECT_THROW(load_camera_settings("/nonexistent/camera.yaml"), InputError);
}

}  // namespace
}  // namespace builtscene
