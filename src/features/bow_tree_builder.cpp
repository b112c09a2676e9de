// Training of BowVocabulary: hierarchical k-means with k-means++ seeding, then idf weights.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>
#include <set>
#include <string>

#include "core/errors.hpp"
#include "features/bow_vocabulary.hpp"

namespace builtscene {

namespace {

// Distances and cluster centres of one descriptor kind. Distances are squared for floats
// (cheaper and order-preserving); k-means++ uses the squared distance either way.
struct BinarySpace {
  int cols;
  double distance(const std::uint8_t* a, const std::uint8_t* b) const { return hamming(a, b, cols); }
  double seeding_weight(double d) const { return d * d; }
  // Bitwise majority: a bit is set when more than half the members have it.
  void centre(const std::vector<const std::uint8_t*>& members, std::uint8_t* out) const {
    std::vector<int> count(static_cast<std::size_t>(cols) * 8, 0);
    for (const auto* m : members)
      for (int byte = 0; byte < cols; ++byte) {
        const unsigned v = m[byte];
        if (!v) continue;
        for (int bit = 0; bit < 8; ++bit) count[static_cast<std::size_t>(byte * 8 + bit)] += (v >> bit) & 1u;
      }
    const int n = static_cast<int>(members.size());
    for (int byte = 0; byte < cols; ++byte) {
      unsigned v = 0;
      for (int bit = 0; bit < 8; ++bit)
        if (2 * count[static_cast<std::size_t>(byte * 8 + bit)] > n) v |= 1u << bit;
      out[byte] = static_cast<std::uint8_t>(v);
    }
  }
};

struct FloatSpace {
  int cols;
  double distance(const float* a, const float* b) const {
    double s = 0;
    for (int i = 0; i < cols; ++i) {
      const double d = static_cast<double>(a[i]) - static_cast<double>(b[i]);
      s += d * d;
    }
    return s;
  }
  double seeding_weight(double d) const { return d; }
  void centre(const std::vector<const float*>& members, float* out) const {
    std::vector<double> sum(static_cast<std::size_t>(cols), 0.0);
    for (const auto* m : members)
      for (int i = 0; i < cols; ++i) sum[static_cast<std::size_t>(i)] += m[i];
    for (int i = 0; i < cols; ++i) out[i] = static_cast<float>(sum[static_cast<std::size_t>(i)] / static_cast<double>(members.size()));
  }
};

}  // namespace

// Builds the tree top-down; a friend of BowVocabulary so it can fill the private arrays.
class BowTreeBuilder {
 public:
  template <typename Space, typename T>
  static void build(BowVocabulary& voc, const Space& space, const std::vector<const T*>& data,
                    const BowTrainingOptions& opt) {
    std::mt19937_64 rng(opt.seed);
    std::vector<std::vector<T>> centres;  // per node
    voc.nodes_.clear();
    voc.nodes_.push_back({});
    centres.emplace_back(static_cast<std::size_t>(space.cols), T{});
    std::vector<int> all(data.size());
    for (std::size_t i = 0; i < data.size(); ++i) all[i] = static_cast<int>(i);
    split(voc, space, data, opt, rng, centres, 0, 0, all);
    voc.centres_ = cv::Mat(static_cast<int>(centres.size()), space.cols, cv::DataType<T>::type);
    for (std::size_t i = 0; i < centres.size(); ++i)
      std::memcpy(voc.centres_.ptr<T>(static_cast<int>(i)), centres[i].data(), sizeof(T) * static_cast<std::size_t>(space.cols));
    voc.index_words();
  }

 private:
  template <typename Space, typename T>
  static void split(BowVocabulary& voc, const Space& space, const std::vector<const T*>& data,
                    const BowTrainingOptions& opt, std::mt19937_64& rng, std::vector<std::vector<T>>& centres,
                    int node, int depth, const std::vector<int>& members) {
    if (depth >= opt.levels || members.size() <= 1) return;
    const std::size_t cols = static_cast<std::size_t>(space.cols);
    std::vector<std::vector<int>> clusters;
    std::vector<std::vector<T>> cluster_centres;
    if (members.size() <= static_cast<std::size_t>(opt.k)) {
      // Fewer descriptors than branches: each is a cluster of its own (DBoW2 does the same).
      for (int m : members) {
        clusters.push_back({m});
        cluster_centres.emplace_back(data[static_cast<std::size_t>(m)], data[static_cast<std::size_t>(m)] + cols);
      }
    } else {
      kmeans(space, data, opt, rng, members, clusters, cluster_centres);
    }
    if (clusters.size() <= 1) return;  // all identical: no split helps
    std::vector<int> child_ids;
    for (std::size_t c = 0; c < clusters.size(); ++c) {
      BowVocabulary::Node n;
      n.parent = node;
      n.depth = depth + 1;
      child_ids.push_back(static_cast<int>(voc.nodes_.size()));
      voc.nodes_.push_back(n);
      centres.push_back(cluster_centres[c]);
    }
    for (std::size_t c = 0; c < clusters.size(); ++c)
      if (clusters[c].size() > 1) split(voc, space, data, opt, rng, centres, child_ids[c], depth + 1, clusters[c]);
  }

