#include "slam/rigid_transform.hpp"

#include <Eigen/SVD>

namespace builtscene::slam {

std::optional<Eigen::Isometry3d> fit_rigid_transform(const std::vector<Eigen::Vector3d>& src,
                                                     const std::vector<Eigen::Vector3d>& dst) {
  if (src.size() != dst.size() || src.size() < 3) return std::nullopt;
  const double n = static_cast<double>(src.size());
  Eigen::Vector3d mean_src = Eigen::Vector3d::Zero();
  Eigen::Vector3d mean_dst = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < src.size(); ++i) {
    mean_src += src[i];
    mean_dst += dst[i];
  }
  mean_src /= n;
  mean_dst /= n;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < src.size(); ++i) cov += (dst[i] - mean_dst) * (src[i] - mean_src).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(cov, Eigen::ComputeFullU | Eigen::ComputeFullV);
  // Collinear points leave the rotation about their line undetermined: two singular values vanish.
  const Eigen::Vector3d sv = svd.singularValues();
  if (sv(0) <= 0.0 || sv(1) <= 1e-12 * sv(0)) return std::nullopt;
  Eigen::Matrix3d s = Eigen::Matrix3d::Identity();
  // Reflection guard (Umeyama 1991): force det(R) = +1.
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0.0) s(2, 2) = -1.0;
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = svd.matrixU() * s * svd.matrixV().transpose();
  t.translation() = mean_dst - t.linear() * mean_src;
  return t;
}

}  // namespace builtscene::slam
