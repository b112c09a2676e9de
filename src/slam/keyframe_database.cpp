#include "slam/keyframe_database.hpp"

#include <algorithm>
#include <unordered_map>
#include <unordered_set>

#include "slam/key_frame.hpp"

namespace builtscene::slam {

KeyFrameDatabase::KeyFrameDatabase(std::shared_ptr<const BowVocabulary> vocabulary, int direct_index_depth)
    : vocabulary_(std::move(vocabulary)), depth_(direct_index_depth) {
  inverted_.resize(vocabulary_->word_count());
}

void KeyFrameDatabase::compute_bow(const cv::Mat& descriptors, BowVector& bow, FeatureVector& features) const {
  vocabulary_->transform(descriptors, bow, &features, depth_);
}

void KeyFrameDatabase::add(const std::shared_ptr<KeyFrame>& kf) {
  purge_bad();
  if (!kf || kf->bad) return;
  if (kf->bow.empty()) compute_bow(kf->f->descriptors, kf->bow, kf->bow_features);
  for (const auto& [w, weight] : kf->bow) inverted_[w].push_back(kf.get());
  keyframes_.push_back(kf);
}

void KeyFrameDatabase::erase(KeyFrame* kf) {
  const auto it = std::find_if(keyframes_.begin(), keyframes_.end(), [&](const auto& k) { return k.get() == kf; });
  if (it == keyframes_.end()) return;
  for (const auto& [w, weight] : kf->bow) {
    auto& list = inverted_[w];
    list.erase(std::remove(list.begin(), list.end(), kf), list.end());
  }
  keyframes_.erase(it);
}

void KeyFrameDatabase::purge_bad() {
  std::vector<KeyFrame*> bad;
  for (const auto& kf : keyframes_)
    if (kf->bad) bad.push_back(kf.get());
  for (KeyFrame* kf : bad) erase(kf);
}

void KeyFrameDatabase::clear() {
  for (auto& list : inverted_) list.clear();
  keyframes_.clear();
}

std::vector<KeyFrameDatabase::Scored> KeyFrameDatabase::sharing_words(const BowVector& bow,
                                                                      const std::vector<const KeyFrame*>& exclude) const {
  std::unordered_map<KeyFrame*, int> common;
  for (const auto& [w, weight] : bow) {
    if (w >= inverted_.size()) continue;
    for (KeyFrame* kf : inverted_[w])
      if (!kf->bad) ++common[kf];
  }
  std::vector<Scored> out;
  for (const auto& [kf, n] : common)
    if (std::find(exclude.begin(), exclude.end(), kf) == exclude.end()) out.push_back({kf, n, 0.0});
  // Independent of pointer values (hash order), so results are reproducible.
  std::sort(out.begin(), out.end(), [](const Scored& a, const Scored& b) { return a.kf->id < b.kf->id; });
  return out;
}

std::vector<KeyFrame*> KeyFrameDatabase::best_groups(const BowVector& bow, std::vector<Scored> shared,
                                                     double min_score) const {
  if (shared.empty()) return {};
  int max_common = 0;
  for (const auto& s : shared) max_common = std::max(max_common, s.common_words);
  const int min_common = static_cast<int>(0.8f * static_cast<float>(max_common));
  std::unordered_map<const KeyFrame*, double> score_of;
  std::vector<Scored> kept;
  for (auto& s : shared) {
    if (s.common_words <= min_common && s.common_words != max_common) continue;
    s.score = bow_l1_score(bow, s.kf->bow);
    if (s.score < min_score) continue;
    score_of[s.kf] = s.score;
    kept.push_back(s);
  }
  if (kept.empty()) return {};
  // A place is seen by a group of covisible keyframes: accumulate over each one's
  // neighbours that also passed, and let the group's best keyframe stand for it.
  struct Group {
    double acc;
    KeyFrame* best;
  };
  std::vector<Group> groups;
  double best_acc = 0;
  for (const auto& s : kept) {
    double acc = s.score, best_score = s.score;
    KeyFrame* best = s.kf;
    for (KeyFrame* n : s.kf->best_covisibles(10)) {
      const auto it = score_of.find(n);
      if (it == score_of.end()) continue;
      acc += it->second;
      if (it->second > best_score) {
        best_score = it->second;
        best = n;
      }
    }
    groups.push_back({acc, best});
    best_acc = std::max(best_acc, acc);
  }
  std::stable_sort(groups.begin(), groups.end(), [](const Group& a, const Group& b) { return a.acc > b.acc; });
  std::vector<KeyFrame*> out;
  std::unordered_set<KeyFrame*> seen;
  for (const auto& g : groups)
    if (g.acc > 0.75 * best_acc && seen.insert(g.best).second) out.push_back(g.best);
  return out;
}

std::vector<KeyFrame*> KeyFrameDatabase::relocalization_candidates(const BowVector& bow) const {
  return best_groups(bow, sharing_words(bow, {}), 0.0);
}

std::vector<KeyFrame*> KeyFrameDatabase::loop_candidates(const KeyFrame& kf, double min_score) const {
  std::vector<const KeyFrame*> exclude{&kf};
  for (const auto& [n, w] : kf.connections) exclude.push_back(n);
  return best_groups(kf.bow, sharing_words(kf.bow, exclude), min_score);
}

}  // namespace builtscene::slam
