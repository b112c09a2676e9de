#include "slam/bow_matcher.hpp"

#include "slam/key_frame.hpp"
#include "slam/map_point.hpp"
#include "slam/matcher.hpp"

namespace builtscene::slam {

std::vector<std::shared_ptr<MapPoint>> search_by_bow(const KeyFrame& kf, const FrameFeatures& frame,
                                                     const FeatureVector& frame_features, int* count, float ratio) {
  const auto& metric = frame.ctx->metric;
  std::vector<std::shared_ptr<MapPoint>> matches(frame.size());
  std::vector<float> best_for_kp(frame.size(), metric.infinity());
  std::vector<int> kf_index(frame.size(), -1);
  RotationConsistency rot;
  int n = 0;
  auto kf_it = kf.bow_features.begin();
  auto f_it = frame_features.begin();
  // Merge the two node-ordered maps: only nodes present in both hold candidate pairs.
  while (kf_it != kf.bow_features.end() && f_it != frame_features.end()) {
    if (kf_it->first < f_it->first) {
      kf_it = kf.bow_features.lower_bound(f_it->first);
      continue;
    }
    if (f_it->first < kf_it->first) {
      f_it = frame_features.lower_bound(kf_it->first);
      continue;
    }
    for (int i : kf_it->second) {
      const auto& p = kf.points[static_cast<std::size_t>(i)];
      if (!p || p->bad) continue;
      float best = metric.infinity(), second = metric.infinity();
      int best_j = -1;
      for (int j : f_it->second) {
        const float d = metric.distance(kf.f->descriptors, i, frame.descriptors, j);
        if (d < best) {
          second = best;
          best = d;
          best_j = j;
        } else if (d < second) {
          second = d;
        }
      }
      if (best_j < 0 || best > metric.strict || best > ratio * second) continue;
      const auto js = static_cast<std::size_t>(best_j);
      // One map point per keypoint: keep the closer descriptor.
      if (matches[js]) {
        if (best >= best_for_kp[js]) continue;
        --n;
      }
      matches[js] = p;
      best_for_kp[js] = best;
      kf_index[js] = i;
      ++n;
    }
    ++kf_it;
    ++f_it;
  }
  for (std::size_t j = 0; j < matches.size(); ++j) {
    if (!matches[j]) continue;
    rot.add(kf.f->keys_un[static_cast<std::size_t>(kf_index[j])].angle, frame.keys_un[j].angle, static_cast<int>(j));
  }
  for (int j : rot.inconsistent()) {
    if (!matches[static_cast<std::size_t>(j)]) continue;
    matches[static_cast<std::size_t>(j)] = nullptr;
    --n;
  }
  if (count) *count = n;
  return matches;
}

}  // namespace builtscene::slam
