#include "couple/message_wrapper.hpp"

#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <limits>
#include <map>
#include <optional>
#include <set>

#include "core/errors.hpp"
#include "core/logging.hpp"
#include "couple/lcm_codec.hpp"
#include "couple/time_manager.hpp"

namespace builtscene::couple {
namespace {

using Clock = std::chrono::steady_clock;
using nlohmann::json;
using Waits = std::vector<std::pair<std::string, int64_t>>;  // channel (or a reason in parentheses), step

// A blocked model repeats an unchanged status at growing intervals, up to this one: a
// hundred blocked or finished models each reporting every 20 ms flooded the mediator and
// the consumers that must decode every status (issue 11's 100-building stall).
constexpr int kFirstRepeatMs = 20;
constexpr int kMaxRepeatMs = 320;
// A producer re-sends the same step to the same consumer at growing intervals, up to this
// one: the copies it sent may still be queued at a busy consumer.
constexpr int kMaxResendGapMs = 640;
// An event consumer that still waits for a step this long after first asking for it, with
// our counts covering it, lost an event (or our status): re-send. Longer than a round
// trip, shorter than its first repeated report.
constexpr int kEventWaitMs = 15;

json merged(const LcmCodec& codec, const json& values, int64_t step) {
  json v = codec.zero();
  for (const auto& [k, val] : values.items()) v[k] = val;
  v[kStepField] = step;
  return v;
}

}  // namespace

struct MessageWrapper::Impl {
  struct Input {
    const Subscription* sub;
    LcmCodec codec;
    std::map<int64_t, Bytes> buffer;  // producer step -> message
    std::optional<Bytes> initial;     // the subscription's own values for steps < 0
    bool producer_initial = false;    // the producer publishes step -1 at start
    bool self = false;                // our own output channel
    bool events = false;              // event-driven: hold the newest event up to the step
  };
  struct Consumer {
    std::string model;
    const ModelConfig* config;
    const Subscription* sub;
    int64_t need;  // oldest of our steps it still needs
    bool done = false;
    // Event-driven output: the consumer waits to know that this step is complete; our
    // status goes out as soon as we have completed it (the consumer cannot tell a lost
    // event from a step without one, and the periodic status would make it wait).
    int64_t awaits = std::numeric_limits<int64_t>::max();
    bool heard = false;  // it has reported at least once (it runs)
    Clock::time_point last_heard{};
    // Re-sending: the step last re-sent to it, when, and the gap before the same again.
    int64_t resent_step = std::numeric_limits<int64_t>::min();
    Clock::time_point resent_at{};
    int resend_gap_ms = 0;
    // Event-driven output: the step it was first seen waiting for although our status had
    // covered it, and when (see on_status).
    int64_t event_wait_step = std::numeric_limits<int64_t>::min();
    Clock::time_point event_wait_since{};
  };
  struct Output {
    const Publication* pub;
    LcmCodec codec;
    std::map<int64_t, Bytes> retained;
    std::vector<Consumer> consumers;  // other models reading this channel
    int64_t last = std::numeric_limits<int64_t>::min();
    int64_t published_before = std::numeric_limits<int64_t>::min();  // resume: steps up to here are out already
    int64_t events = 0;  // event-driven: events published so far (stamped before n)
  };

  const ScenarioConfig& sc;
  const ModelConfig& cfg;
  Transport& tr;
  std::unique_ptr<ModelFunction> fn;
  WrapperOptions opt;
  std::vector<Input> inputs;
  std::vector<Output> outputs;
  int64_t n = 0;
  int64_t total = 0;
  bool was_stopped = false;
  std::vector<std::vector<const Bytes*>> args;
  std::vector<Bytes> results;
  ModelStatus status;
  Clock::time_point last_status{};
  std::string self_channel_note;
  TimeManager time;
  Waits reported_wait;  // in our last status
  std::string reported_signature;  // state, step and waits of our last status
  int repeat_ms = kFirstRepeatMs;  // while blocked: repeat an unchanged status after this long
  bool status_wanted = false;  // a consumer of an event channel waits: tell it our counts

