#include "slam/key_frame.hpp"

#include <algorithm>
#include <unordered_map>

#include "slam/map.hpp"
#include "slam/map_point.hpp"

namespace builtscene::slam {

KeyFrame::KeyFrame(long id_, const Frame& frame)
    : id(id_), frame_id(frame.id), timestamp(frame.timestamp), f(frame.f) {
  points.assign(f->size(), nullptr);
  set_pose(frame.T_cw);
}

int KeyFrame::tracked_points(int min_obs) const {
  int n = 0;
  for (const auto& p : points)
    if (p && !p->bad && p->observation_count() >= min_obs) ++n;
  return n;
}

std::vector<std::shared_ptr<MapPoint>> KeyFrame::good_points() const {
  std::vector<std::shared_ptr<MapPoint>> out;
  for (const auto& p : points)
    if (p && !p->bad) out.push_back(p);
  return out;
}

void KeyFrame::sort_connections() {
  ordered_connections.clear();
  std::vector<std::pair<int, KeyFrame*>> v;
  for (const auto& [kf, w] : connections) v.emplace_back(w, kf);
  // Heaviest first; ties by id so the order does not depend on pointer values.
  std::sort(v.begin(), v.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first > b.first : a.second->id < b.second->id;
  });
  for (const auto& [w, kf] : v) ordered_connections.push_back(kf);
}

void KeyFrame::add_connection(KeyFrame* other, int weight) {
  connections[other] = weight;
  sort_connections();
}

void KeyFrame::erase_connection(KeyFrame* other) {
  if (connections.erase(other)) sort_connections();
}

void KeyFrame::update_connections(int min_weight) {
  KeyFrameMap<int> counts;
  for (const auto& p : points) {
    if (!p || p->bad) continue;
    for (const auto& [kf, idx] : p->observations)
      if (kf != this && !kf->bad) ++counts[kf];
  }
  if (counts.empty()) return;
  KeyFrame* best = nullptr;
  int best_w = 0;
  KeyFrameMap<int> kept;
  for (const auto& [kf, w] : counts) {
    if (w > best_w || (w == best_w && best && kf->id < best->id)) {
      best = kf;
      best_w = w;
    }
    if (w >= min_weight) kept[kf] = w;
  }
  if (kept.empty()) kept[best] = best_w;
  for (const auto& [kf, w] : kept) kf->add_connection(this, w);
  // Drop links to keyframes no longer sharing enough points.
  for (const auto& [kf, w] : connections)
    if (!kept.count(kf)) kf->erase_connection(this);
  connections = kept;
  sort_connections();
  if (id != 0) link_to_parent(*best);
}

void KeyFrame::link_to_parent(KeyFrame& p) {
  if (has_parent_link || &p == this) return;
  parent = p.shared_from_this();
  p.children.insert(this);
  has_parent_link = true;
}

std::vector<KeyFrame*> KeyFrame::best_covisibles(std::size_t n) const {
  if (ordered_connections.size() <= n) return ordered_connections;
  return {ordered_connections.begin(), ordered_connections.begin() + static_cast<long>(n)};
}

void KeyFrame::set_bad(Map& map) {
  if (bad || keep) return;
  auto keep_alive = shared_from_this();
  bad = true;
  for (const auto& [kf, w] : connections) kf->erase_connection(this);
  connections.clear();
  ordered_connections.clear();
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (auto p = points[i]) {
      points[i] = nullptr;
      p->erase_observation(this, map);
    }
  }
  // Children join this keyframe's parent; the pose relative to the parent is frozen so frames
  // tracked against this keyframe can still be placed.
  if (parent) {
    for (KeyFrame* c : children) {
      c->parent = parent;
      parent->children.insert(c);
    }
    parent->children.erase(this);
    T_cp = pose() * parent->pose_inverse();
  }
  children.clear();
  map.erase_keyframe(this);
}

void add_depth_links(const std::vector<std::shared_ptr<KeyFrame>>& cams, BundleAdjustmentProblem& pb) {
  std::unordered_map<const KeyFrame*, int> index;
  for (std::size_t c = 0; c < cams.size(); ++c) index[cams[c].get()] = static_cast<int>(c);
  for (std::size_t c = 0; c < cams.size(); ++c) {
    const auto to = cams[c]->depth_link_to.lock();
    if (!to || to->bad) continue;
    const auto it = index.find(to.get());
    if (it == index.end()) continue;
    pb.relative_poses.push_back({static_cast<int>(c), it->second, cams[c]->depth_link_T, cams[c]->depth_link_information});
  }
}

}  // namespace builtscene::slam
