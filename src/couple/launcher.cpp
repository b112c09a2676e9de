#include "couple/launcher.hpp"

#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <optional>
#include <cstring>
#include <limits>
#include <set>
#include <thread>

#include "core/errors.hpp"
#include "core/logging.hpp"
#include "couple/event_tracker.hpp"
#include "couple/lcm_codec.hpp"
#include "couple/hybrid_transport.hpp"
#include "couple/lcm_log.hpp"
#include "couple/message_wrapper.hpp"
#include "couple/nats_server.hpp"
#include "couple/nats_transport.hpp"
#include "couple/status.hpp"
#include "couple/transport.hpp"

namespace builtscene::couple {
namespace {

using Clock = std::chrono::steady_clock;

void on_signal(int) { stop_flag().store(true); }

// Watches statuses and channel traffic; records everything.
class Monitor {
 public:
  Monitor(const ScenarioConfig& sc, Transport& tr, const std::filesystem::path& record) : sc_(sc) {
    if (!record.empty()) log_ = std::make_unique<LcmLogWriter>(record);
    auto handler = [this](const std::string& ch, const uint8_t* d, std::size_t n) { on_message(ch, d, n); };
    if (log_ || !is_nats_url(tr.url())) {
      tr.subscribe("", handler);  // the recorder takes everything (on LCM one pattern is cheapest)
    } else {
      // Through the mediator only the statuses: at 100 buildings the data channels would
      // double what nats-server sends, for a launcher that drops them.
      for (const auto& m : sc.models) tr.subscribe(status_channel(m.name), handler);
    }
    for (const auto& m : sc.models) {
      statuses_[m.name].model = m.name;
      statuses_[m.name].steps = m.steps();
      if (log_)
        for (const auto& p : m.publish)
          recorded_.emplace(p.channel, Recorded{LcmCodec(sc.types, p.type), {}, p.initial ? -1 : 0, m.steps(), m.name,
                                                p.events, EventTracker(p.initial ? -1 : 0)});
    }
    last_progress_ = Clock::now();
  }

  // The recorder's own status: per channel the first step it has not logged, and a wait
  // for it when a later one arrived (a gap: lost on the network). Producers re-send.
  void report_recorder(Transport& tr) {
    if (recorded_.empty() || Clock::now() - last_report_ < std::chrono::milliseconds(5)) return;
    last_report_ = Clock::now();
    ModelStatus s;
    s.model = kRecorderName;
    s.utime = now_us();
    bool complete = true;
    for (auto& [ch, r] : recorded_) {
      if (r.events) {
        // Event-driven: complete up to where the producer's counts say; ask for the rest.
        const int64_t done = r.tracker.complete();
        if (done < r.total) complete = false;
        s.needs.emplace_back(ch, done >= r.total ? std::numeric_limits<int64_t>::max() : done);
        if (done < r.total && statuses_.at(r.producer).step > done) s.waiting.emplace_back(ch, done);
        continue;
      }
      while (r.steps.count(r.next)) r.steps.erase(r.next++);
      if (r.next < r.total) complete = false;
      s.needs.emplace_back(ch, r.next >= r.total ? std::numeric_limits<int64_t>::max() : r.next);
      // A gap, or the producer is past a step we never got: ask for it.
      if (r.next < r.total && (!r.steps.empty() || statuses_.at(r.producer).step > r.next))
        s.waiting.emplace_back(ch, r.next);
    }
    s.state = complete ? ModelState::kDone : ModelState::kRunning;
    const auto bytes = encode_status(sc_.types, s);
    tr.publish(status_channel(kRecorderName), bytes.data(), bytes.size());
  }

  void on_message(const std::string& ch, const uint8_t* d, std::size_t n) {
    if (log_) log_->write(now_us(), ch, d, n);
    if (!is_status_channel(ch)) {
      auto it = recorded_.find(ch);
      if (it != recorded_.end()) {
        try {
          const int64_t step = it->second.codec.read_int64(d, n, kStepField);
          if (it->second.events)
            it->second.tracker.on_event(step);
          else
            it->second.steps.insert(step);
        } catch (const InputError&) {
        }
      }
      return;
    }
    try {
      ModelStatus s = decode_status(sc_.types, d, n);
      auto it = statuses_.find(s.model);
      if (it == statuses_.end()) return;
      for (const auto& [ch, count] : s.events) {
        auto rec = recorded_.find(ch);
        if (rec != recorded_.end() && rec->second.events && rec->second.producer == s.model)
          rec->second.tracker.on_count(s.step, count);
      }
      if (s.step > it->second.step || s.state != it->second.state) last_progress_ = Clock::now();
      if (s.step >= it->second.step) it->second = std::move(s);
      if (!all_started_) {
        bool all = true;
        for (const auto& [_, st] : statuses_) all = all && st.utime != 0;
        if (all) all_started_ = Clock::now();
      }
    } catch (const InputError&) {
    }
  }