  Impl(const ScenarioConfig& s, const std::string& model, Transport& t, std::unique_ptr<ModelFunction> f,
       WrapperOptions o)
      : sc(s), cfg(s.model(model)), tr(t), fn(std::move(f)), opt(std::move(o)), time(s, model) {
    total = cfg.steps();
    status.model = cfg.name;
    status.steps = total;
    for (const auto& p : cfg.publish) {
      Output out{&p, LcmCodec(sc.types, p.type), {}, {}, std::numeric_limits<int64_t>::min(), std::numeric_limits<int64_t>::min(), 0};
      for (const auto& m : sc.models) {
        if (m.name == cfg.name) continue;
        for (const auto& sub : m.subscribe)
          if (sub.channel == p.channel) {
            // An event consumer holds the newest event at or before its step, so until it
            // reports it needs every event from the first: the initial one at step -1 too,
            // which a consumer that subscribed after it went out can only get re-sent (the
            // initial event was trimmed before the slowest consumer's first report, and
            // that consumer then waited for it for ever: 14 runs in 25 of the event test).
            const int64_t first = p.events ? (p.initial ? -1 : 0) : sub.expected_step(0) - (sub.history - 1);
            out.consumers.push_back({m.name, &m, &sub, first});
          }
      }
      if (opt.recorder) out.consumers.push_back({kRecorderName, nullptr, nullptr, p.initial ? -1 : 0});
      if (opt.resume) {
        const Bytes last = tr.last_stored(p.channel);
        if (!last.empty()) out.published_before = out.codec.read_int64(last.data(), last.size(), kStepField);
      }
      outputs.push_back(std::move(out));
    }
    for (const auto& sub : cfg.subscribe) {
      Input in{&sub, LcmCodec(sc.types, sub.type), {}, {}, false, false};
      if (sub.initial) in.initial = in.codec.encode(merged(in.codec, *sub.initial, -1));
      for (const auto& m : sc.models)
        for (const auto& p : m.publish)
          if (p.channel == sub.channel) {
            in.producer_initial = p.initial.has_value();
            in.self = m.name == cfg.name;
            in.events = p.events;
          }
      inputs.push_back(std::move(in));
    }
    for (std::size_t i = 0; i < inputs.size(); ++i) {
      if (inputs[i].self) continue;  // our own outputs go straight into the buffer
      auto handler = [this, i](const std::string&, const uint8_t* d, std::size_t size) { on_input(i, d, size); };
      if (opt.resume && tr.keeps_history())
        tr.subscribe_from_start(inputs[i].sub->channel, handler);
      else
        tr.subscribe(inputs[i].sub->channel, handler);
    }
    // Statuses of our producers (time grants) and consumers (flow control, re-sends) only.
    std::set<std::string> peers;
    for (const auto& out : outputs)
      for (const auto& c : out.consumers) peers.insert(c.model);
    for (const auto& sub : cfg.subscribe)
      for (const auto& m : sc.models)
        for (const auto& p : m.publish)
          if (p.channel == sub.channel && m.name != cfg.name) peers.insert(m.name);
    for (const auto& peer : peers)
      tr.subscribe(status_channel(peer), [this](const std::string&, const uint8_t* d, std::size_t size) { on_status(d, size); });
    args.resize(inputs.size());
    results.resize(outputs.size());
  }

  void on_input(std::size_t i, const uint8_t* d, std::size_t size) {
    auto& in = inputs[i];
    int64_t step;
    try {
      step = in.codec.read_int64(d, size, kStepField);
    } catch (const InputError& e) {
      spdlog::warn("{}: dropped a message on '{}': {}", cfg.name, in.sub->channel, e.what());
      return;
    }
    if (in.events) {
      // Every event before the complete step is here already: this is a re-sent copy.
      if (step < time.events_complete(in.sub->channel)) return;
      time.on_message(in.sub->channel, step);
      in.buffer.try_emplace(step, d, d + size);
      return;
    }
    time.on_message(in.sub->channel, step);
    if (step < oldest_needed(in, n)) return;  // a late duplicate
    in.buffer.try_emplace(step, d, d + size);
  }

