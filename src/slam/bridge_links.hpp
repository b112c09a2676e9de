#pragma once
// Bridge links: relative-pose terms in global bundle adjustment across stretches the
// depth-odometry bridge carried.
//
// Where features fail (a featureless turn, a plain wall), tracking carries the pose by
// depth odometry and the keyframes made there hold few or no map points. Global bundle
// adjustment leaves such keyframes out (nothing measures them), so nothing in the problem
// ties the keyframes before the stretch to those after it: each side is held only by its
// own points and can slide along directions those points do not fix (a corridor's straight
// along its own axis). A bridge link holds the relative pose, as it is when the problem is
// built (after the pose graph), between a camera and its nearest spanning-tree ancestor in
// the problem whenever the tree path between them passes an edge the bridge made.
// docs/slam.md, "Bridge links in global bundle adjustment".

#include <memory>
#include <vector>

#include "slam/key_frame.hpp"
#include "slam/local_bundle_adjuster.hpp"

namespace builtscene::slam {

struct BridgeLinkOptions {
  double sigma_m = 0.02;    // standard deviation of each translation component; <= 0: no links
  double sigma_deg = 0.5;   // ... of each rotation component
};

// For every camera c of `cams` (the problem's cameras, index = camera index in `pb`): walk up
// the spanning tree to the first ancestor that is also in `cams`; when a keyframe on the way
// (c itself included, the ancestor excluded) has `parent_by_odometry`, add the term
// T_ca = T_cw * T_aw^-1 with the options' information. Returns the number of links added.
// The caller holds the map lock.
int add_bridge_links(const std::vector<std::shared_ptr<KeyFrame>>& cams, const BridgeLinkOptions& options,
                     BundleAdjustmentProblem& pb);

}  // namespace builtscene::slam
