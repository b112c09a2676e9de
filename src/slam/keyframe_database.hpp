#pragma once
// Place recognition over the keyframes of a map (ORB-SLAM2's KeyFrameDatabase, written here):
// an inverted index word -> keyframes whose bag of words holds the word, and the two queries
// built on it, relocalization candidates for a lost frame and loop candidates for a new
// keyframe. Both keep only keyframes sharing at least 0.8 of the best count of common
// words, score them with the L1 score, accumulate scores over each one's 10 best
// covisible keyframes, and return the best keyframe of every group scoring above 0.75 of the
// best group.
//
// Locking: guarded by the Map's mutex, like the keyframes it indexes (the caller holds
// Map::mutex() for every call). Keyframes that turn bad are skipped by the queries and
// dropped from the index at the next add() or purge_bad(); until then the database keeps
// them alive.
#include <memory>
#include <vector>

#include "features/bow_vocabulary.hpp"

namespace builtscene::slam {

class KeyFrame;

class KeyFrameDatabase {
 public:
  // `direct_index_depth`: the vocabulary depth whose nodes group features for BoW matching.
  explicit KeyFrameDatabase(std::shared_ptr<const BowVocabulary> vocabulary, int direct_index_depth = 2);

  const BowVocabulary& vocabulary() const { return *vocabulary_; }
  int direct_index_depth() const { return depth_; }

  // Bag of words and direct index of a descriptor matrix.
  void compute_bow(const cv::Mat& descriptors, BowVector& bow, FeatureVector& features) const;

  // Computes kf->bow (when empty) and indexes the keyframe. Bad keyframes are ignored.
  void add(const std::shared_ptr<KeyFrame>& kf);
  void erase(KeyFrame* kf);
  void purge_bad();
  void clear();
  std::size_t size() const { return keyframes_.size(); }

  // Keyframes that may show the place a lost frame sees, best group first.
  std::vector<KeyFrame*> relocalization_candidates(const BowVector& bow) const;

  // Keyframes not connected to `kf` (not kf, not its covisible keyframes) that score at
  // least `min_score` against it, best group first (ORB-SLAM passes the lowest score of kf
  // against its own covisible keyframes).
  std::vector<KeyFrame*> loop_candidates(const KeyFrame& kf, double min_score) const;

 private:
  struct Scored {
    KeyFrame* kf;
    int common_words;
    double score;
  };
  // Keyframes sharing words with `bow` (excluding `exclude`), with their common word counts.
  std::vector<Scored> sharing_words(const BowVector& bow, const std::vector<const KeyFrame*>& exclude) const;
  std::vector<KeyFrame*> best_groups(const BowVector& bow, std::vector<Scored> shared, double min_score) const;

  std::shared_ptr<const BowVocabulary> vocabulary_;
  int depth_;
  std::vector<std::vector<KeyFrame*>> inverted_;         // word -> keyframes
  std::vector<std::shared_ptr<KeyFrame>> keyframes_;  // the indexed keyframes (keeps them valid)
};

}  // namespace builtscene::slam
