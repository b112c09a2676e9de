#include "slam/loop_fusion.hpp"

#include <unordered_set>

#include "slam/key_frame.hpp"
#include "slam/map.hpp"
#include "slam/map_point.hpp"

namespace builtscene::slam {

int fuse_loop_matches(KeyFrame& kf, const std::vector<std::shared_ptr<MapPoint>>& loop_points, Map& map) {
  int fused = 0;
  const std::size_t n = std::min(loop_points.size(), kf.points.size());
  for (std::size_t i = 0; i < n; ++i) {
    const auto& loop = loop_points[i];
    if (!loop || loop->bad) continue;
    auto existing = kf.points[i];
    if (existing == loop) continue;
    if (existing && !existing->bad) {
      // The loop side is the older, better-anchored copy: it survives.
      existing->replace_with(loop, map);
      ++fused;
    } else if (!loop->observed_by(&kf)) {
      loop->add_observation(&kf, static_cast<int>(i));
      kf.add_point(static_cast<int>(i), loop);
      loop->update_descriptor();
      ++fused;
    }
  }
  return fused;
}

std::vector<std::shared_ptr<MapPoint>> neighbourhood_points(const KeyFrame& keyframe) {
  std::vector<const KeyFrame*> kfs{&keyframe};
  for (const KeyFrame* k : keyframe.ordered_connections) kfs.push_back(k);
  std::unordered_set<const MapPoint*> seen;
  std::vector<std::shared_ptr<MapPoint>> out;
  for (const KeyFrame* k : kfs) {
    if (k->bad) continue;
    for (const auto& p : k->points)
      if (p && !p->bad && seen.insert(p.get()).second) out.push_back(p);
  }
  return out;
}

}  // namespace builtscene::slam
