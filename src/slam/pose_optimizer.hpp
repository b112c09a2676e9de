#pragma once
// Motion-only bundle adjustment: the camera pose that best explains 3D-2D (and, with depth,
// 3D-stereo) matches. Ceres, Levenberg-Marquardt, Huber loss (delta = sqrt of the chi-square
// threshold), four rounds of ten iterations after each of which every match is re-classified
// inlier or outlier by the chi-square test at 95 %, as ORB-SLAM does; the robust loss is
// dropped for the last two rounds, when the outliers are out.
#include <optional>
#include <vector>

#include "core/se3.hpp"
#include "slam/observation.hpp"

namespace builtscene::slam {

class Frame;

// A Gaussian prior on the pose with a full information matrix: residual
// sqrt_information * [log(R R0^T); t - R R0^T t0], the left perturbation of T_cw relative to
// T_cw0 (rotation first). Directions the information leaves at zero are not held.
struct PosePrior {
  SE3 T_cw;
  Eigen::Matrix<double, 6, 6> sqrt_information;
};

struct PoseOptimizerOptions {
  int rounds = 4;
  int iterations = 10;
  int min_inliers = 10;  // fewer inliers stop the rounds early
  // A prior on the pose (the motion model's prediction), as a 6-D term with these standard
  // deviations: it holds the directions the matches leave weak (a slide and a turn towards
  // far points look alike) and hardly moves the others.
  std::optional<SE3> prior_T_cw;
  double prior_sigma_m = 0.01, prior_sigma_rad = 0.005;
  // Further priors, added to the problem with the one above (the depth alignment to the last
  // keyframe: TrackingOptions::depth_prior_weight).
  std::vector<PosePrior> priors;
};

struct PoseOptimizationResult {
  SE3 T_cw;
  std::vector<bool> inlier;
  int inliers = 0;
  bool ok = false;  // enough matches to optimize at all
};

PoseOptimizationResult optimize_pose(const SE3& T_cw_initial, const std::vector<Eigen::Vector3d>& points_w,
                                     const std::vector<Observation>& observations, const Intrinsics& K,
                                     const PoseOptimizerOptions& options = {});

// Optimizes frame.T_cw against its matched map points and sets frame.outlier; returns the
// number of inliers. The caller holds the map lock (it reads map point positions).
int optimize_frame_pose(Frame& frame, const PoseOptimizerOptions& options = {});

Intrinsics intrinsics_of(const struct FrameContext& ctx);
// The same with global / local bundle adjustment's disparity weight
// (RgbdCameraSettings::global_ba_disparity_sigma, local_ba_disparity_sigma).
Intrinsics global_ba_intrinsics_of(const struct FrameContext& ctx);
Intrinsics local_ba_intrinsics_of(const struct FrameContext& ctx);

}  // namespace builtscene::slam