  void on_status(const uint8_t* d, std::size_t size) {
    ModelStatus s;
    try {
      s = decode_status(sc.types, d, size);
    } catch (const InputError&) {
      return;
    }
    time.on_status(s.model, s.step, s.state == ModelState::kDone, s.events);
    for (auto& out : outputs) {
      for (auto& c : out.consumers) {
        if (c.model != s.model) continue;
        c.heard = true;
        c.last_heard = Clock::now();
        if (s.state == ModelState::kDone) c.done = true;
        for (const auto& [ch, step] : s.needs)
          if (ch == out.pub->channel) c.need = std::max(c.need, step);
        for (const auto& [ch, step] : s.waiting) {
          if (ch != out.pub->channel) continue;
          if (out.pub->events) {
            // It cannot tell a lost event from a step without one: re-send what we keep
            // from that step, and our counts once we are past it.
                    if (step >= n) {
              c.awaits = std::min(c.awaits, step);  // answered when we complete it
            } else if (step >= status.step) {
              status_wanted = true;  // our last status did not cover it yet
            } else if (c.event_wait_step != step) {
              // Our last status covered it; this report may have crossed that status on
              // the way. Answer with our counts, and re-send only if it keeps waiting.
              c.event_wait_step = step;
              c.event_wait_since = Clock::now();
              status_wanted = true;
            } else if (Clock::now() - c.event_wait_since >= std::chrono::milliseconds(kEventWaitMs)) {
              // It still waits for the same step: an event or our status was lost. (Timing
              // this from our own last status instead missed it for 17 s and more: a
              // blocked producer and consumer wake each other with their statuses, so the
              // report always came in just after our status and was taken for a crossing.)
              republish(out, c, step);
              status_wanted = true;
            }
          } else if (step <= out.last) {
            republish(out, c, step);
          }
        }
      }
    }
  }

  // Re-sends our retained steps from `from` on, for a consumer that reports waiting for it.
  // A new step goes at once; the same step again only after a gap that doubles each time
  // (republish_ms, 2x, 4x ... kMaxResendGapMs): a consumer that is slow to work through
  // its queue keeps asking for a step whose copies are already on their way, and re-sending
  // them at every report (every 20 ms) only lengthened its queue.
  void republish(Output& out, Consumer& c, int64_t from) {
    const auto now = Clock::now();
    if (from == c.resent_step && now - c.resent_at < std::chrono::milliseconds(c.resend_gap_ms)) return;
    c.resend_gap_ms = from == c.resent_step ? std::min(2 * std::max(c.resend_gap_ms, 1), kMaxResendGapMs) : opt.republish_ms;
    c.resent_step = from;
    c.resent_at = now;
    spdlog::debug("{}: re-sending {} from step {}", cfg.name, out.pub->channel, from);
    int count = 0;
    for (auto it = out.retained.lower_bound(from); it != out.retained.end() && count < opt.window; ++it, ++count)
      tr.publish(out.pub->channel, it->second.data(), it->second.size());
  }

  int64_t oldest_needed(const Input& in, int64_t step) const {
    // Event-driven: the producer need not keep (or re-send) anything before the complete step.
    if (in.events) return time.events_complete(in.sub->channel);
    return in.sub->expected_step(step) - (in.sub->history - 1);
  }

  bool is_event_input(const std::string& channel) const {
    for (const auto& in : inputs)
      if (in.events && in.sub->channel == channel) return true;
    return false;
  }

  // Sample-and-hold: the newest event stamped at or before the step needed, else the
  // subscription's initial values; only once every event up to that step is known.
  bool gather_events(std::size_t i, Waits* missing) {
    auto& in = inputs[i];
    const int64_t want = in.sub->expected_step(n);
    const int64_t complete = time.events_complete(in.sub->channel);
    const bool before_events = want < -1 || (want == -1 && !in.producer_initial);  // initial values only
    if (!before_events && want >= complete) {
      if (missing) missing->emplace_back(in.sub->channel, complete);
      return false;
    }
    auto it = in.buffer.upper_bound(want);
    if (it != in.buffer.begin()) {
      args[i].push_back(&std::prev(it)->second);
    } else if (in.initial) {
      args[i].push_back(&*in.initial);
    } else {
      if (missing) missing->emplace_back(in.sub->channel, want);  // validation prevents this
      return false;
    }
    return true;
  }

