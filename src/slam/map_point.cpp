#include "slam/map_point.hpp"

#include <algorithm>
#include <cmath>

#include "slam/key_frame.hpp"
#include "slam/map.hpp"

namespace builtscene::slam {

MapPoint::MapPoint(long id_, const Eigen::Vector3d& p, KeyFrame* ref, long created)
    : id(id_), position(p), reference(ref), created_by_kf(created) {}

bool MapPoint::observed_by(const KeyFrame* kf) const {
  return observations.count(const_cast<KeyFrame*>(kf)) > 0;
}

void MapPoint::add_observation(KeyFrame* kf, int index) { observations[kf] = index; }

void MapPoint::erase_observation(KeyFrame* kf, Map& map) {
  if (observations.erase(kf) == 0) return;
  if (reference == kf) reference = observations.empty() ? nullptr : observations.begin()->first;
  if (observations.size() <= 1) set_bad(map);
}

void MapPoint::set_bad(Map& map) {
  if (bad) return;
  bad = true;
  auto keep_alive = shared_from_this();  // map.erase_point may drop the last owner
  for (auto& [kf, idx] : observations)
    if (kf->points[static_cast<std::size_t>(idx)].get() == this) kf->erase_point(idx);
  observations.clear();
  reference = nullptr;
  map.erase_point(this);
}

void MapPoint::replace_with(const std::shared_ptr<MapPoint>& other, Map& map) {
  if (other.get() == this || bad) return;
  auto keep_alive = shared_from_this();
  auto obs = observations;
  observations.clear();
  bad = true;
  replaced_by = other;
  for (auto& [kf, idx] : obs) {
    if (!other->observed_by(kf)) {
      kf->points[static_cast<std::size_t>(idx)] = other;
      other->add_observation(kf, idx);
    } else {
      kf->erase_point(idx);
    }
  }
  other->visible += visible;
  other->found += found;
  other->update_descriptor();
  map.erase_point(this);
}

void MapPoint::update_descriptor() {
  if (bad || observations.empty()) return;
  std::vector<cv::Mat> d;
  d.reserve(observations.size());
  for (const auto& [kf, idx] : observations) {
    if (kf->bad) continue;
    d.push_back(kf->f->descriptors.row(idx));
  }
  if (d.empty()) return;
  const int best = most_representative_descriptor(d, observations.begin()->first->f->ctx->metric);
  descriptor = d[static_cast<std::size_t>(best)].clone();
}

void MapPoint::update_normal_and_depth() {
  if (bad || observations.empty() || reference == nullptr) return;
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  int count = 0;
  for (const auto& [kf, idx] : observations) {
    const Eigen::Vector3d v = position - kf->camera_center();
    if (v.norm() > 0) {
      n += v.normalized();
      ++count;
    }
  }
  if (count > 0) normal = n / count;
  const auto it = observations.find(reference);
  if (it == observations.end()) return;
  const double dist = (position - reference->camera_center()).norm();
  const auto& pyr = reference->f->ctx->pyramid;
  const int level = reference->f->keys_un[static_cast<std::size_t>(it->second)].octave;
  max_distance = static_cast<float>(dist) * pyr.scale[static_cast<std::size_t>(level)];
  min_distance = max_distance / pyr.scale.back();
}

int MapPoint::predict_level(double distance, const ScalePyramid& pyr) const {
  if (distance <= 0) return pyr.levels() - 1;
  const double ratio = max_distance / distance;
  const int level = static_cast<int>(std::ceil(std::log(ratio) / std::log(static_cast<double>(pyr.scale_factor))));
  return std::clamp(level, 0, pyr.levels() - 1);
}

}  // namespace builtscene::slam
