#pragma once
// The large planes in one depth image (walls, floor, ceiling), for plane landmarks
// (plane_landmark.hpp). A wall a metre away is measured by thousands of depth readings, so
// its plane gives the camera's distance and tilt to it to millimetres and tenths of a degree,
// where the features on a plain wall give nothing.
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace builtscene::slam {

// The plane n.X + d = 0 in camera coordinates; n is a unit vector oriented so that d > 0
// (it points from the plane towards the camera) and d is the camera's distance to the plane.
struct PlaneMeasurement {
  Eigen::Vector3d n_c = Eigen::Vector3d::UnitZ();
  double d_c = 0;
  std::size_t inliers = 0;
};

struct DepthPlaneOptions {
  int max_planes = 4;
  std::size_t min_inliers = 600;  // of the strided points (640 x 480 at stride 4: 19200 at most)
  double inlier_m = 0.02;
  double max_depth_m = 4.0;       // farther readings are too noisy to help
  int stride_px = 4;
  int normal_step_px = 6;         // a point's own surface normal from neighbours this far
  double max_normal_dev_deg = 20; // ... within this of the plane's to count as its inlier
  int iterations = 200;           // RANSAC hypotheses per plane
};

// The least-squares plane through `points` (3 or more): n (unit, turned towards `orient_like`)
// and d with n.X + d = 0 for the points' mean. Shared with the floor fit (floor_plane.hpp).
void fit_plane_least_squares(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& orient_like,
                             Eigen::Vector3d& n, double& d);

// Sequential RANSAC over the strided depth points (metres, CV_32F, 0 = none; undistorted
// pinhole fx, fy, cx, cy): the plane with most inliers, refit by least squares, its inliers
// removed, and again, up to max_planes; largest first. Deterministic.
std::vector<PlaneMeasurement> extract_depth_planes(const cv::Mat& depth_m, double fx, double fy, double cx, double cy,
                                                   const DepthPlaneOptions& opt = {});

}  // namespace builtscene::slam
