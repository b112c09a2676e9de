#include "features/bow_vocabulary.hpp"

#include <cmath>
#include <limits>
#include <string>

#include "core/errors.hpp"

namespace builtscene {

void BowVocabulary::check_descriptors(const cv::Mat& d, const char* what) const {
  const int expected_type = kind_ == DescriptorKind::kBinary ? CV_8U : CV_32F;
  if (d.type() != expected_type || d.cols != cols_)
    throw InputError(std::string(what) + ": descriptors of type " + std::to_string(d.type()) + " width " +
                     std::to_string(d.cols) + " do not match the vocabulary (type " + std::to_string(expected_type) +
                     " width " + std::to_string(cols_) + ")");
}

void BowVocabulary::index_words() {
  words_.clear();
  for (auto& n : nodes_) n.children.clear();
  for (std::size_t i = 1; i < nodes_.size(); ++i) nodes_[static_cast<std::size_t>(nodes_[i].parent)].children.push_back(static_cast<std::int32_t>(i));
  for (std::size_t i = 0; i < nodes_.size(); ++i) {
    auto& n = nodes_[i];
    n.depth = i == 0 ? 0 : nodes_[static_cast<std::size_t>(n.parent)].depth + 1;
    if (n.children.empty() && i != 0) {
      n.word = static_cast<std::int32_t>(words_.size());
      words_.push_back(static_cast<std::int32_t>(i));
    } else {
      n.word = -1;
    }
  }
}

WordId BowVocabulary::word_of(const cv::Mat& descriptors, int row, NodeId* node_at_depth, int depth) const {
  std::int32_t current = 0;
  NodeId at_depth = 0;
  const bool binary = kind_ == DescriptorKind::kBinary;
  while (!nodes_[static_cast<std::size_t>(current)].children.empty()) {
    const auto& children = nodes_[static_cast<std::size_t>(current)].children;
    double best = std::numeric_limits<double>::infinity();
    std::int32_t best_child = children.front();
    for (std::int32_t c : children) {
      const double d = binary ? static_cast<double>(hamming(descriptors.ptr<std::uint8_t>(row), centres_.ptr<std::uint8_t>(c), cols_))
                              : static_cast<double>(l2_distance(descriptors.ptr<float>(row), centres_.ptr<float>(c), cols_));
      if (d < best) {
        best = d;
        best_child = c;
      }
    }
    current = best_child;
    if (nodes_[static_cast<std::size_t>(current)].depth <= depth) at_depth = static_cast<NodeId>(current);
  }
  if (node_at_depth) *node_at_depth = at_depth;
  return static_cast<WordId>(nodes_[static_cast<std::size_t>(current)].word);
}

void BowVocabulary::transform(const cv::Mat& descriptors, BowVector& bow, FeatureVector* features, int depth) const {
  bow.clear();
  if (features) features->clear();
  if (descriptors.empty() || empty()) return;
  check_descriptors(descriptors, "bag-of-words transform");
  for (int r = 0; r < descriptors.rows; ++r) {
    NodeId node = 0;
    const WordId w = word_of(descriptors, r, &node, depth);
    const double weight = word_weight(w);
    // A word seen in every training image carries no information (idf 0); DBoW2 leaves it
    // out of the vector but keeps the feature in the direct index.
    if (weight > 0) bow[w] += weight;
    if (features) (*features)[node].push_back(r);
  }
  double sum = 0;
  for (const auto& [w, x] : bow) sum += std::abs(x);
  if (sum > 0)
    for (auto& [w, x] : bow) x /= sum;
}

}  // namespace builtscene
