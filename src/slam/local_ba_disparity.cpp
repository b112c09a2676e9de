#include "slam/local_ba_disparity.hpp"

#include <algorithm>
#include <map>
#include <utility>
#include <vector>

#include "core/disjoint_sets.hpp"
#include "slam/disparity_noise.hpp"

namespace builtscene::slam {

bool free_cameras_held_by_fixed(const BundleAdjustmentProblem& pb, int min_shared_points) {
  const std::size_t nc = pb.cameras.size();
  std::vector<std::vector<int>> cameras_of_point(pb.points.size());
  for (const auto& m : pb.measurements)
    if (m.point >= 0 && static_cast<std::size_t>(m.point) < cameras_of_point.size() && m.camera >= 0 &&
        static_cast<std::size_t>(m.camera) < nc)
      cameras_of_point[static_cast<std::size_t>(m.point)].push_back(m.camera);
  std::map<std::pair<int, int>, int> shared;
  for (auto& cams : cameras_of_point) {
    std::sort(cams.begin(), cams.end());
    cams.erase(std::unique(cams.begin(), cams.end()), cams.end());
    for (std::size_t a = 0; a < cams.size(); ++a)
      for (std::size_t b = a + 1; b < cams.size(); ++b) ++shared[{cams[a], cams[b]}];
  }
  DisjointSets groups(nc);
  for (const auto& [pair, n] : shared)
    if (n >= min_shared_points) groups.join(pair.first, pair.second);
  auto group_of = [&](std::size_t c) { return static_cast<std::size_t>(groups.find(static_cast<int>(c))); };
  std::vector<char> group_has_fixed(nc, 0);
  bool any_fixed = false;
  for (std::size_t c = 0; c < nc; ++c)
    if (pb.cameras[c].fixed) group_has_fixed[group_of(c)] = 1, any_fixed = true;
  if (!any_fixed) return false;
  for (std::size_t c = 0; c < nc; ++c)
    if (!pb.cameras[c].fixed && !group_has_fixed[group_of(c)]) return false;
  return true;
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