  bool all_done() const {
    for (const auto& [_, s] : statuses_)
      if (s.state != ModelState::kDone) return false;
    return true;
  }
  std::optional<std::string> failure() const {
    for (const auto& [name, s] : statuses_)
      if (s.state == ModelState::kFailed) return s.error.empty() ? "model '" + name + "' failed" : s.error;
    return std::nullopt;
  }
  void touch() { last_progress_ = Clock::now(); }  // a restarted model gets a fresh timeout
  double idle_seconds() const { return std::chrono::duration<double>(Clock::now() - last_progress_).count(); }
  // Start-up (loading plugins, starting interpreters) gets more time than a step.
  bool stalled(double timeout) const { return idle_seconds() > (all_started_ ? timeout : 3 * timeout + 10); }

  // Where the models are: "steps done: 301 models, 12 done, the others at steps 3-197".
  std::string progress() const {
    int64_t lo = std::numeric_limits<int64_t>::max(), hi = std::numeric_limits<int64_t>::min();
    int done = 0;
    for (const auto& [_, s] : statuses_) {
      if (s.state == ModelState::kDone) {
        ++done;
        continue;
      }
      lo = std::min(lo, s.step);
      hi = std::max(hi, s.step);
    }
    std::string r = std::to_string(statuses_.size()) + " models, " + std::to_string(done) + " done";
    if (done < static_cast<int>(statuses_.size())) r += ", the others at steps " + std::to_string(lo) + "-" + std::to_string(hi);
    return r;
  }

  std::string stall_report() const {
    std::string r;
    for (const auto& [name, s] : statuses_) {
      if (s.state == ModelState::kDone) continue;
      r += (r.empty() ? "" : "; ") + std::string("model '") + name + "' at step " + std::to_string(s.step);
      if (!s.waiting.empty() && s.waiting[0].first.rfind("(", 0) == 0) {
        r += " waits for " + s.waiting[0].first.substr(1, s.waiting[0].first.size() - 2) + ", granted time " +
             fmt::format("{:g}", s.granted) + " s";
      } else if (!s.waiting.empty()) {
        r += " waits for channel '" + s.waiting[0].first + "' step " + std::to_string(s.waiting[0].second);
        for (const auto& m : sc_.models)
          for (const auto& p : m.publish)
            if (p.channel == s.waiting[0].first) r += " (published by model '" + m.name + "')";
      }
      else if (s.utime == 0)
        r += " never reported (did it start?)";
      else if (s.state == ModelState::kRunning)
        r += " (running; its last report)";
    }
    return r;
  }

  void show(bool final) {
    if (!isatty(2)) return;
    std::string line;
    for (const auto& [name, s] : statuses_)
      line += " " + name + " " + std::to_string(s.step) + "/" + std::to_string(s.steps) + " " + state_name(s.state);
    std::fprintf(stderr, "\r\033[Kcouple:%s%s", line.c_str(), final ? "\n" : "");
  }

  const std::map<std::string, ModelStatus>& statuses() const { return statuses_; }
  int64_t events() const { return log_ ? log_->events() : 0; }
  void flush() {
    if (log_) log_->flush();
  }

 private:
  struct Recorded {
    LcmCodec codec;
    std::set<int64_t> steps;  // logged beyond `next`
    int64_t next;             // first step not yet logged
    int64_t total;
    std::string producer;
    bool events = false;   // event-driven: `tracker` instead of steps/next
    EventTracker tracker;
  };
  const ScenarioConfig& sc_;
  std::unique_ptr<LcmLogWriter> log_;
  std::map<std::string, Recorded> recorded_;
  Clock::time_point last_report_{};
  std::map<std::string, ModelStatus> statuses_;
  Clock::time_point last_progress_;

