#include "slam/local_ba_disparity.hpp"

#include <algorithm>

#include "slam/camera_groups.hpp"
#include "slam/disparity_noise.hpp"

namespace builtscene::slam {

bool free_cameras_held_by_fixed(const BundleAdjustmentProblem& pb, int min_shared_points) {
  DisjointSets groups = camera_groups(pb, min_shared_points);
  const auto held = held_by_fixed_camera(pb, groups);
  bool any_fixed = false;
  for (std::size_t c = 0; c < pb.cameras.size(); ++c) {
    if (pb.cameras[c].fixed) any_fixed = true;
    else if (!held[c]) return false;
  }
  return any_fixed;
}

LocalBADisparityChoice choose_local_ba_disparity_sigma(const BundleAdjustmentProblem& pb,
                                                       const LocalBADisparityOptions& o) {
  LocalBADisparityChoice c;
  c.sigma = pb.K.disparity_sigma;
  if (!o.adaptive || !(pb.K.disparity_sigma > 0)) return c;
  c.held = free_cameras_held_by_fixed(pb, o.min_shared_points);
  if (!c.held) return c;
  c.measured = estimate_disparity_noise(pb, 100, 2).sigma;
  if (c.measured > 0) {
    const double hi = pb.K.disparity_sigma, lo = std::min(o.min_sigma, hi);
    c.sigma = std::clamp(o.noise_factor * c.measured, lo, hi);
  }
  return c;
}

}  // namespace builtscene::slam
