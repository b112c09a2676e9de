#pragma once
// The bag-of-words representation of one image (DBoW2's BowVector and FeatureVector, written
// here): word id -> weight, L1-normalised, and the direct index node id -> the feature rows
// that fell under that vocabulary node (the node at a fixed tree depth), which restricts
// descriptor matching between two images to features that share a node.
#include <cstdint>
#include <map>
#include <vector>

namespace builtscene {

using WordId = std::uint32_t;
using NodeId = std::uint32_t;

// Word -> weight (TF-IDF, L1-normalised after transform). Ordered so that two vectors can be
// compared in one merge pass.
using BowVector = std::map<WordId, double>;

// Node at the direct-index depth -> indices of the descriptor rows under it (ascending).
using FeatureVector = std::map<NodeId, std::vector<int>>;

// DBoW2's L1 score of two L1-normalised vectors: 1 - 0.5 * |a - b|_1, in [0, 1]
// (1 = same distribution of words, 0 = no word in common).
double bow_l1_score(const BowVector& a, const BowVector& b);

}  // namespace builtscene
