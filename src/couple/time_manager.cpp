#include "couple/time_manager.hpp"

#include <algorithm>

#include "core/errors.hpp"

namespace builtscene::couple {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
}

TimeManager::TimeManager(const ScenarioConfig& sc, const std::string& model) {
  const ModelConfig& cfg = sc.model(model);
  for (const auto& sub : cfg.subscribe)
    for (const auto& m : sc.models)
      for (const auto& p : m.publish)
        if (p.channel == sub.channel && m.name != cfg.name)  // own lagged outputs are local
          links_.push_back({&sub, m.name, m.dt, m.lookahead, m.steps(), std::numeric_limits<int64_t>::min(), false,
                            p.initial ? -1 : 0, {}, p.events, EventTracker(p.initial ? -1 : 0)});
}

double TimeManager::Link::bound() const {
  if (events) {
    // Nothing stamped before the first step not known complete can still come.
    if (finished && tracker.complete() >= producer_steps) return kInf;
    return stamp(tracker.complete());
  }
  if (finished && next >= producer_steps) return kInf;
  if (completed == std::numeric_limits<int64_t>::min()) return stamp(next);  // P not heard yet: what has arrived
  // P will send nothing stamped before its next step's stamp; we may still miss one it sent.
  return std::min(finished ? kInf : stamp(completed), stamp(next));
}

const TimeManager::Link* TimeManager::find(const std::string& channel) const {
  for (const auto& l : links_)
    if (l.sub->channel == channel) return &l;
  return nullptr;
}

void TimeManager::on_status(const std::string& model, int64_t completed, bool finished,
                            const std::vector<std::pair<std::string, int64_t>>& event_counts) {
  for (auto& l : links_)
    if (l.producer == model) {
      l.completed = std::max(l.completed, completed);
      l.finished = l.finished || finished;
      if (l.events)
        for (const auto& [channel, count] : event_counts)
          if (channel == l.sub->channel) l.tracker.on_count(completed, count);
    }
}

int64_t TimeManager::events_complete(const std::string& channel) const {
  const Link* l = find(channel);
  if (!l || !l->events) throw InputError("time manager: no event-driven input channel '" + channel + "'");
  return l->tracker.complete();
}

void TimeManager::on_message(const std::string& channel, int64_t step) {
  for (auto& l : links_) {
    if (l.sub->channel != channel) continue;
    if (l.events) {
      l.completed = std::max(l.completed, step + 1);
      l.tracker.on_event(step);
      continue;
    }
    if (step < l.next) continue;
    l.completed = std::max(l.completed, step + 1);  // P publishes a step's outputs when it has computed it
    l.ahead.insert(step);
    while (!l.ahead.empty() && *l.ahead.begin() == l.next) {
      l.ahead.erase(l.ahead.begin());
      ++l.next;
    }
  }
}

double TimeManager::granted() const {
  double g = kInf;
  for (const auto& l : links_) g = std::min(g, l.bound());
  return g;
}

bool TimeManager::may_advance(int64_t n, std::string* holder) const {
  for (const auto& l : links_) {
    const int64_t need = l.sub->expected_step(n);
    if (l.events ? need < l.tracker.complete() && need < 0  // initial values, or every event up to need is here
                 : need < 0 && need < l.next)               // initial values, or the producer's step -1 already here
      continue;
    const double t = l.stamp(need);
    // A relative margin: stamps are computed from different time steps in floating point.
    if (!(l.bound() > t + 1e-9 * l.producer_dt)) {
      if (holder) *holder = l.producer;
      return false;
    }
  }
  return true;
}

double TimeManager::stamp(const std::string& channel, int64_t step) const {
  const Link* l = find(channel);
  if (!l) throw InputError("time manager: no input channel '" + channel + "'");
  return l->stamp(step);
}

}  // namespace builtscene::couple
