#pragma once
// Closed-form rigid fit (Horn/Umeyama without scale) used by loop closing: RGB-D depth fixes
// the scale, so a loop correction is an SE3, never a Sim3.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <vector>

namespace builtscene::slam {

/// Rotation R and translation t minimising sum |R*src_i + t - dst_i|^2 (least squares, no scale).
/// Returns nothing when fewer than 3 pairs are given or the points are degenerate (collinear).
std::optional<Eigen::Isometry3d> fit_rigid_transform(const std::vector<Eigen::Vector3d>& src,
                                                     const std::vector<Eigen::Vector3d>& dst);

}  // namespace builtscene::slam
