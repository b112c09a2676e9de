#include "slam/bridge_links.hpp"

#include <cmath>
#include <unordered_map>

namespace builtscene::slam {

int add_bridge_links(const std::vector<std::shared_ptr<KeyFrame>>& cams, const BridgeLinkOptions& options,
                     BundleAdjustmentProblem& pb) {
  if (!(options.sigma_m > 0.0) || !(options.sigma_deg > 0.0)) return 0;
  std::unordered_map<const KeyFrame*, int> index;
  for (std::size_t c = 0; c < cams.size(); ++c) index[cams[c].get()] = static_cast<int>(c);
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Zero();
  const double sigma_rad = options.sigma_deg * M_PI / 180.0;
  information.diagonal() << Eigen::Vector3d::Constant(1.0 / (options.sigma_m * options.sigma_m)),
      Eigen::Vector3d::Constant(1.0 / (sigma_rad * sigma_rad));
  int added = 0;
  for (std::size_t c = 0; c < cams.size(); ++c) {
    const KeyFrame* k = cams[c].get();
    bool bridged = false;
    // The tree ends at the root (a loaded map with a cycle is rejected by the map reader).
    for (const KeyFrame* a = k; a->parent;) {
      bridged = bridged || a->parent_by_odometry;
      a = a->parent.get();
      const auto it = index.find(a);
      if (it == index.end()) continue;
      if (bridged) {
        pb.relative_poses.push_back({static_cast<int>(c), it->second, k->pose() * a->pose_inverse(), information});
        ++added;
      }
      break;
    }
  }
  return added;
}

}  // namespace builtscene::slam
