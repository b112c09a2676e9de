#pragma once
// Which cameras of a bundle-adjustment problem hang together, and which groups a fixed camera
// holds. A group of free cameras joined to no fixed one can move as a block: plane terms hold
// such cameras in place (plane_landmark.hpp), and local BA keeps DisparitySigma when a window has
// one (local_ba_disparity.hpp).
#include <vector>

#include "core/disjoint_sets.hpp"
#include "slam/local_bundle_adjuster.hpp"

namespace builtscene::slam {

// Cameras joined where a pair of them shares at least `min_shared_points` points (1 or less: any
// point), and, with `by_relative_poses`, by the problem's relative-pose terms.
DisjointSets camera_groups(const BundleAdjustmentProblem& problem, int min_shared_points, bool by_relative_poses = false);

// Per camera of the problem: whether its group holds a fixed camera.
std::vector<char> held_by_fixed_camera(const BundleAdjustmentProblem& problem, DisjointSets& groups);

}  // namespace builtscene::slam
