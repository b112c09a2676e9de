#include "ogm/ground_frame.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include <Eigen/Eigenvalues>

#include "core/errors.hpp"
#include "core/logging.hpp"
#include "ogm/map_server_io.hpp"

namespace builtscene {

GroundFrame GroundFrame::first_camera(double camera_height) {
  Eigen::Matrix3d R;  // rows: ground axes in camera-0 coordinates
  R << 1, 0, 0,       //
      0, 0, 1,        //
      0, -1, 0;
  return GroundFrame(SE3(R, Eigen::Vector3d(0, 0, camera_height)));
}

Pose2D GroundFrame::to_2d(const SE3& T_wc) const {
  const SE3 T_gc = T_gw_ * T_wc;
  const Eigen::Vector3d forward = T_gc.rotation() * Eigen::Vector3d::UnitZ();
  return {T_gc.translation().x(), T_gc.translation().y(), std::atan2(forward.y(), forward.x())};
}

GroundFrame GroundFrame::estimate(const std::vector<SE3>& T_wc, const std::vector<cv::Mat>& depths,
                                  const PinholeCamera& camera) {
  if (T_wc.empty()) throw InputError("ground frame: no poses to estimate the floor from");
  // A first guess of up from the cameras' mean down axis; it is biased by any mean pitch, so
  // the floor plane found in the depth points decides the final up direction and height.
  Eigen::Vector3d down = Eigen::Vector3d::Zero();
  for (const auto& T : T_wc) down += T.rotation() * Eigen::Vector3d::UnitY();
  if (down.norm() < 1e-6 * static_cast<double>(T_wc.size()))
    throw InputError("ground frame: camera orientations give no consistent up direction; pass --world");
  const Eigen::Vector3d up0 = -down.normalized();
  double lowest_camera = std::numeric_limits<double>::infinity();
  for (const auto& T : T_wc) lowest_camera = std::min(lowest_camera, up0.dot(T.translation()));

  std::vector<Eigen::Vector3d> pts;
  for (std::size_t k = 0; k < depths.size() && k < T_wc.size(); ++k) {
    const cv::Mat& d = depths[k];
    for (int v = 0; v < d.rows; v += 8)
      for (int u = 0; u < d.cols; u += 8) {
        const float z = d.at<float>(v, u);
        if (z > 0.1f && z < 8.0f) pts.push_back(T_wc[k] * camera.unproject({u, v}, z));
      }
  }
  if (pts.size() < 100) throw InputError("ground frame: too few depth readings to find the floor; pass --world");

  // RANSAC over planes whose normal is within 40 degrees of up0, that lie at least 0.2 m
  // below the lowest camera and that have at most 1 % of the points below them; the plane
  // with most inliers (2 cm) is the floor.
  // Hypotheses are drawn from the lowest fifth of the points along up0 (below the cameras),
  // where the floor is; drawn from all points, a floor seen only at the image's bottom edge
  // (a forward-looking robot camera) would almost never be sampled.
  std::vector<std::size_t> low;
  {
    std::vector<double> h;
    for (const auto& p : pts) h.push_back(up0.dot(p));
    std::vector<double> sorted = h;
    const auto q = sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 5);
    std::nth_element(sorted.begin(), q, sorted.end());
    for (std::size_t i = 0; i < pts.size(); ++i)
      if (h[i] <= *q && h[i] < lowest_camera - 0.2) low.push_back(i);
  }
  if (low.size() < 3) throw InputError("ground frame: no depth readings below the cameras; pass --world");
  std::mt19937 rng(12345);
  std::uniform_int_distribution<std::size_t> pick_low(0, low.size() - 1);
  auto pick = [&](std::mt19937& g) { return low[pick_low(g)]; };
  Eigen::Vector3d best_n = up0;
  double best_d = 0;
  std::size_t best_count = 0;
  for (int it = 0; it < 300; ++it) {
    const Eigen::Vector3d a = pts[pick(rng)], b = pts[pick(rng)], c = pts[pick(rng)];
    Eigen::Vector3d n = (b - a).cross(c - a);
    if (n.norm() < 1e-9) continue;
    n.normalize();
    if (n.dot(up0) < 0) n = -n;
    if (n.dot(up0) < std::cos(40.0 * std::numbers::pi / 180.0)) continue;
    const double d = n.dot(a);  // plane: n.p = d
    if (d > lowest_camera - 0.2) continue;
    // The floor has (almost) nothing below it: this rejects planes that cut obliquely
    // through walls and furniture, however many points they happen to graze.
    std::size_t count = 0, below = 0;
    for (const auto& p : pts) {
      const double e = n.dot(p) - d;
      if (std::abs(e) < 0.02) ++count;
      else if (e < -0.05) ++below;
    }
    if (below > pts.size() / 100) continue;
    if (count > best_count) {
      best_count = count;
      best_n = n;
      best_d = d;
    }
  }
  spdlog::debug("ground frame: {} points, floor plane n=({:.3f},{:.3f},{:.3f}) d={:.3f} with {} inliers", pts.size(), best_n.x(), best_n.y(), best_n.z(), best_d, best_count);
  if (best_count < 50) throw InputError("ground frame: no floor plane found in the depth images; pass --world");
  // Least-squares refinement on the inliers.
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  std::vector<Eigen::Vector3d> inliers;
  for (const auto& p : pts)
    if (std::abs(best_n.dot(p) - best_d) < 0.02) inliers.push_back(p);
  for (const auto& p : inliers) centroid += p;
  centroid /= static_cast<double>(inliers.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : inliers) cov += (p - centroid) * (p - centroid).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  Eigen::Vector3d up = eig.eigenvectors().col(0);
  if (up.dot(up0) < 0) up = -up;
  const double floor = up.dot(centroid);

  // Ground x: the world's own x axis made horizontal, so that a map of a z-up world (or of a
  // first-camera world, where this gives the source's x <- camera x, y <- camera z) overlays
  // that world's maps cell for cell; the world's z axis if x is nearly vertical.
  Eigen::Vector3d fwd = Eigen::Vector3d::UnitX() - up * up.x();
  if (fwd.norm() < 0.3) fwd = Eigen::Vector3d::UnitZ() - up * up.z();
  const Eigen::Vector3d gx = fwd.normalized();
  const Eigen::Vector3d gy = up.cross(gx);
  Eigen::Matrix3d R;
  R.row(0) = gx.transpose();
  R.row(1) = gy.transpose();
  R.row(2) = up.transpose();
  return GroundFrame(SE3(R, Eigen::Vector3d(0, 0, -floor)));
}

bool parse_ground_frame(const std::string& name, double camera_height, GroundFrame& out) {
  if (name == "zup") {
    out = GroundFrame::z_up();
    return true;
  }
  if (name == "camera") {
    out = GroundFrame::first_camera(camera_height);
    return true;
  }
  if (name == "auto") return false;
  // An occupancy grid's YAML: its ground frame, so regions and poses are on that grid.
  if (name.size() > 5 && name.ends_with(".yaml")) {
    const auto T_gw = read_ground_frame(name);
    if (!T_gw) throw InputError(located(name, 0, "field 'ground_frame_T_gw' missing (written by slam --ogm-out and ogm build)"));
    out = GroundFrame(*T_gw);
    return true;
  }
  throw InputError("--world: unknown world frame '" + name + "' (expected zup, camera, auto or a grid's .yaml)");
}

}  // namespace builtscene
