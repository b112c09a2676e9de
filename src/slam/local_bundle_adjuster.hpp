#pragma once
// Bundle adjustment over a window of keyframes (local BA): the poses of the local keyframes
// and the positions of the points they see are refined together, keyframes that only observe
// those points stay fixed and anchor the gauge. Ceres with the Schur complement, Huber loss;
// five iterations, then observations failing the chi-square test (or behind the camera) are
// dropped and ten more iterations run without the robust loss, as ORB-SLAM does.
//
// The problem is plain data so it can be filled under the map lock, solved without it, and
// written back under it (see LocalMapping), and tested on constructed configurations.
#include <atomic>
#include <vector>

#include "core/se3.hpp"
#include "slam/depth_planes.hpp"
#include "slam/observation.hpp"
#include "slam/planar_motion.hpp"

namespace builtscene::slam {

struct BundleAdjustmentProblem {
  struct Camera {
    SE3 T_cw;
    bool fixed = false;
  };
  struct Measurement {
    int camera = 0;
    int point = 0;
    Observation o;
  };
  Intrinsics K;
  std::vector<Camera> cameras;
  std::vector<Eigen::Vector3d> points;
  std::vector<Measurement> measurements;
  // Measured relative poses T_ij = T_iw * T_jw^-1 between two cameras with their information
  // (6 x 6, left increment (t, w) of T_ij): the keyframes' depth links.
  struct RelativePose {
    int i = 0, j = 0;
    SE3 T_ij;
    Eigen::Matrix<double, 6, 6> information;
  };
  std::vector<RelativePose> relative_poses;
  // A ground robot's planar motion (planar_motion.hpp): a term on every free camera.
  PlanarMotion planar;
  // Plane landmarks (plane_landmark.hpp): planes n.X + d = 0 in the world, refined with the
  // poses, and the planes the cameras' depth measured (camera coordinates), each held with
  // standard deviations plane_sigma_rad on the normal and plane_sigma_m on the distance.
  struct Plane {
    Eigen::Vector3d n = Eigen::Vector3d::UnitZ();
    double d = 0;
  };
  struct PlaneObservation {
    int camera = 0;
    int plane = 0;
    PlaneMeasurement m;
  };
  std::vector<Plane> planes;
  std::vector<PlaneObservation> plane_measurements;
  double plane_sigma_rad = 0.005, plane_sigma_m = 0.01;
  // Cameras held near their starting pose: where nothing else fixes a direction the plane
  // terms leave free. A group of `group` cameras joined by shared points is held as a whole:
  // each camera with standard deviations sqrt(group) * hold_sigma_m on the block translation
  // and sqrt(group) * hold_sigma_rad on the rotation, so the group's common motion has
  // hold_sigma_m and hold_sigma_rad whatever its size (a large group is shaped by its points,
  // not by the hold).
  struct Held {
    int camera = 0;
    int group = 1;
    bool operator==(const Held&) const = default;
  };
  std::vector<Held> held_in_place;
  double hold_sigma_m = 0.05, hold_sigma_rad = 0.02;
};

struct BundleAdjustmentOptions {
  int first_iterations = 5;
  int second_iterations = 10;
};

struct BundleAdjustmentResult {
  std::vector<SE3> poses;                 // per camera (fixed ones unchanged)
  std::vector<Eigen::Vector3d> points;
  std::vector<BundleAdjustmentProblem::Plane> planes;
  std::vector<bool> measurement_inlier;   // per measurement, after the final iterations
  double initial_rms_px = 0;              // RMS reprojection error (pixels, all measurements)
  double final_rms_px = 0;                // RMS over the inliers at the end
  bool aborted = false;
  bool solved = false;
};

// `abort` (optional) stops the solver between iterations when set, keeping the best state.
BundleAdjustmentResult solve_bundle_adjustment(const BundleAdjustmentProblem& problem,
                                               const BundleAdjustmentOptions& options = {},
                                               const std::atomic<bool>* abort = nullptr);

}  // namespace builtscene::slam