  template <typename Space, typename T>
  static void kmeans(const Space& space, const std::vector<const T*>& data, const BowTrainingOptions& opt,
                     std::mt19937_64& rng, const std::vector<int>& members, std::vector<std::vector<int>>& clusters,
                     std::vector<std::vector<T>>& centres) {
    const std::size_t cols = static_cast<std::size_t>(space.cols);
    const std::size_t n = members.size();
    auto row = [&](std::size_t i) { return data[static_cast<std::size_t>(members[i])]; };
    // k-means++: first centre uniform, then each next one with probability proportional to
    // the (squared) distance to the nearest centre chosen so far.
    centres.clear();
    std::vector<double> nearest(n, std::numeric_limits<double>::infinity());
    std::size_t first = std::uniform_int_distribution<std::size_t>(0, n - 1)(rng);
    centres.emplace_back(row(first), row(first) + cols);
    while (centres.size() < static_cast<std::size_t>(opt.k)) {
      double total = 0;
      for (std::size_t i = 0; i < n; ++i) {
        nearest[i] = std::min(nearest[i], space.seeding_weight(space.distance(row(i), centres.back().data())));
        total += nearest[i];
      }
      if (total <= 0) break;  // fewer distinct descriptors than k
      double pick = std::uniform_real_distribution<double>(0.0, total)(rng);
      std::size_t chosen = n - 1;
      for (std::size_t i = 0; i < n; ++i) {
        pick -= nearest[i];
        if (pick <= 0 && nearest[i] > 0) {
          chosen = i;
          break;
        }
      }
      centres.emplace_back(row(chosen), row(chosen) + cols);
    }
    std::vector<int> assignment(n, -1);
    for (int it = 0; it < std::max(1, opt.max_iterations); ++it) {
      bool changed = false;
      for (std::size_t i = 0; i < n; ++i) {
        double best = std::numeric_limits<double>::infinity();
        int best_c = 0;
        for (std::size_t c = 0; c < centres.size(); ++c) {
          const double d = space.distance(row(i), centres[c].data());
          if (d < best) {
            best = d;
            best_c = static_cast<int>(c);
          }
        }
        if (assignment[i] != best_c) {
          assignment[i] = best_c;
          changed = true;
        }
      }
      if (!changed && it > 0) break;
      std::vector<std::vector<const T*>> groups(centres.size());
      for (std::size_t i = 0; i < n; ++i) groups[static_cast<std::size_t>(assignment[i])].push_back(row(i));
      for (std::size_t c = 0; c < centres.size(); ++c)
        if (!groups[c].empty()) space.centre(groups[c], centres[c].data());
    }
    // Drop clusters that ended empty.
    std::vector<std::vector<int>> groups(centres.size());
    for (std::size_t i = 0; i < n; ++i) groups[static_cast<std::size_t>(assignment[i])].push_back(members[i]);
    std::vector<std::vector<T>> kept_centres;
    clusters.clear();
    for (std::size_t c = 0; c < centres.size(); ++c) {
      if (groups[c].empty()) continue;
      clusters.push_back(std::move(groups[c]));
      kept_centres.push_back(std::move(centres[c]));
    }
    centres = std::move(kept_centres);
  }
};

BowVocabulary BowVocabulary::train(const std::vector<cv::Mat>& images, const BowTrainingOptions& opt) {
  if (opt.k < 2) throw InputError("vocabulary training: --k must be at least 2, got " + std::to_string(opt.k));
  if (opt.levels < 1 || opt.levels > 8)
    throw InputError("vocabulary training: --levels must be in 1..8, got " + std::to_string(opt.levels));
  int type = -1, cols = 0;
  std::size_t total = 0, with_rows = 0;
  for (const auto& m : images) {
    if (m.empty()) continue;
    if (m.type() != CV_8U && m.type() != CV_32F)
      throw InputError("vocabulary training: descriptors must be CV_8U or CV_32F rows, got type " + std::to_string(m.type()));
    if (type < 0) {
      type = m.type();
      cols = m.cols;
    } else if (m.type() != type || m.cols != cols) {
      throw InputError("vocabulary training: images have descriptors of different types or widths");
    }
    total += static_cast<std::size_t>(m.rows);
    ++with_rows;
  }
  if (total == 0) throw InputError("vocabulary training: no descriptors");

  BowVocabulary voc;
  voc.kind_ = type == CV_8U ? DescriptorKind::kBinary : DescriptorKind::kFloat;
  voc.cols_ = cols;
  voc.k_ = opt.k;
  voc.levels_ = opt.levels;
  std::vector<cv::Mat> contiguous;  // keeps row pointers valid
  for (const auto& m : images) contiguous.push_back(m.isContinuous() ? m : m.clone());
  if (voc.kind_ == DescriptorKind::kBinary) {
    std::vector<const std::uint8_t*> data;
    data.reserve(total);
    for (const auto& m : contiguous)
      for (int r = 0; r < m.rows; ++r) data.push_back(m.ptr<std::uint8_t>(r));
    BowTreeBuilder::build(voc, BinarySpace{cols}, data, opt);
  } else {
    std::vector<const float*> data;
    data.reserve(total);
    for (const auto& m : contiguous)
      for (int r = 0; r < m.rows; ++r) data.push_back(m.ptr<float>(r));
    BowTreeBuilder::build(voc, FloatSpace{cols}, data, opt);
  }
  if (voc.words_.empty()) throw InputError("vocabulary training: every descriptor is identical; no words");

  // idf = log(N / n_i): N images with descriptors, n_i of them containing word i.
  std::vector<int> images_with_word(voc.words_.size(), 0);
  for (const auto& m : contiguous) {
    if (m.empty()) continue;
    std::set<WordId> seen;
    for (int r = 0; r < m.rows; ++r) seen.insert(voc.word_of(m, r));
    for (WordId w : seen) ++images_with_word[w];
  }
  for (std::size_t w = 0; w < voc.words_.size(); ++w) {
    const int n_i = images_with_word[w];
    voc.nodes_[static_cast<std::size_t>(voc.words_[w])].weight =
        n_i > 0 ? std::log(static_cast<double>(with_rows) / static_cast<double>(n_i)) : 0.0;
  }
  return voc;
}

}  // namespace builtscene
