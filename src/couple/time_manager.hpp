#pragma once
// Conservative time management like an HLA runtime infrastructure's, computed inside each
// model's wrapper from what it hears (no central process): a model is granted time G
// when no message stamped earlier than G can still reach it. A message of producer step
// s on a subscription has the time stamp
//     (s + lag) * dt_producer + lookahead_producer
// (the lag and the producer's declared lookahead are the link's lookahead). From each
// producer P the model knows P's completed steps k (its status) and which steps it has
// received, so
//     G = min over inputs of min(stamp(k), stamp(first step not yet received)),
// infinite without inputs. A step may run only when G exceeds the stamp of every input
// it needs. For an event-driven channel the first step not yet received is replaced by
// the first step not known complete (EventTracker: the producer's status counts its
// events), since a step may carry no message at all. Zero-lookahead cycles are broken by lags with initial data, which the
// scenario check already demands. The granted time is published on the status channel.
#include <cstdint>
#include <limits>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "couple/event_tracker.hpp"
#include "couple/model_config.hpp"

namespace builtscene::couple {

class TimeManager {
 public:
  TimeManager(const ScenarioConfig& scenario, const std::string& model);

  // A producer reported `completed` steps (or finished: no more messages at all) and, per
  // event-driven channel, how many events it had published before them.
  void on_status(const std::string& model, int64_t completed, bool finished,
                 const std::vector<std::pair<std::string, int64_t>>& event_counts = {});
  // A message stamped with producer step `step` arrived on `channel`.
  void on_message(const std::string& channel, int64_t step);

  // Every message stamped earlier than this has arrived; +inf when nothing can come.
  double granted() const;
  // Whether step n may run: granted() exceeds the stamp of every input it needs.
  // On false, `holder` names the producer the grant waits for.
  bool may_advance(int64_t n, std::string* holder = nullptr) const;
  // An event-driven input: every event stamped before this producer step has arrived.
  int64_t events_complete(const std::string& channel) const;
  // The time stamp of producer step `step` on `channel` (for conformance checks).
  double stamp(const std::string& channel, int64_t step) const;

 private:
  struct Link {
    const Subscription* sub;
    std::string producer;
    double producer_dt;
    double lookahead;
    int64_t producer_steps;
    int64_t completed = std::numeric_limits<int64_t>::min();  // unknown until its first status
    bool finished = false;
    int64_t next;               // first producer step not yet received
    std::set<int64_t> ahead;    // received beyond `next`
    bool events = false;        // event-driven channel: `tracker` instead of next/ahead
    EventTracker tracker;
    double stamp(int64_t s) const { return static_cast<double>(s + sub->lag) * producer_dt + lookahead; }
    double bound() const;
  };
  const Link* find(const std::string& channel) const;
  std::vector<Link> links_;
};

}  // namespace builtscene::couple
