#include "eval/umeyama.hpp"

#include <Eigen/SVD>

#include "core/errors.hpp"

namespace builtscene {

Sim3 umeyama_alignment(const std::vector<Eigen::Vector3d>& src, const std::vector<Eigen::Vector3d>& dst,
                       bool with_scale) {
  if (src.size() != dst.size()) throw InputError("alignment: point sets differ in size");
  if (src.size() < 3) throw InputError("alignment: need at least 3 corresponding positions, got " + std::to_string(src.size()));
  const double n = static_cast<double>(src.size());
  Eigen::Vector3d mu_s = Eigen::Vector3d::Zero(), mu_d = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < src.size(); ++i) {
    mu_s += src[i];
    mu_d += dst[i];
  }
  mu_s /= n;
  mu_d /= n;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  double var_s = 0;
  for (std::size_t i = 0; i < src.size(); ++i) {
    const Eigen::Vector3d a = src[i] - mu_s, b = dst[i] - mu_d;
    cov += b * a.transpose();
    var_s += a.squaredNorm();
  }
  cov /= n;
  var_s /= n;
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(cov, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Vector3d sv = svd.singularValues();
  if (sv(1) < 1e-12 * std::max(1.0, sv(0))) throw InputError("alignment: positions are collinear, rotation is undetermined");
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) S(2, 2) = -1;
  const Eigen::Matrix3d R = svd.matrixU() * S * svd.matrixV().transpose();
  const double scale = with_scale ? (sv.asDiagonal() * S).trace() / var_s : 1.0;
  const Eigen::Vector3d t = mu_d - scale * R * mu_s;
  return Sim3(Eigen::Quaterniond(R), t, scale);
}

}  // namespace builtscene
