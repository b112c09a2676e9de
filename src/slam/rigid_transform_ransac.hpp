#pragma once
// RANSAC over 3D-3D matches for the loop candidate check: minimal 3-point samples through
// fit_rigid_transform, refit on the largest inlier set.
#include <cstdint>
#include <optional>
#include <vector>

#include "slam/rigid_transform.hpp"

namespace builtscene::slam {

/// Result of a RANSAC rigid fit: the transform (src -> dst) and which pairs agree with it.
struct RigidRansacResult {
  Eigen::Isometry3d transform = Eigen::Isometry3d::Identity();
  std::vector<bool> inliers;
  int inlier_count = 0;
};

/// Pairs whose residual |T*src - dst| is below inlier_distance (metres) count as inliers.
/// Returns nothing when no sample reaches min_inliers.
std::optional<RigidRansacResult> ransac_rigid_transform(const std::vector<Eigen::Vector3d>& src,
                                                        const std::vector<Eigen::Vector3d>& dst,
                                                        double inlier_distance, int min_inliers,
                                                        int iterations, std::uint32_t seed);

}  // namespace builtscene::slam
