#pragma once
// ROC of a descriptor distance on labelled pairs: a pair is declared matching when its
// distance is at most a threshold. FPR95, the standard patch-verification number (Brown et
// al.; the source's Figure 3.5), is the false positive rate at the smallest threshold that
// accepts 95 % of the matching pairs.
#include <vector>

namespace builtscene {

struct RocPoint {
  double threshold = 0.0;
  double tpr = 0.0;
  double fpr = 0.0;
};

// The smallest threshold t with at least `tpr` of `positive` distances <= t, and the
// fraction of `negative` distances <= t there. Throws InputError for empty inputs or a tpr
// outside (0, 1].
RocPoint fpr_at_tpr(std::vector<double> positive, std::vector<double> negative, double tpr = 0.95);

// The curve at tpr = 1/points ... 1 (points >= 1).
std::vector<RocPoint> roc_curve(const std::vector<double>& positive, const std::vector<double>& negative, int points = 100);

}  // namespace builtscene
