#pragma once
// Completeness of an event-driven channel as a consumer sees it. A producer publishes an
// event only on the steps that have one, so a missing step number says nothing; instead
// its status reports, with the steps it has completed (k), how many events it has
// published stamped before k (c, its initial publication at step -1 included). When the
// consumer holds c distinct events stamped before k, it has every event up to step k - 1:
// `complete()` becomes k. Events may arrive out of order, duplicated or late (lossy UDP,
// re-sends); a status may arrive before the events it counts, so the newest status is kept
// and re-checked on every arrival. Used by the time manager, the wrapper and the recorder.
#include <cstdint>
#include <set>

namespace builtscene::couple {

class EventTracker {
 public:
  // `first`: the first step an event can carry (-1 with an initial publication, else 0).
  explicit EventTracker(int64_t first = 0) : complete_(first) {}

  // An event stamped `step` arrived; false for one already counted (a duplicate).
  bool on_event(int64_t step);
  // The producer completed `completed` steps and had published `count` events before them.
  void on_count(int64_t completed, int64_t count);
  // Every event stamped before this step has arrived.
  int64_t complete() const { return complete_; }

 private:
  void settle();
  int64_t complete_;
  int64_t count_below_ = 0;   // events stamped before complete_
  std::set<int64_t> beyond_;  // distinct events at or after complete_
  int64_t status_k_ = INT64_MIN, status_c_ = 0;  // the newest count report
};

}  // namespace builtscene::couple