 public:
  std::optional<Clock::time_point> all_started_;  // every model has reported once
};

LaunchResult finish(const ScenarioConfig& sc, Monitor& mon, Clock::time_point start) {
  LaunchResult r;
  const auto end = Clock::now();
  r.seconds = std::chrono::duration<double>(end - start).count();
  r.run_seconds = std::chrono::duration<double>(end - mon.all_started_.value_or(start)).count();
  for (const auto& m : sc.models) {
    r.steps = std::max(r.steps, m.steps());
    r.model_steps[m.name] = mon.statuses().at(m.name).step;
  }
  r.steps_per_second = r.run_seconds > 0 ? static_cast<double>(r.steps) / r.run_seconds : 0;
  mon.flush();
  r.logged_events = mon.events();
  return r;
}

// Runs each wrapper on its own thread; the first model that throws raises `stop` for the
// others and its message is kept (the launcher's thread mode and a process hosting several
// models both run wrappers this way).
class WrapperThreads {
 public:
  WrapperThreads(const std::vector<std::unique_ptr<MessageWrapper>>& wrappers, std::atomic<bool>& stop)
      : running_(static_cast<int>(wrappers.size())) {
    for (const auto& w : wrappers)
      threads_.emplace_back([this, &stop, wp = w.get()] {
        try {
          wp->run();
        } catch (const std::exception& e) {
          std::lock_guard lock(m_);
          if (first_error_.empty()) first_error_ = e.what();
          stop = true;
        }
        --running_;
      });
  }
  ~WrapperThreads() { join(); }
  int running() const { return running_; }
  void join() {
    for (auto& t : threads_)
      if (t.joinable()) t.join();
  }
  std::string first_error() {
    std::lock_guard lock(m_);
    return first_error_;
  }

