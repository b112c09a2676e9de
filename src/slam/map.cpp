#include "slam/map.hpp"

#include <algorithm>

namespace builtscene::slam {

void Map::add_keyframe(const std::shared_ptr<KeyFrame>& kf) { keyframes_[kf.get()] = kf; }
void Map::add_point(const std::shared_ptr<MapPoint>& p) { points_[p.get()] = p; }
void Map::erase_keyframe(KeyFrame* kf) { keyframes_.erase(kf); }
void Map::erase_point(MapPoint* p) { points_.erase(p); }

std::shared_ptr<KeyFrame> Map::keyframe(KeyFrame* kf) const {
  const auto it = keyframes_.find(kf);
  return it == keyframes_.end() ? nullptr : it->second;
}

std::vector<std::shared_ptr<KeyFrame>> Map::keyframes() const {
  std::vector<std::shared_ptr<KeyFrame>> out;
  out.reserve(keyframes_.size());
  for (const auto& [k, v] : keyframes_) out.push_back(v);
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a->id < b->id; });
  return out;
}

std::vector<std::shared_ptr<MapPoint>> Map::points() const {
  std::vector<std::shared_ptr<MapPoint>> out;
  out.reserve(points_.size());
  for (const auto& [k, v] : points_) out.push_back(v);
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a->id < b->id; });
  return out;
}

void Map::clear() {
  // Break the keyframe -> point -> keyframe raw links before dropping ownership.
  for (auto& [k, kf] : keyframes_) {
    kf->points.clear();
    kf->connections.clear();
    kf->ordered_connections.clear();
    kf->children.clear();
    kf->loop_edges.clear();
    kf->parent.reset();
    kf->planes.clear();
  }
  planes_.clear();
  for (auto& [k, p] : points_) {
    p->observations.clear();
    p->replaced_by.reset();
  }
  keyframes_.clear();
  points_.clear();
}

}  // namespace builtscene::slam
