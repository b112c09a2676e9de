#pragma once
// Test-only ATE: rigid (rotation + translation, no scale) alignment of estimated camera
// centres to ground truth by Horn/Umeyama's closed form, then the RMSE of the residuals.
// Kept here, independent of the SLAM code, until src/eval lands on main.
#include <cmath>
#include <map>
#include <vector>

#include <Eigen/Dense>

#include "io/trajectory.hpp"

namespace builtscene::slam::test {

struct AteResult {
  std::size_t matched = 0;
  double rmse = 0, median = 0, max = 0;
};

inline AteResult absolute_trajectory_error(const Trajectory& truth, const Trajectory& estimate,
                                           double max_dt = 0.005) {
  std::map<double, Eigen::Vector3d> gt;
  for (const auto& p : truth) gt[p.timestamp] = p.pose.translation();
  std::vector<Eigen::Vector3d> a, b;
  for (const auto& p : estimate) {
    auto it = gt.lower_bound(p.timestamp - max_dt);
    if (it == gt.end() || std::abs(it->first - p.timestamp) > max_dt) continue;
    a.push_back(p.pose.translation());
    b.push_back(it->second);
  }
  AteResult r;
  r.matched = a.size();
  if (a.size() < 3) return r;
  Eigen::Vector3d ma = Eigen::Vector3d::Zero(), mb = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < a.size(); ++i) {
    ma += a[i];
    mb += b[i];
  }
  ma /= static_cast<double>(a.size());
  mb /= static_cast<double>(b.size());
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < a.size(); ++i) H += (a[i] - ma) * (b[i] - mb).transpose();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  if ((svd.matrixV() * svd.matrixU().transpose()).determinant() < 0) D(2, 2) = -1;
  const Eigen::Matrix3d R = svd.matrixV() * D * svd.matrixU().transpose();
  const Eigen::Vector3d t = mb - R * ma;
  std::vector<double> e;
  double s = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    e.push_back((R * a[i] + t - b[i]).norm());
    s += e.back() * e.back();
  }
  r.rmse = std::sqrt(s / static_cast<double>(e.size()));
  std::sort(e.begin(), e.end());
  r.median = e[e.size() / 2];
  r.max = e.back();
  return r;
}

}  // namespace builtscene::slam::test
