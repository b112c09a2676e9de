#include "features/descriptor_roc.hpp"

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"

namespace builtscene {

RocPoint fpr_at_tpr(std::vector<double> positive, std::vector<double> negative, double tpr) {
  if (positive.empty() || negative.empty()) throw InputError("ROC: needs matching and non-matching pairs");
  if (!(tpr > 0.0 && tpr <= 1.0)) throw InputError("ROC: true positive rate must be in (0, 1]");
  std::sort(positive.begin(), positive.end());
  std::sort(negative.begin(), negative.end());
  // k positives must be accepted; the k-th smallest distance is the threshold. The 1e-9
  // keeps 0.95 * 100 from becoming 95.00000000000001 -> 96.
  const auto n = positive.size();
  const auto k = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(tpr * static_cast<double>(n) - 1e-9)));
  RocPoint r;
  r.threshold = positive[k - 1];
  // Ties at the threshold are accepted too, for both kinds of pairs.
  const auto pos_accepted = static_cast<std::size_t>(std::upper_bound(positive.begin(), positive.end(), r.threshold) - positive.begin());
  const auto neg_accepted = static_cast<std::size_t>(std::upper_bound(negative.begin(), negative.end(), r.threshold) - negative.begin());
  r.tpr = static_cast<double>(pos_accepted) / static_cast<double>(n);
  r.fpr = static_cast<double>(neg_accepted) / static_cast<double>(negative.size());
  return r;
}

std::vector<RocPoint> roc_curve(const std::vector<double>& positive, const std::vector<double>& negative, int points) {
  if (points < 1) throw InputError("ROC: at least one point");
  std::vector<RocPoint> out;
  for (int i = 1; i <= points; ++i) out.push_back(fpr_at_tpr(positive, negative, static_cast<double>(i) / points));
  return out;
}

}  // namespace builtscene