 private:
  std::mutex m_;
  std::string first_error_;
  std::atomic<int> running_;
  std::vector<std::thread> threads_;
};

LaunchResult launch_threads(const ScenarioConfig& sc, const LaunchOptions& opt) {
  auto tr = make_transport(sc.transport);
  Monitor mon(sc, *tr, opt.record);
  std::atomic<bool> stop{false};
  std::vector<std::unique_ptr<Transport>> transports;
  std::vector<std::unique_ptr<MessageWrapper>> wrappers;
  // Load every model before any starts, so a bad plugin fails before traffic.
  for (const auto& cfg : sc.models) {
    transports.push_back(make_model_transport(sc, cfg.name, sc.transport, !opt.record.empty()));
    WrapperOptions wo;
    wo.stop = &stop;
    wo.linger_seconds = sc.timeout_seconds;
    wo.recorder = !opt.record.empty();
    wrappers.push_back(std::make_unique<MessageWrapper>(sc, cfg.name, *transports.back(),
                                                        load_model_function(cfg, sc.types), wo));
  }
  const auto start = Clock::now();
  WrapperThreads threads(wrappers, stop);
  std::string failure;
  while (threads.running() > 0) {
    tr->handle(20);
    mon.report_recorder(*tr);
    mon.show(false);
    if (stop_flag()) failure = "interrupted";
    else if (mon.stalled(sc.timeout_seconds))
      failure = "no model advanced for " + std::to_string(sc.timeout_seconds) + " s: " + mon.stall_report();
    if (!failure.empty()) {
      stop = true;
      break;
    }
  }
  threads.join();
  while (tr->handle(0) > 0) {
  }
  mon.show(true);
  if (failure.empty()) failure = threads.first_error();
  LaunchResult r = finish(sc, mon, start);
  if (!failure.empty())
    throw Failure(failure + (opt.record.empty() ? "" : " (log kept: " + opt.record.string() + ")"));
  return r;
}

std::string describe_exit(int status) {
  if (WIFEXITED(status)) return "exited with code " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) return std::string("was killed by signal ") + strsignal(WTERMSIG(status));
  return "stopped";
}

// A local input (LCM between sub-models) keeps no history: its reader cannot resume.
std::string local_input(const ScenarioConfig& sc, const std::string& model) {
  for (const auto& s : sc.model(model).subscribe)
    if (reads_locally(sc, model, s.channel)) return s.channel;
  return "";
}

// The models to restart when `model` dies: itself, or, when it reads a local channel, its
// whole group (every member must run under this launcher); empty when that is impossible.
std::vector<std::string> restart_group(const ScenarioConfig& sc, const std::string& model,
                                       const std::vector<std::string>& only) {
  if (local_input(sc, model).empty()) return {model};
  std::vector<std::string> group;
  for (const auto& m : sc.models) {
    if (m.group != sc.model(model).group) continue;
    if (!only.empty() && std::find(only.begin(), only.end(), m.name) == only.end()) return {};
    group.push_back(m.name);
  }
  return group;
}

LaunchResult launch_processes(const ScenarioConfig& sc, const LaunchOptions& opt, NatsServer* server,
                              bool recovery) {
  auto tr = make_transport(sc.transport);
  Monitor mon(sc, *tr, opt.record);
  std::filesystem::path exe = opt.executable.empty() ? std::filesystem::read_symlink("/proc/self/exe") : opt.executable;
  const std::string scenario = std::filesystem::absolute(opt.scenario_file.empty() ? sc.file : opt.scenario_file);
  // Each process hosts one model, or `models_per_process` consecutive ones (one wrapper
  // thread each): pid -> its models.
  std::map<pid_t, std::vector<std::string>> children;
  const auto start = Clock::now();
  auto spawn = [&](const std::vector<std::string>& models, bool resume) {
    std::vector<std::string> args = {exe.string(), "couple", "run-model", scenario, "--transport", sc.transport};
    // `builtscene -v couple launch`: the model processes log their debug messages too.
    if (spdlog::should_log(spdlog::level::debug)) args.insert(args.begin() + 1, "-v");
    for (const auto& m : models) args.insert(args.end(), {"--model", m});
    if (!opt.record.empty()) args.push_back("--recorder");
    if (resume) args.push_back("--resume");
    for (const auto& [m, step] : opt.kills)
      if (!resume && std::find(models.begin(), models.end(), m) != models.end())
        args.insert(args.end(), {"--kill-at", m + "@" + std::to_string(step)});
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    const pid_t launcher = getpid();
    const pid_t pid = fork();
    if (pid < 0) throw Failure("fork failed");
    if (pid == 0) {
      // A model process never outlives its launcher, even one killed by SIGKILL (a stopped
      // benchmark or a crashed launcher used to leave hundreds of them running).
      prctl(PR_SET_PDEATHSIG, SIGTERM);
      if (getppid() != launcher) _exit(1);  // the launcher died before the prctl
      execv(exe.c_str(), argv.data());
      std::fprintf(stderr, "cannot run %s: %s\n", exe.c_str(), std::strerror(errno));
      _exit(127);
    }
    children[pid] = models;
  };
  {
    std::vector<std::string> ours;
    for (const auto& m : sc.models)
      if (opt.only.empty() || std::find(opt.only.begin(), opt.only.end(), m.name) != opt.only.end()) ours.push_back(m.name);
    const std::size_t per =
        static_cast<std::size_t>(std::max(1, opt.models_per_process > 0 ? opt.models_per_process : sc.models_per_process));
    for (std::size_t i = 0; i < ours.size(); i += per)
      spawn(std::vector<std::string>(ours.begin() + i, ours.begin() + std::min(ours.size(), i + per)), false);
  }
  std::string failure;
  std::map<std::string, int> restarts;
  auto reap = [&](bool block) {
    int status = 0;
    pid_t pid;
    while ((pid = waitpid(-1, &status, block ? 0 : WNOHANG)) > 0) {
      if (server && pid == server->pid() && failure.empty() && !stop_flag())
        failure = "the mediator (nats-server) " + describe_exit(status);
      auto it = children.find(pid);
      if (it == children.end()) continue;
      const std::vector<std::string> models = it->second;
      const std::string& model = models.front();
      // A process that died by a signal (kill -9, a crash) is restarted while the run goes
      // on; its models replay their inputs from the mediator's history. One that reads a
      // local channel (LCM, no history) is restarted with its whole group, here, so the
      // group's producers re-send those steps; a process hosting a restarted model is
      // restarted whole.
      std::set<std::string> restart;
      bool possible = true;
      std::string not_restartable;
      for (const auto& m : models) {
        const auto g = restart_group(sc, m, opt.only);
        if (g.empty()) {
          possible = false;
          not_restartable = m;
        }
        restart.insert(g.begin(), g.end());
      }
      std::vector<std::vector<std::string>> respawn = {models};
      if (recovery && !block && failure.empty() && !stop_flag() && WIFSIGNALED(status) && possible &&
          restarts[model] < opt.max_restarts) {
        children.erase(it);
        std::set<std::string> covered(models.begin(), models.end());
        for (bool grew = true; grew;) {  // whole processes, whole groups
          grew = false;
          for (auto c = children.begin(); c != children.end();) {
            bool hit = false;
            for (const auto& m : c->second) hit = hit || restart.count(m);
            if (!hit) {
              ++c;
              continue;
            }
            ::kill(c->first, SIGKILL);
            ::waitpid(c->first, nullptr, 0);
            for (const auto& m : c->second) {
              covered.insert(m);
              if (restart.insert(m).second) grew = true;
              for (const auto& g : restart_group(sc, m, opt.only))
                if (restart.insert(g).second) grew = true;
            }
            respawn.push_back(c->second);
            c = children.erase(c);
          }
        }
        for (const auto& m : restart)  // a group member whose process had already finished
          if (!covered.count(m)) respawn.push_back({m});
        std::string who = "model '" + model + "'";
        for (std::size_t i = 1; i < models.size(); ++i) who += (i == 1 ? " (its process also hosts '" : ", '") + models[i] + "'";
        if (models.size() > 1) who += ")";
        spdlog::warn("couple: {} {} at step {}; restarting {} (attempt {}), resuming from the mediator's history",
                     who, describe_exit(status), mon.statuses().at(model).step,
                     restart.size() == 1 ? std::string("it") : fmt::format("{} models with it", restart.size() - 1),
                     restarts[model] + 1);
        if (!sc.model(model).group.empty() && restart.size() > 1)
          spdlog::warn("couple: restarting its group '{}'", sc.model(model).group);
        for (const auto& list : respawn) {
          for (const auto& m : list) ++restarts[m];
          spawn(list, true);
        }
        mon.touch();
        continue;
      }
      if (failure.empty() && !(WIFEXITED(status) && WEXITSTATUS(status) == 0) && !stop_flag()) {
        tr->handle(0);  // pick up its last status (the model's own error message)
        auto why = mon.failure();
        failure = why ? *why : "model '" + model + "' " + describe_exit(status) + " at step " +
                                   std::to_string(mon.statuses().at(model).step);
        if (recovery && WIFSIGNALED(status) && !possible)
          failure += " (not restarted: '" + not_restartable + "' reads the local channel '" + local_input(sc, not_restartable) +
                     "', LCM within its group, and not every model of the group runs here to restart with it)";
      }
      children.erase(it);
      if (children.empty()) break;
    }
  };
  while (!children.empty()) {
    tr->handle(20);
    mon.report_recorder(*tr);
    mon.show(false);
    reap(false);
    if (!failure.empty()) break;
    if (auto why = mon.failure()) {
      failure = *why;
      break;
    }
    if (stop_flag()) {
      failure = "interrupted (" + mon.progress() + ")";
      break;
    }
    if (mon.stalled(sc.timeout_seconds)) {
      failure = "no model advanced for " + std::to_string(static_cast<int>(sc.timeout_seconds)) + " s: " + mon.stall_report();
      break;
    }
  }
  if (!children.empty()) {
    for (const auto& [pid, _] : children) kill(pid, SIGTERM);
    const auto deadline = Clock::now() + std::chrono::seconds(3);
    while (!children.empty() && Clock::now() < deadline) {
      tr->handle(20);
      reap(false);
    }
    for (const auto& [pid, _] : children) kill(pid, SIGKILL);
    if (!children.empty()) reap(true);
  }
  while (tr->handle(0) > 0) {
  }
  mon.show(true);
  LaunchResult r = finish(sc, mon, start);
  if (server) r.mediator_cpu_seconds = server->cpu_seconds();
  for (const auto& [m, k] : restarts) r.restarts[m] = k;
  if (!failure.empty())
    throw Failure(failure + "; the other models were stopped" +
                  (opt.record.empty() ? "" : " (log kept: " + opt.record.string() + ")"));
  return r;
}

}  // namespace

