#include "slam/icp_with_motion_prior.hpp"

#include <cmath>
#include <vector>

#include <Eigen/Cholesky>

#include "core/so3.hpp"

namespace builtscene::slam {
namespace {

bool valid_depth(float z, const IcpWithPriorOptions& o) {
  return std::isfinite(z) && z >= o.min_depth && z <= o.max_depth;
}

// Point and unit normal (towards the camera) of the current image at (u, v), from the
// neighbours two pixels away; nothing at depth edges or without readings.
bool point_and_normal(const cv::Mat& depth, int u, int v, double fx, double fy, double cx, double cy,
                      const IcpWithPriorOptions& o, Eigen::Vector3d& p, Eigen::Vector3d& n) {
  constexpr int d = 2;
  if (u < d || v < d || u + d >= depth.cols || v + d >= depth.rows) return false;
  auto at = [&](int x, int y, Eigen::Vector3d& q) {
    const float z = depth.at<float>(y, x);
    if (!valid_depth(z, o)) return false;
    q = Eigen::Vector3d((x - cx) / fx * z, (y - cy) / fy * z, z);
    return true;
  };
  Eigen::Vector3d l, r, t, b;
  if (!at(u, v, p) || !at(u - d, v, l) || !at(u + d, v, r) || !at(u, v - d, t) || !at(u, v + d, b)) return false;
  // A depth edge between the neighbours is not a surface.
  const double gap = 0.05 + 0.03 * p.z();
  if (std::abs(l.z() - r.z()) > gap || std::abs(t.z() - b.z()) > gap) return false;
  n = (r - l).cross(b - t);
  const double len = n.norm();
  if (!(len > 1e-12)) return false;
  n /= len;
  if (n.dot(p) > 0) n = -n;
  return true;
}

}  // namespace

std::optional<SE3> icp_with_motion_prior(const cv::Mat& prev_depth, const cv::Mat& cur_depth, double fx, double fy,
                                         double cx, double cy, const SE3& prediction,
                                         const IcpWithPriorOptions& o, Eigen::Matrix<double, 6, 6>* correspondence_information) {
  if (prev_depth.type() != CV_32F || cur_depth.type() != CV_32F || prev_depth.size() != cur_depth.size())
    return std::nullopt;
  std::vector<Eigen::Vector3d> src;
  for (int v = 0; v < prev_depth.rows; v += o.stride) {
    const float* row = prev_depth.ptr<float>(v);
    for (int u = 0; u < prev_depth.cols; u += o.stride)
      if (valid_depth(row[u], o)) src.emplace_back((u - cx) / fx * row[u], (v - cy) / fy * row[u], row[u]);
  }
  if (static_cast<int>(src.size()) < o.min_correspondences) return std::nullopt;

  using Vec6 = Eigen::Matrix<double, 6, 1>;
  using Mat6 = Eigen::Matrix<double, 6, 6>;
  // Increment delta = (translation, rotation) applied on the left: T <- (exp(w), t) * T.
  Mat6 prior_info = Mat6::Zero();
  for (int i = 0; i < 3; ++i) {
    prior_info(i, i) = 1.0 / (o.prior_sigma_m * o.prior_sigma_m);
    prior_info(3 + i, 3 + i) = 1.0 / (o.prior_sigma_rad * o.prior_sigma_rad);
  }
  const SE3 prediction_inv = prediction.inverse();
  const double info = 1.0 / (o.sigma_m * o.sigma_m);
  SE3 T = prediction;
  for (int it = 0; it < o.iterations; ++it) {
    Mat6 H = prior_info;
    // Prior residual: the deviation from the prediction, D = T * prediction^-1 (zero at the start).
    const SE3 D = T * prediction_inv;
    Vec6 e;
    e.head<3>() = D.translation();
    e.tail<3>() = so3_log(D.rotation());
    Vec6 g = prior_info * e;
    int used = 0;
    for (const auto& p : src) {
      const Eigen::Vector3d q = T * p;
      if (q.z() <= 0.1) continue;
      const int u = static_cast<int>(std::lround(fx * q.x() / q.z() + cx));
      const int v = static_cast<int>(std::lround(fy * q.y() / q.z() + cy));
      Eigen::Vector3d c, n;
      if (!point_and_normal(cur_depth, u, v, fx, fy, cx, cy, o, c, n)) continue;
      if (std::abs(c.z() - q.z()) > o.max_gap_m) continue;
      const double r = n.dot(q - c);
      Vec6 J;
      J.head<3>() = n;
      J.tail<3>() = q.cross(n);
      const double w = std::abs(r) <= o.huber_m ? info : info * o.huber_m / std::abs(r);
      H.noalias() += w * J * J.transpose();
      g.noalias() += w * r * J;
      ++used;
    }
    if (used < o.min_correspondences) return std::nullopt;
    if (correspondence_information) *correspondence_information = H - prior_info;
    const Vec6 delta = -H.ldlt().solve(g);
    if (!delta.allFinite()) return std::nullopt;
    T = SE3(so3_exp(delta.tail<3>()), delta.head<3>()) * T;
    if (delta.head<3>().norm() < 1e-6 && delta.tail<3>().norm() < 1e-7) break;
  }
  return T;
}

}  // namespace builtscene::slam
