#include "slam/rigid_transform_ransac.hpp"

#include <random>

namespace builtscene::slam {
namespace {

int mark_inliers(const Eigen::Isometry3d& t, const std::vector<Eigen::Vector3d>& src,
                 const std::vector<Eigen::Vector3d>& dst, double max_sq, std::vector<bool>& out) {
  out.assign(src.size(), false);
  int count = 0;
  for (std::size_t i = 0; i < src.size(); ++i) {
    if ((t * src[i] - dst[i]).squaredNorm() < max_sq) {
      out[i] = true;
      ++count;
    }
  }
  return count;
}

}  // namespace

std::optional<RigidRansacResult> ransac_rigid_transform(const std::vector<Eigen::Vector3d>& src,
                                                        const std::vector<Eigen::Vector3d>& dst,
                                                        double inlier_distance, int min_inliers,
                                                        int iterations, std::uint32_t seed) {
  if (src.size() != dst.size() || src.size() < 3) return std::nullopt;
  const double max_sq = inlier_distance * inlier_distance;
  std::mt19937 rng(seed);
  std::uniform_int_distribution<std::size_t> pick(0, src.size() - 1);
  RigidRansacResult best;
  std::vector<bool> mask;
  for (int it = 0; it < iterations; ++it) {
    std::size_t a = pick(rng), b = pick(rng), c = pick(rng);
    if (a == b || b == c || a == c) continue;
    const auto t = fit_rigid_transform({src[a], src[b], src[c]}, {dst[a], dst[b], dst[c]});
    if (!t) continue;
    const int count = mark_inliers(*t, src, dst, max_sq, mask);
    if (count > best.inlier_count) {
      best.inlier_count = count;
      best.transform = *t;
      best.inliers = mask;
    }
  }
  if (best.inlier_count < min_inliers) return std::nullopt;
  // Refit on all inliers: the 3-point sample carries the noise of only three matches.
  std::vector<Eigen::Vector3d> in_src, in_dst;
  for (std::size_t i = 0; i < src.size(); ++i) {
    if (best.inliers[i]) {
      in_src.push_back(src[i]);
      in_dst.push_back(dst[i]);
    }
  }
  if (const auto refit = fit_rigid_transform(in_src, in_dst)) {
    best.transform = *refit;
    best.inlier_count = mark_inliers(best.transform, src, dst, max_sq, best.inliers);
  }
  if (best.inlier_count < min_inliers) return std::nullopt;
  return best;
}

}  // namespace builtscene::slam
