#pragma once
// Disjoint sets (union-find with path halving) over the indices 0..n-1: which pose-graph nodes
// or bundle-adjustment cameras a chain of edges joins.
#include <cstddef>
#include <vector>

namespace builtscene {

class DisjointSets {
 public:
  explicit DisjointSets(std::size_t n) : parent_(n) {
    for (std::size_t i = 0; i < n; ++i) parent_[i] = static_cast<int>(i);
  }
  // The representative of i's set.
  int find(int i) {
    while (at(i) != i) i = at(i) = at(at(i));
    return i;
  }
  void join(int a, int b) { at(find(a)) = find(b); }

 private:
  int& at(int i) { return parent_[static_cast<std::size_t>(i)]; }
  std::vector<int> parent_;
};

}  // namespace builtscene