  // Collects the inputs of step n; names every input that is missing (its first missing
  // step), so that all their producers re-send at once: a consumer that joined late (the
  // district aggregator of 100 buildings) otherwise recovered one input per round trip.
  bool gather(Waits* missing) {
    if (missing) missing->clear();
    bool complete = true;
    for (std::size_t i = 0; i < inputs.size(); ++i) {
      auto& in = inputs[i];
      args[i].clear();
      if (in.events) {
        if (!gather_events(i, missing)) complete = false;
        continue;
      }
      const int64_t newest = in.sub->expected_step(n);
      for (int k = 0; k < in.sub->history; ++k) {
        const int64_t s = newest - k;
        auto it = in.buffer.find(s);
        if (it != in.buffer.end()) {
          args[i].push_back(&it->second);
        } else if (s < 0 && in.initial && !(s == -1 && in.producer_initial)) {
          args[i].push_back(&*in.initial);
        } else {
          if (missing) missing->emplace_back(in.sub->channel, s);
          complete = false;
          break;
        }
      }
    }
    return complete;
  }

  // The inputs are there; the time grant must cover them too (it also covers messages
  // that are on their way but not yet here).
  bool granted(Waits* blocked) {
    std::string holder;
    if (time.may_advance(n, &holder)) return true;
    if (blocked) *blocked = {{"(time grant from " + holder + ")", n}};
    return false;
  }

  bool flow_ok(Waits* blocked) {
    for (auto& out : outputs)
      for (auto& c : out.consumers)
        if (!c.done && n - c.need >= opt.window) {
          if (blocked) *blocked = {{"(flow control: " + c.model + " needs " + out.pub->channel + ")", c.need}};
          return false;
        }
    return true;
  }

  void publish_output(Output& out, int64_t step, Bytes bytes) {
    if (out.pub->events) {
      if (bytes.empty()) return;  // no event at this step
      ++out.events;
    }
    if (step > out.published_before)
      tr.publish(out.pub->channel, bytes.data(), bytes.size());
    else
      tr.publish_within_group(out.pub->channel, bytes.data(), bytes.size());  // its peers re-run too
    out.last = step;
    for (auto& in : inputs)
      if (in.self && in.sub->channel == out.pub->channel) in.buffer.emplace(step, bytes);
    if (!out.consumers.empty()) out.retained.emplace(step, std::move(bytes));
  }

  void trim() {
    for (auto& in : inputs) {
      if (in.events) {
        // Keep the newest event at or before the step needed next (it is held) and later ones.
        auto it = in.buffer.upper_bound(in.sub->expected_step(n));
        if (it != in.buffer.begin()) in.buffer.erase(in.buffer.begin(), std::prev(it));
        continue;
      }
      const int64_t keep = oldest_needed(in, n);
      in.buffer.erase(in.buffer.begin(), in.buffer.lower_bound(keep));
    }
    for (auto& out : outputs) {
      int64_t keep = std::numeric_limits<int64_t>::max();
      for (const auto& c : out.consumers)
        if (!c.done) keep = std::min(keep, c.need);
      out.retained.erase(out.retained.begin(), out.retained.lower_bound(keep));
    }
  }

  void send_status(ModelState state, const Waits* waiting, const std::string& error = "") {
    status.step = n;
    status.utime = now_us();
    status.state = state;
    status.waiting = waiting ? *waiting : Waits{};
    reported_wait = status.waiting;
    std::string signature = std::to_string(static_cast<int>(state)) + " " + std::to_string(n);
    for (const auto& [ch, step] : status.waiting) signature += " " + ch + " " + std::to_string(step);
    repeat_ms = signature == reported_signature ? std::min(2 * repeat_ms, kMaxRepeatMs) : kFirstRepeatMs;
    reported_signature = std::move(signature);
    status.needs.clear();
    for (const auto& in : inputs)
      status.needs.emplace_back(in.sub->channel, n >= total ? std::numeric_limits<int64_t>::max() : oldest_needed(in, n));
    status.events.clear();
    for (const auto& out : outputs)
      if (out.pub->events) status.events.emplace_back(out.pub->channel, out.events);
    status.error = error;
    status.granted = time.granted();
    const auto bytes = encode_status(sc.types, status);
    tr.publish(status_channel(cfg.name), bytes.data(), bytes.size());
    last_status = Clock::now();
  }

  bool consumers_done() const {
    for (const auto& out : outputs)
      for (const auto& c : out.consumers) {
        // An event consumer is served only once it knows our last step had no more events.
        const int64_t last = out.pub->events ? total - 1 : out.last;
        if (!c.done && c.need <= last) return false;
      }
    return true;
  }

