#include "features/bow_vector.hpp"

#include <cmath>

namespace builtscene {

double bow_l1_score(const BowVector& a, const BowVector& b) {
  // |a - b|_1 = |a|_1 + |b|_1 - sum over common words (|x| + |y| - |x - y|); with both
  // vectors normalised only the common words need visiting.
  double norm_a = 0, norm_b = 0;
  for (const auto& [w, x] : a) norm_a += std::abs(x);
  for (const auto& [w, y] : b) norm_b += std::abs(y);
  double common = 0;
  auto ia = a.begin();
  auto ib = b.begin();
  while (ia != a.end() && ib != b.end()) {
    if (ia->first < ib->first) {
      ia = a.lower_bound(ib->first);
    } else if (ib->first < ia->first) {
      ib = b.lower_bound(ia->first);
    } else {
      const double x = ia->second, y = ib->second;
      common += std::abs(x) + std::abs(y) - std::abs(x - y);
      ++ia;
      ++ib;
    }
  }
  const double l1 = norm_a + norm_b - common;
  return 1.0 - 0.5 * l1;
}

}  // namespace builtscene
