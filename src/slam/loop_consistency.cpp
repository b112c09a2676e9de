#include "slam/loop_consistency.hpp"

#include <algorithm>

namespace builtscene::slam {

std::vector<long> LoopConsistency::update(const std::vector<Candidate>& candidates) {
  std::vector<Group> next;
  std::vector<long> accepted;
  // A previous group continues into at most one new group, so one chain cannot multiply.
  std::vector<char> continued(groups_.size(), 0);
  one_short_.clear();
  for (const auto& c : candidates) {
    Group g;
    g.members.insert(c.id);
    g.members.insert(c.group.begin(), c.group.end());
    bool consistent_with_any = false, enough = false;
    int best = -1;
    for (std::size_t k = 0; k < groups_.size(); ++k) {
      const auto& prev = groups_[k].members;
      const bool shares = std::any_of(g.members.begin(), g.members.end(), [&](long id) { return prev.count(id) > 0; });
      if (!shares) continue;
      consistent_with_any = true;
      const int consistency = groups_[k].consistency + 1;
      best = std::max(best, consistency);
      if (!continued[k]) {
        next.push_back({g.members, consistency});
        continued[k] = 1;
      }
      if (consistency >= required_ && !enough) {
        accepted.push_back(c.id);
        enough = true;
      }
    }
    if (!consistent_with_any) {
      next.push_back({g.members, 0});
      best = 0;
    }
    if (!enough && best == required_ - 1) one_short_.push_back(c.id);
  }
  groups_ = std::move(next);
  return accepted;
}

}  // namespace builtscene::slam