  // After our last step: a consumer not yet served that may still come for our steps, i.e.
  // one that has not reported yet (it may still be starting: hundreds of processes start
  // slowly; the launcher fails a run whose model never reports) or one that reported
  // within the linger time (alive, maybe slow: a consumer recovering a hundred inputs
  // under load took longer than a fixed linger, and the producers left before it was
  // served). Empty when every unserved consumer has been silent for the linger time.
  std::string unserved_consumer_alive(Clock::time_point now) const {
    for (const auto& out : outputs)
      for (const auto& c : out.consumers) {
        const int64_t last = out.pub->events ? total - 1 : out.last;
        if (c.done || c.need > last) continue;
        if (!c.heard || now - c.last_heard <= std::chrono::duration<double>(opt.linger_seconds)) return c.model;
      }
    return "";
  }

  bool stop_requested() const { return opt.stop && opt.stop->load(); }

  bool checkpointing() const { return cfg.checkpoint_every > 0 && fn->can_checkpoint() && tr.keeps_history(); }

  // The model's state, our own inputs still needed and the next step, on the mediator.
  void save_checkpoint() {
    json self = json::object();
    for (const auto& in : inputs) {
      if (!in.self) continue;
      json list = json::array();
      for (const auto& [step, bytes] : in.buffer) list.push_back({{"step", step}, {"message", json::binary(bytes)}});
      self[in.sub->channel] = std::move(list);
    }
    json events = json::object();
    for (const auto& out : outputs)
      if (out.pub->events) events[out.pub->channel] = out.events;
    const json j = {{"step", n}, {"model", json::binary(fn->save())}, {"self", std::move(self)}, {"events", std::move(events)}};
    const auto bytes = json::to_cbor(j);
    tr.publish(checkpoint_channel(cfg.name), bytes.data(), bytes.size());
  }

  // A restarted model continues from its last checkpoint (outputs before it are out).
  void load_checkpoint() {
    const Bytes stored = tr.last_stored(checkpoint_channel(cfg.name));
    if (stored.empty()) {
      spdlog::warn("{}: no checkpoint stored yet; replaying the inputs from step 0", cfg.name);
      return;
    }
    json j;
    int64_t step = 0;
    try {
      j = json::from_cbor(stored);
      step = j.at("step").get<int64_t>();
      if (step < 0 || step > total) throw std::out_of_range("step");
    } catch (const std::exception& e) {
      spdlog::warn("{}: its checkpoint is unreadable ({}); replaying the inputs from step 0", cfg.name, e.what());
      return;
    }
    fn->load(j.at("model").get_binary());
    for (auto& in : inputs) {
      if (!in.self || !j["self"].contains(in.sub->channel)) continue;
      in.buffer.clear();
      for (const auto& e : j["self"][in.sub->channel]) in.buffer.emplace(e.at("step").get<int64_t>(), e.at("message").get_binary());
    }
    n = step;
    for (auto& out : outputs) {
      out.last = n - 1;
      if (out.pub->events) out.events = j.value("events", json::object()).value(out.pub->channel, int64_t{0});
    }
    spdlog::warn("{}: resumed from its checkpoint at step {}", cfg.name, n);
  }