std::atomic<bool>& stop_flag() {
  static std::atomic<bool> flag{false};
  return flag;
}

void install_stop_signals() {
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;  // no SA_RESTART: blocking waits return so the flag is seen
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

nlohmann::json LaunchResult::to_json() const {
  nlohmann::json j = {{"models", model_steps}, {"steps", steps}, {"seconds", seconds}, {"run_seconds", run_seconds},
                      {"steps_per_second", steps_per_second}, {"logged_events", logged_events},
                      {"transport", transport}};
  if (mediator_cpu_seconds >= 0) j["mediator_cpu_seconds"] = mediator_cpu_seconds;
  j["restarts"] = restarts;
  return j;
}

LaunchResult launch(const ScenarioConfig& scenario, const LaunchOptions& opt) {
  install_stop_signals();
  for (const auto& [m, step] : opt.kills) {
    scenario.model(m);  // InputError naming an unknown model
    if (restart_group(scenario, m, opt.only).empty())
      throw InputError("--kill " + m + "@" + std::to_string(step) + ": model '" + m + "' reads the local channel '" +
                       local_input(scenario, m) + "' (LCM, no history) and not every model of its group '" +
                       scenario.model(m).group + "' runs under this launcher (--only) to restart with it");
    if (step < 0 || step >= scenario.model(m).steps())
      throw InputError("--kill " + m + "@" + std::to_string(step) + ": the step must be in 0.." +
                       std::to_string(scenario.model(m).steps() - 1));
  }
  for (const auto& m : opt.only) scenario.model(m);  // InputError naming an unknown model
  if (!opt.only.empty() && opt.nats.empty())
    throw InputError("--only needs --nats nats://HOST:PORT: the models on other hosts must reach the same mediator");
  if (!opt.kills.empty() && opt.nats.empty() && scenario.transport != kMediator && !is_nats_url(scenario.transport))
    throw InputError("--kill needs the mediator (transport: mediator, nats://HOST:PORT or --nats): over '" +
                     scenario.transport + "' a killed model has no history to resume from");
  if (is_in_process(scenario.transport) && opt.nats.empty()) {
    LaunchResult r = launch_threads(scenario, opt);
    r.transport = scenario.transport;
    return r;
  }
  ScenarioConfig sc = scenario;
  std::optional<NatsServer> server;  // stopped last, on every way out of this function
  if (!opt.nats.empty()) {
    sc.transport = opt.nats;
  } else if (sc.transport == kMediator) {
    server.emplace();
    sc.transport = server->url();
    spdlog::info("couple: mediator (nats-server, JetStream) at {}", sc.transport);
  }
  bool history = false;
  if (is_nats_url(sc.transport)) {
    std::vector<std::string> channels;
    for (const auto& m : sc.models) {
      for (const auto& p : m.publish) channels.push_back(p.channel);
      if (m.checkpoint_every > 0) channels.push_back(checkpoint_channel(m.name));
    }
    try {
      create_history_stream(sc.transport, channels, opt.history_per_channel);
      history = true;
    } catch (const Failure& e) {
      if (!opt.kills.empty()) throw;
      // A plain NATS server (no JetStream) still carries the run, without recovery.
      spdlog::warn("couple: {}; running without recovery (a model that dies ends the run)", e.what());
    }
  }
  LaunchResult r = launch_processes(sc, opt, server ? &*server : nullptr, history);
  r.transport = sc.transport;
  return r;
}

int run_model_process(const std::filesystem::path& scenario_file, const std::vector<std::string>& models,
                      const std::string& transport, bool recorder, bool resume,
                      const std::map<std::string, int64_t>& kill_at) {
  install_stop_signals();
  const ScenarioConfig sc = load_scenario(scenario_file);
  // One wrapper (own transport, own thread) per model; each blocks in its transport, so
  // many models share a process and its cores without busy-waiting.
  std::atomic<bool> stop{false};
  const std::atomic<bool>* stop_ptr = models.size() == 1 ? &stop_flag() : &stop;
  std::vector<std::unique_ptr<Transport>> transports;
  std::vector<std::unique_ptr<MessageWrapper>> wrappers;
  for (const auto& model : models) {
    const ModelConfig& cfg = sc.model(model);
    const std::string url = !transport.empty() ? transport : cfg.transport.empty() ? sc.transport : cfg.transport;
    transports.push_back(make_model_transport(sc, model, url, recorder));
    WrapperOptions wo;
    wo.stop = stop_ptr;
    wo.linger_seconds = sc.timeout_seconds;
    wo.recorder = recorder;
    wo.resume = resume;
    if (auto k = kill_at.find(model); k != kill_at.end()) wo.kill_at = k->second;
    wrappers.push_back(std::make_unique<MessageWrapper>(sc, model, *transports.back(), load_model_function(cfg, sc.types), wo));
  }
  if (wrappers.size() == 1) {
    wrappers[0]->run();
    return wrappers[0]->stopped() ? 130 : 0;
  }
  WrapperThreads threads(wrappers, stop);
  while (threads.running() > 0) {
    if (stop_flag()) stop = true;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  threads.join();
  if (const std::string e = threads.first_error(); !e.empty()) throw Failure(e);
  for (const auto& w : wrappers)
    if (w->stopped()) return 130;
  return 0;
}

}  // namespace builtscene::couple
