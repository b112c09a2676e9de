#pragma once
// The disparity sigma a local bundle adjustment weighs and judges depth readings with.
// DisparitySigma (0.2 px) was chosen for tracking, where map points are held fixed; a sensor
// whose readings are better than that is trusted as much as they show they deserve:
//   sigma = clamp(noise_factor x the window's measured noise, min_sigma, DisparitySigma)
// where the noise is estimate_disparity_noise over the readings of points read twice or more
// in the window (at least 100 of them; otherwise DisparitySigma stays). But only where the
// window is held: a tighter weight lets a keyframe that shares few points with the rest slide
// as a block along its view to meet its own points' readings (a generated office's bare
// corner turn, docs/slam.md, "Local bundle adjustment at the noise its window shows").
// Cameras are joined when a pair of them shares at least `min_shared_points` points; if a free
// camera's group holds no fixed camera, the window keeps DisparitySigma.
// A camera file's LocalBADisparitySigma (a fixed sigma) turns this off.
#include "slam/local_bundle_adjuster.hpp"

namespace builtscene::slam {

// Off by default: on the generated corridor it lowers two of three seeds' error (5.65 -> 4.80,
// 4.11 -> 3.77 cm) but raises the generated offices' and the real kitchen's a little (docs/slam.md).
struct LocalBADisparityOptions {
  bool adaptive = false;
  double noise_factor = 1.6;
  double min_sigma = 0.1;       // pixels
  int min_shared_points = 30;
};

// Whether every free camera is joined to a fixed one through pairs of cameras that share at
// least `min_shared_points` points (a problem without fixed cameras: false).
bool free_cameras_held_by_fixed(const BundleAdjustmentProblem& problem, int min_shared_points);

struct LocalBADisparityChoice {
  double sigma = 0;      // pixels: what the problem's K.disparity_sigma should be
  double measured = 0;   // the window's measured noise (0: too few readings or not measured)
  bool held = true;      // free_cameras_held_by_fixed
};

// For a problem whose K.disparity_sigma is DisparitySigma (> 0; ORB-SLAM's form, 0, stays 0).
LocalBADisparityChoice choose_local_ba_disparity_sigma(const BundleAdjustmentProblem& problem,
                                                       const LocalBADisparityOptions& options);

}  // namespace builtscene::slam