  void run() {
    if (opt.resume && checkpointing()) load_checkpoint();
    else if (cfg.checkpoint_every > 0 && !fn->can_checkpoint())
      spdlog::warn("{}: checkpoint_every is set but the plugin has no save/load hooks (see {}_model.hpp)", cfg.name,
                   cfg.name);
    for (auto& out : outputs)
      if (out.pub->initial) publish_output(out, -1, out.codec.encode(merged(out.codec, *out.pub->initial, -1)));
    send_status(ModelState::kRunning, nullptr);
    Waits wait;
    bool finished = false;
    while (!stop_requested()) {
      tr.handle(0);
      answer_status_request();
      if (n < total) {
        if (gather(&wait) && granted(&wait) && flow_ok(&wait)) {
          compute();
          continue;
        }
      } else {
        if (!finished) {
          finished = true;
          send_status(ModelState::kDone, nullptr);
        }
        if (consumers_done()) {
          // Our producers stop serving us when they hear we are done, and this is the last
          // status we send: it goes out three times. One lost copy on a lossy network left a
          // producer serving us until the launcher, seeing every model done but a thread
          // still running, declared a stall (DistributedRun.LosingMessagesIsRecoveredByRepublishing,
          // about 1 run in 50).
          for (int copy = 0; copy < 2; ++copy) {
            tr.handle(5);
            send_status(ModelState::kDone, nullptr);
          }
          return;
        }
        // Serve consumers for as long as they may still come (see unserved_consumer_alive).
        if (unserved_consumer_alive(Clock::now()).empty()) {
          spdlog::warn("{}: finished, but a consumer stopped reporting for {} s before it confirmed the last steps",
                       cfg.name, opt.linger_seconds);
          return;
        }
      }
      // A new wait for an event channel's completeness is reported at once (see Consumer::awaits).
      if (n < total && wait != reported_wait &&
          std::any_of(wait.begin(), wait.end(), [&](const auto& w) { return is_event_input(w.first); }))
        send_status(ModelState::kWaiting, &wait);
      tr.handle(20);
      answer_status_request();
      // Report while blocked, after 20 ms and then at growing intervals while nothing
      // changes (up to kMaxRepeatMs): consumers learn what to re-send, the launcher what
      // everyone waits for.
      if (Clock::now() - last_status > std::chrono::milliseconds(repeat_ms)) {
        if (n < total)
          send_status(ModelState::kWaiting, &wait);
        else
          send_status(ModelState::kDone, nullptr);
      }
    }
    was_stopped = true;
    send_status(ModelState::kStopped, nullptr);
  }

  // A consumer of an event channel waits for a step it cannot know complete: send our
  // counts now (at most every republish interval) instead of at the next periodic report.
  void answer_status_request() {
    if (!status_wanted) return;
    status_wanted = false;
    if (n < total) send_status(ModelState::kRunning, nullptr);
    else send_status(ModelState::kDone, nullptr);
  }

  void compute() {
    if (n == opt.kill_at) {
      spdlog::warn("{}: --kill: SIGKILL at step {}", cfg.name, n);
      ::kill(::getpid(), SIGKILL);
    }
    // A model stuck in its function still shows which step it is computing.
    if (Clock::now() - last_status > std::chrono::milliseconds(100)) send_status(ModelState::kRunning, nullptr);
    try {
      fn->step(n, static_cast<double>(n) * cfg.dt, args, results);
      for (std::size_t i = 0; i < outputs.size(); ++i) {
        if (outputs[i].pub->events && results[i].empty()) continue;  // no event this step
        const int64_t stamped = outputs[i].codec.read_int64(results[i].data(), results[i].size(), kStepField);
        if (stamped != n)
          throw Failure("model '" + cfg.name + "' stamped step " + std::to_string(stamped) + " on channel '" +
                        outputs[i].pub->channel + "' at step " + std::to_string(n));
      }
    } catch (const std::exception& e) {
      send_status(ModelState::kFailed, nullptr, e.what());
      throw Failure(e.what());
    }
    for (std::size_t i = 0; i < outputs.size(); ++i) publish_output(outputs[i], n, std::move(results[i]));
    if (opt.on_step) opt.on_step(n);
    ++n;
    trim();
    bool awaited = false;
    for (auto& out : outputs)
      for (auto& c : out.consumers)
        if (c.awaits < n) {
          awaited = true;
          c.awaits = std::numeric_limits<int64_t>::max();
        }
    if (awaited && n % opt.status_every != 0) send_status(ModelState::kRunning, nullptr);
    if (checkpointing() && n % cfg.checkpoint_every == 0 && n < total) save_checkpoint();
    if (n % opt.status_every == 0) send_status(ModelState::kRunning, nullptr);
  }
};

MessageWrapper::MessageWrapper(const ScenarioConfig& scenario, const std::string& model, Transport& transport,
                               std::unique_ptr<ModelFunction> function, WrapperOptions options)
    : impl_(std::make_unique<Impl>(scenario, model, transport, std::move(function), std::move(options))) {}
MessageWrapper::~MessageWrapper() = default;
void MessageWrapper::run() { impl_->run(); }
bool MessageWrapper::stopped() const { return impl_->was_stopped; }
int64_t MessageWrapper::steps_done() const { return impl_->n; }

}  // namespace builtscene::couple
