#pragma once
// A bag-of-words vocabulary tree (the design of DBoW2, Galvez-Lopez & Tardos 2012, written
// here): hierarchical k-means with k branches and L levels over training descriptors,
// k-means++ seeding, leaves are the words, each word weighted by its inverse document
// frequency idf = log(N / n_i) over the N training images. Works for binary descriptors
// (CV_8U rows, Hamming distance, cluster centre = bitwise majority) and float descriptors
// (CV_32F rows, Euclidean distance, centre = mean); see DescriptorKind.
//
// A vocabulary is immutable after training or loading, so any number of threads may
// transform with it at once.
//
//   BowVocabulary voc = BowVocabulary::train(per_image_descriptors, {.k = 10, .levels = 4});
//   voc.save("orb_k10_L4.bsvoc");
//   BowVector v; FeatureVector fv;
//   voc.transform(descriptors, v, &fv, /*direct_index_depth=*/2);
//   double s = bow_l1_score(v, other);
#include <cstdint>
#include <filesystem>
#include <vector>

#include <opencv2/core.hpp>

#include "features/bow_vector.hpp"
#include "features/descriptor.hpp"

namespace builtscene {

struct BowTrainingOptions {
  int k = 10;                 // branching factor
  int levels = 4;             // depth of the tree (words at depth `levels` at most)
  int max_iterations = 10;    // k-means iterations per node (stops earlier when stable)
  std::uint64_t seed = 1;     // k-means++ seeding; same data and seed -> same vocabulary
};

class BowVocabulary {
 public:
  struct Node {
    std::int32_t parent = -1;  // -1 for the root (node 0)
    std::int32_t depth = 0;    // root 0
    std::vector<std::int32_t> children;
    std::int32_t word = -1;    // word id when this node is a leaf
    double weight = 0;         // idf of the word (leaves only)
  };

  BowVocabulary() = default;

  // Trains on the descriptors of several images (one matrix per image, all of one type and
  // width; images without rows are allowed). Throws InputError when there are no descriptors
  // or the types or widths differ, or when k < 2 or levels < 1.
  static BowVocabulary train(const std::vector<cv::Mat>& images, const BowTrainingOptions& options = {});

  // Binary file (see docs/slam.md "Vocabulary file"); load throws InputError naming the file
  // on a missing, truncated, corrupt (checksum), foreign (magic) or newer-version file.
  void save(const std::filesystem::path& path) const;
  static BowVocabulary load(const std::filesystem::path& path);

  bool empty() const { return words_.empty(); }
  DescriptorKind kind() const { return kind_; }
  int descriptor_cols() const { return cols_; }
  int k() const { return k_; }
  int levels() const { return levels_; }
  std::size_t word_count() const { return words_.size(); }
  std::size_t node_count() const { return nodes_.size(); }
  const Node& node(std::size_t i) const { return nodes_[i]; }
  double word_weight(WordId w) const { return nodes_[static_cast<std::size_t>(words_[w])].weight; }
  // Centre of node i (one row of the descriptor type).
  cv::Mat centre(std::size_t i) const { return centres_.row(static_cast<int>(i)); }

  // The word of one descriptor row, and the node on its path at `depth` (clamped to the
  // word's own depth), for the direct index.
  WordId word_of(const cv::Mat& descriptors, int row, NodeId* node_at_depth = nullptr, int depth = 0) const;

  // TF-IDF vector of an image, L1-normalised; with `features`, the direct index at `depth`
  // (ORB-SLAM uses 2 levels below the root for a 6-level tree; a shallow node gathers more
  // candidates). Throws InputError when the descriptor type or width does not match.
  void transform(const cv::Mat& descriptors, BowVector& bow, FeatureVector* features = nullptr, int depth = 2) const;

 private:
  DescriptorKind kind_ = DescriptorKind::kBinary;
  int cols_ = 0;  // bytes (binary) or floats per row
  int k_ = 0, levels_ = 0;
  std::vector<Node> nodes_;
  cv::Mat centres_;               // one row per node (the root's row is unused, zero)
  std::vector<std::int32_t> words_;  // word id -> node index

  void check_descriptors(const cv::Mat& d, const char* what) const;
  void index_words();
  friend class BowTreeBuilder;
};

}  // namespace builtscene
