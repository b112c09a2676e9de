#include "couple/event_tracker.hpp"

#include <iterator>

namespace builtscene::couple {

bool EventTracker::on_event(int64_t step) {
  if (step < complete_) return false;
  if (!beyond_.insert(step).second) return false;
  settle();
  return true;
}

void EventTracker::on_count(int64_t completed, int64_t count) {
  if (completed <= status_k_) return;  // an older report (reordered)
  status_k_ = completed;
  status_c_ = count;
  settle();
}

void EventTracker::settle() {
  if (status_k_ <= complete_) return;
  const auto end = beyond_.lower_bound(status_k_);
  const int64_t have = count_below_ + static_cast<int64_t>(std::distance(beyond_.begin(), end));
  if (have < status_c_) return;  // some event before k is still on its way
  // have > count cannot happen with a producer that reports truthfully; trust the count.
  count_below_ = have;
  beyond_.erase(beyond_.begin(), end);
  complete_ = status_k_;
}

}  // namespace builtscene::couple
