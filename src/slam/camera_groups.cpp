#include "slam/camera_groups.hpp"

#include <algorithm>
#include <map>
#include <unordered_map>
#include <utility>

namespace builtscene::slam {

DisjointSets camera_groups(const BundleAdjustmentProblem& pb, int min_shared_points, bool by_relative_poses) {
  const std::size_t nc = pb.cameras.size();
  DisjointSets groups(nc);
  auto valid = [&](const BundleAdjustmentProblem::Measurement& m) {
    return m.camera >= 0 && static_cast<std::size_t>(m.camera) < nc && m.point >= 0 &&
           static_cast<std::size_t>(m.point) < pb.points.size();
  };
  if (min_shared_points <= 1) {
    // Any shared point joins: every camera of a point to the first that saw it.
    std::unordered_map<int, int> first_camera;
    for (const auto& m : pb.measurements)
      if (valid(m))
        if (const auto [it, fresh] = first_camera.emplace(m.point, m.camera); !fresh) groups.join(m.camera, it->second);
  } else {
    std::vector<std::vector<int>> cameras_of_point(pb.points.size());
    for (const auto& m : pb.measurements)
      if (valid(m)) cameras_of_point[static_cast<std::size_t>(m.point)].push_back(m.camera);
    std::map<std::pair<int, int>, int> shared;
    for (auto& cams : cameras_of_point) {
      std::sort(cams.begin(), cams.end());
      cams.erase(std::unique(cams.begin(), cams.end()), cams.end());
      for (std::size_t a = 0; a < cams.size(); ++a)
        for (std::size_t b = a + 1; b < cams.size(); ++b) ++shared[{cams[a], cams[b]}];
    }
    for (const auto& [pair, n] : shared)
      if (n >= min_shared_points) groups.join(pair.first, pair.second);
  }
  if (by_relative_poses)
    for (const auto& rp : pb.relative_poses) groups.join(rp.i, rp.j);
  return groups;
}

std::vector<char> held_by_fixed_camera(const BundleAdjustmentProblem& pb, DisjointSets& groups) {
  const std::size_t nc = pb.cameras.size();
  std::vector<char> group_has_fixed(nc, 0), held(nc, 0);
  for (std::size_t c = 0; c < nc; ++c)
    if (pb.cameras[c].fixed) group_has_fixed[static_cast<std::size_t>(groups.find(static_cast<int>(c)))] = 1;
  for (std::size_t c = 0; c < nc; ++c) held[c] = group_has_fixed[static_cast<std::size_t>(groups.find(static_cast<int>(c)))];
  return held;
}

}  // namespace builtscene::slam
