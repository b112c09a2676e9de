#include "markers/tag_pose.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/Eigenvalues>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

namespace builtscene {

std::array<Eigen::Vector3d, 4> tag_corners(double s) {
  const double h = s / 2;
  // libapriltag's order: bottom-left, bottom-right, top-right, top-left of the upright tag.
  return {Eigen::Vector3d(-h, -h, 0), Eigen::Vector3d(h, -h, 0), Eigen::Vector3d(h, h, 0), Eigen::Vector3d(-h, h, 0)};
}

std::optional<TagPose> estimate_tag_pose(const TagDetection& det, double tag_size, const PinholeCamera& cam,
                                         const cv::Mat& depth) {
  // IPPE_SQUARE wants the object points in this order: (-h, h), (h, h), (h, -h), (-h, -h).
  const double h = tag_size / 2;
  const std::vector<cv::Point3d> object{{-h, h, 0}, {h, h, 0}, {h, -h, 0}, {-h, -h, 0}};
  const int order[4] = {3, 2, 1, 0};  // detector corner index for each object point
  std::vector<cv::Point2d> image;
  for (int k : order) {
    const Eigen::Vector2d u = cam.undistort_pixel(det.corners[static_cast<std::size_t>(k)]);
    image.emplace_back(u.x(), u.y());
  }
  const cv::Matx33d K(cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1);
  cv::Vec3d rvec, tvec;
  if (!cv::solvePnP(object, image, K, cv::noArray(), rvec, tvec, false, cv::SOLVEPNP_IPPE_SQUARE)) return std::nullopt;
  cv::Matx33d Rcv;
  cv::Rodrigues(rvec, Rcv);
  Eigen::Matrix3d R;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) R(r, c) = Rcv(r, c);
  Eigen::Vector3d t(tvec[0], tvec[1], tvec[2]);
  if (t.z() <= 0) return std::nullopt;

  TagPose p;
  p.id = det.id;
  // Reprojection error of the PnP pose.
  double sq = 0;
  for (std::size_t i = 0; i < 4; ++i) {
    const Eigen::Vector3d pc = R * Eigen::Vector3d(object[i].x, object[i].y, 0) + t;
    const Eigen::Vector2d proj(cam.fx * pc.x() / pc.z() + cam.cx, cam.fy * pc.y() / pc.z() + cam.cy);
    sq += (proj - Eigen::Vector2d(image[i].x, image[i].y)).squaredNorm();
  }
  p.reprojection_rms_px = std::sqrt(sq / 4);

  if (!depth.empty() && depth.type() == CV_32F) {
    // The depth pixels of the tag (its quad shrunk by 20 % so that edge pixels, which may see
    // the background, do not count) give the tag's plane: its normal replaces the corners'
    // (poorly conditioned) tilt, and the ray through the detected centre meets it at the
    // tag's centre. The in-plane rotation stays the corners'.
    std::vector<cv::Point> quad;
    for (const auto& c : det.corners) {
      const Eigen::Vector2d q = det.center + 0.8 * (c - det.center);
      quad.emplace_back(static_cast<int>(std::lround(q.x())), static_cast<int>(std::lround(q.y())));
    }
    const cv::Rect box = cv::boundingRect(quad) & cv::Rect(0, 0, depth.cols, depth.rows);
    std::vector<Eigen::Vector3d> pts;
    for (int v = box.y; v < box.y + box.height; ++v)
      for (int u = box.x; u < box.x + box.width; ++u) {
        if (cv::pointPolygonTest(quad, cv::Point2f(static_cast<float>(u), static_cast<float>(v)), false) < 0) continue;
        const float z = depth.at<float>(v, u);
        if (z > 0.0f && std::isfinite(z)) pts.push_back(cam.unproject({u, v}, z));
      }
    if (pts.size() >= 30) {
      Eigen::Vector3d c = Eigen::Vector3d::Zero();
      for (const auto& q : pts) c += q;
      c /= static_cast<double>(pts.size());
      Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
      for (const auto& q : pts) cov += (q - c) * (q - c).transpose();
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov / static_cast<double>(pts.size()));
      Eigen::Vector3d n = eig.eigenvectors().col(0);
      if (n.dot(-c) < 0) n = -n;  // the face looks at the camera
      const double rms = std::sqrt(std::max(0.0, eig.eigenvalues()(0)));
      const Eigen::Vector2d uc = cam.undistort_pixel(det.center);
      const Eigen::Vector3d ray((uc.x() - cam.cx) / cam.fx, (uc.y() - cam.cy) / cam.fy, 1.0);
      const double denom = n.dot(ray);
      // Accept a plane that is flat to within the sensor's noise and agrees with the corners'
      // tilt to 30 degrees; else the depth sees something other than the tag.
      if (rms < 0.01 + 0.005 * c.z() * c.z() && std::abs(denom) > 1e-3 && n.dot(R.col(2)) > std::cos(30.0 * std::numbers::pi / 180.0)) {
        const Eigen::Vector3d x = (R.col(0) - R.col(0).dot(n) * n).normalized();
        R.col(2) = n;
        R.col(0) = x;
        R.col(1) = n.cross(x);
        t = ray * (n.dot(c) / denom);
        p.depth_refined = true;
      }
    }
  }
  p.T_cg = SE3(R, t);
  p.distance = t.norm();
  const Eigen::Vector3d to_camera = -t.normalized();
  p.viewing_angle_deg = std::acos(std::clamp(R.col(2).dot(to_camera), -1.0, 1.0)) * 180.0 / std::numbers::pi;
  return p;
}

}  // namespace builtscene
