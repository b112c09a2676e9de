// `builtscene couple ...`: distributed coupling analysis (src/couple, docs/coupling.md).
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <memory>

#include "command_registry.hpp"
#include "core/errors.hpp"
#include "core/logging.hpp"
#include "couple/export.hpp"
#include "couple/launcher.hpp"
#include "couple/lcm_codec.hpp"
#include "couple/model_config.hpp"
#include "couple/monolithic.hpp"
#include "couple/prototype_generator.hpp"
#include "couple/status.hpp"
#include "couple/time_series_plot.hpp"
#include "couple/nats_transport.hpp"
#include "couple/transport.hpp"

namespace builtscene::app {
namespace {

namespace fs = std::filesystem;
using namespace builtscene::couple;
using nlohmann::json;

const bool group_couple = register_group("couple", "Distributed coupling analysis: models, message wrapper, LCM");

struct NewModelOptions {
  fs::path config, out;
  std::vector<fs::path> messages;
  bool force = false;
};

const bool new_model = register_command({
    .path = {"couple", "new-model"},
    .description = "Write a model-function stub (C++ plugin + CMake project, Python JSON-lines stub)",
    .setup = [](CLI::App& cmd) -> Action {
      auto o = std::make_shared<NewModelOptions>();
      cmd.add_option("--config", o->config, "Model config (YAML)")->required();
      cmd.add_option("--messages", o->messages, "Message definitions (.lcm); default: the config's 'messages'");
      cmd.add_option("--out", o->out, "Output folder")->required();
      cmd.add_flag("--force", o->force, "Overwrite the user files (MODEL.cpp, MODEL.py) if they exist");
      return [o] {
        const ModelConfig cfg = load_model_config(o->config);
        const auto stub = generate_model_stub(cfg, o->messages, o->out, o->force);
        spdlog::info("wrote {} files to {}; fill in {}", stub.written.size(), o->out.string(),
                     (o->out / (cfg.name + ".cpp")).string());
        for (const auto& k : stub.kept) spdlog::info("kept your {}", k.string());
        json files = json::array();
        for (const auto& f : stub.written) files.push_back(f.string());
        return json{{"model", cfg.name}, {"files", files}, {"signature", stub.signature}};
      };
    },
    .order = 10});

struct LaunchCliOptions {
  fs::path scenario, record;
  std::string transport, nats;
  std::vector<std::string> kills, only;
  int models_per_process = 0;
};

const bool launch_cmd = register_command({
    .path = {"couple", "launch"},
    .description = "Run a scenario: every model its own process (udpm, mediator) or thread (memq)",
    .setup = [](CLI::App& cmd) -> Action {
      auto o = std::make_shared<LaunchCliOptions>();
      cmd.add_option("scenario", o->scenario, "Scenario (YAML)")->required();
      cmd.add_option("--record", o->record, "Record every channel to this LCM log (lcm-logplayer replays it)");
      cmd.add_option("--transport", o->transport,
                     "Override the scenario's transport (udpm://..., nats://HOST:PORT, mediator, memq://NAME)");
      cmd.add_option("--nats", o->nats,
                     "Use this running mediator (nats://HOST:PORT) instead of starting a local nats-server");
      cmd.add_option("--kill", o->kills,
                     "Fault injection: SIGKILL MODEL's process at STEP (MODEL@STEP, repeatable); the launcher "
                     "restarts it and it resumes from the mediator's history");
      cmd.add_option("--models-per-process", o->models_per_process,
                     "Host this many consecutive models per process, a wrapper thread each (default: the "
                     "scenario's models_per_process, 1)")
          ->check(CLI::PositiveNumber);
      cmd.add_option("--only", o->only,
                     "Several hosts: start only this model here (repeatable); the others run on other hosts "
                     "under their own `couple launch --only ...` with the same --nats");
      return [o] {
        ScenarioConfig sc = load_scenario(o->scenario);
        if (!o->transport.empty()) {
          if (o->transport != kMediator) make_transport(o->transport);  // validates the URL before anything starts
          sc.transport = o->transport;
        }
        if (!o->nats.empty() && !is_nats_url(o->nats))
          throw InputError("--nats '" + o->nats + "': expected nats://HOST:PORT");
        for (const auto& m : o->only) sc.model(m);  // names a model of the scenario
        if (!o->nats.empty()) make_transport(o->nats);  // reachable before anything starts
        LaunchOptions lo;
        lo.nats = o->nats;
        lo.only = o->only;
        lo.models_per_process = o->models_per_process;
        for (const auto& k : o->kills) {
          const auto at = k.rfind('@');
          int64_t step = -1;
          try {
            if (at == std::string::npos) throw std::invalid_argument(k);
            std::size_t used = 0;
            step = std::stoll(k.substr(at + 1), &used);
            if (used != k.size() - at - 1) throw std::invalid_argument(k);
          } catch (const std::exception&) {
            throw InputError("--kill '" + k + "': expected MODEL@STEP, e.g. structure@3000");
          }
          lo.kills.emplace_back(k.substr(0, at), step);
        }
        lo.record = o->record;
        lo.scenario_file = o->scenario;
        const LaunchResult r = launch(sc, lo);
        spdlog::info("{}: {} steps in {:.3f} s ({:.0f} steps/s){}", sc.name, r.steps, r.seconds, r.steps_per_second,
                     o->record.empty() ? "" : ", log " + o->record.string());
        json j = r.to_json();
        j["scenario"] = sc.name;
        if (!o->record.empty()) j["record"] = o->record.string();
        return j;
      };
    },
    .order = 20});

struct RunModelOptions {
  fs::path scenario;
  std::vector<std::string> models;
  std::string transport;
  bool recorder = false, resume = false;
  std::vector<std::string> kill_at;
};

const bool run_model = register_command({
    .path = {"couple", "run-model"},
    .description = "(internal) one model's wrapper; started by `couple launch`",
    .setup = [](CLI::App& cmd) -> Action {
      auto o = std::make_shared<RunModelOptions>();
      cmd.add_option("scenario", o->scenario, "Scenario (YAML)")->required();
      cmd.add_option("--model", o->models, "Model name (repeat: several models in this process, a thread each)")->required();
      cmd.add_option("--transport", o->transport, "Transport URL (default: the scenario's)");
      cmd.add_flag("--recorder", o->recorder, "The launcher records: re-send lost messages to it too");
      cmd.add_flag("--resume", o->resume, "Restarted after a crash: replay the inputs' history from the mediator");
      cmd.add_option("--kill-at", o->kill_at,
                     "Fault injection: SIGKILL this process when MODEL reaches STEP (MODEL@STEP, or STEP with one --model)");
      return [o] {
        std::map<std::string, int64_t> kill_at;
        for (const auto& k : o->kill_at) {
          const auto at = k.rfind('@');
          const std::string model = at == std::string::npos ? (o->models.size() == 1 ? o->models[0] : "") : k.substr(0, at);
          try {
            std::size_t used = 0;
            const std::string step = at == std::string::npos ? k : k.substr(at + 1);
            kill_at[model] = std::stoll(step, &used);
            if (used != step.size() || model.empty()) throw std::invalid_argument(k);
          } catch (const std::exception&) {
            throw InputError("--kill-at '" + k + "': expected MODEL@STEP (or STEP with a single --model)");
          }
        }
        const int rc = run_model_process(o->scenario, o->models, o->transport, o->recorder, o->resume, kill_at);
        std::string names;
        for (const auto& m : o->models) names += (names.empty() ? "" : ", ") + m;
        if (rc != 0) throw Failure("model(s) " + names + " stopped");
        return json{{"models", o->models}};
      };
    },
    .order = 90});

struct ExportOptions {
  fs::path log, csv, scenario;
  std::vector<fs::path> messages;
};

const bool export_cmd = register_command({
    .path = {"couple", "export"},
    .description = "Write one CSV per channel from an LCM log",
    .setup = [](CLI::App& cmd) -> Action {
      auto o = std::make_shared<ExportOptions>();
      cmd.add_option("log", o->log, "LCM log (from --record or lcm-logger)")->required();
      cmd.add_option("--csv", o->csv, "Output folder")->required();
      cmd.add_option("--scenario", o->scenario, "Scenario whose message types decode the log");
      cmd.add_option("--messages", o->messages, "Message definitions (.lcm) that decode the log");
      return [o] {
        TypeRegistry types;
        if (!o->scenario.empty()) types = load_scenario(o->scenario).types;
        for (const auto& m : o->messages) types.parse_file(m);
        if (o->scenario.empty() && o->messages.empty())
          throw InputError("give --scenario or --messages so the log's messages can be decoded");
        types.validate();
        const auto s = export_log_csv(o->log, types, o->csv);
        for (const auto& [ch, n] : s.skipped) spdlog::warn("channel {}: {} messages of an unknown type skipped", ch, n);
        return json{{"rows", s.rows}, {"skipped", s.skipped}, {"out", o->csv.string()}};
      };
    },
    .order = 30});

struct ReferenceOptions {
  fs::path scenario, csv;
};

const bool reference_cmd = register_command({
    .path = {"couple", "reference"},
    .description = "The monolithic reference: the same model functions in one loop, no messaging",
    .setup = [](CLI::App& cmd) -> Action {
      auto o = std::make_shared<ReferenceOptions>();
      cmd.add_option("scenario", o->scenario, "Scenario (YAML)")->required();
      cmd.add_option("--csv", o->csv, "Write one CSV per channel here")->required();
      return [o] {
        const ScenarioConfig sc = load_scenario(o->scenario);
        const auto t0 = std::chrono::steady_clock::now();
        const auto rec = run_monolithic(sc);
        const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        fs::create_directories(o->csv);
        json rows = json::object();
        for (const auto& [ch, steps] : rec) {
          std::vector<json> r;
          for (const auto& [n, v] : steps)
            if (n >= 0) r.push_back(v);
          write_csv(o->csv / (ch + ".csv"), r);
          rows[ch] = r.size();
        }
        return json{{"rows", rows}, {"seconds", s}, {"out", o->csv.string()}};
      };
    },
    .order = 40});

struct PlotOptions {
  std::vector<fs::path> logs;
  fs::path scenario, out;
  std::vector<std::string> labels;
  std::vector<double> limits;
  std::string limit_member;
};

const bool plot_cmd = register_command({
    .path = {"couple", "plot"},
    .description = "PNG plot of every numeric member of every channel, one curve per log",
    .setup = [](CLI::App& cmd) -> Action {
      auto o = std::make_shared<PlotOptions>();
      cmd.add_option("logs", o->logs, "LCM logs (e.g. with and without control)")->required();
      cmd.add_option("--scenario", o->scenario, "Scenario whose message types and time steps apply")->required();
      cmd.add_option("--out", o->out, "PNG file")->required();
      cmd.add_option("--labels", o->labels, "Curve labels, one per log (default: file names)");
      cmd.add_option("--limit", o->limit_member, "Draw +-LIMIT lines on this member, e.g. --limit A=1.5");
      return [o] {
        const ScenarioConfig sc = load_scenario(o->scenario);
        std::map<std::string, double> dt;
        for (const auto& m : sc.models)
          for (const auto& p : m.publish) dt[p.channel] = m.dt;
        std::string lim_member;
        double lim = 0;
        if (!o->limit_member.empty()) {
          const auto eq = o->limit_member.find('=');
          if (eq == std::string::npos) throw InputError("--limit: expected MEMBER=VALUE, got '" + o->limit_member + "'");
          lim_member = o->limit_member.substr(0, eq);
          lim = std::stod(o->limit_member.substr(eq + 1));
        }
        const int colors[][3] = {{150, 150, 150}, {20, 90, 200}, {200, 60, 20}, {20, 150, 60}};
        std::map<std::string, Panel> panels;  // "CHANNEL.member"
        std::vector<std::string> order;
        for (std::size_t i = 0; i < o->logs.size(); ++i) {
          const auto channels = read_log_channels(o->logs[i], sc.types);
          for (const auto& [ch, steps] : channels) {
            if (steps.empty()) continue;
            for (const auto& [member, v] : steps.begin()->second.items()) {
              if (member == kStepField || !v.is_number()) continue;
              const std::string key = ch + "." + member;
              if (!panels.count(key)) {
                order.push_back(key);
                panels[key].title = key;
                if (member == lim_member) panels[key].limits = {-lim, lim};
              }
              Curve c;
              c.label = i < o->labels.size() ? o->labels[i] : o->logs[i].filename().string();
              c.y = member_series(steps, member);
              for (std::size_t k = 0; k < c.y.size(); ++k) c.x.push_back(static_cast<double>(k) * dt[ch]);
              c.r = colors[i % 4][0];
              c.g = colors[i % 4][1];
              c.b = colors[i % 4][2];
              panels[key].curves.push_back(std::move(c));
            }
          }
        }
        std::vector<Panel> list;
        for (const auto& k : order) list.push_back(panels[k]);
        if (list.empty()) throw InputError("nothing to plot: no numeric members in the logs' known channels");
        plot_panels(list, "t [s]", o->out);
        return json{{"out", o->out.string()}, {"panels", order}};
      };
    },
    .order = 45});

struct SpyOptions {
  std::string url = "udpm://239.255.76.67:7667?ttl=0";
  fs::path scenario;
  double duration = 0;
};

const bool spy_cmd = register_command({
    .path = {"couple", "spy"},
    .description = "Show live channels: messages, rate, last step, model status",
    .setup = [](CLI::App& cmd) -> Action {
      auto o = std::make_shared<SpyOptions>();
      auto* url_opt = cmd.add_option("--url", o->url, "Transport URL (udpm://..., nats://HOST:PORT)")->capture_default_str();
      cmd.add_option("--scenario", o->scenario, "Scenario (its transport and message types)");
      cmd.add_option("--duration", o->duration, "Stop after this many seconds (default: until Ctrl-C)");
      return [o, url_opt] {
        TypeRegistry types;
        if (!o->scenario.empty()) {
          auto sc = load_scenario(o->scenario);
          if (url_opt->count() == 0) o->url = sc.transport;  // an explicit --url wins (e.g. a launched mediator)
          types = std::move(sc.types);
        }
        add_builtin_types(types);
        std::map<uint64_t, std::string> by_fp;
        for (const auto& n : types.names()) by_fp[types.fingerprint(n)] = n;
        struct Chan {
          int64_t count = 0, last_step = -2;
          std::string type;
        };
        std::map<std::string, Chan> chans;
        std::map<std::string, ModelStatus> models;
        auto tr = make_transport(o->url);
        tr->subscribe("", [&](const std::string& ch, const uint8_t* d, std::size_t n) {
          auto& c = chans[ch];
          ++c.count;
          auto it = by_fp.find(peek_fingerprint(d, n));
          if (it == by_fp.end()) return;
          c.type = it->second;
          try {
            if (is_status_channel(ch)) {
              auto s = decode_status(types, d, n);
              models[s.model] = s;
            } else if (types.get(it->second).member(kStepField)) {
              c.last_step = std::max(c.last_step, LcmCodec(types, it->second).read_int64(d, n, kStepField));
            }
          } catch (const InputError&) {
          }
        });
        install_stop_signals();
        // Scripts wait for this line before they start the models they want to watch.
        spdlog::info("couple spy: listening on {}", o->url);
        const auto start = std::chrono::steady_clock::now();
        auto last_print = start;
        std::map<std::string, int64_t> prev;
        while (!stop_flag()) {
          tr->handle(100);
          const auto now = std::chrono::steady_clock::now();
          const double elapsed = std::chrono::duration<double>(now - start).count();
          if (now - last_print >= std::chrono::seconds(1)) {
            const double dt = std::chrono::duration<double>(now - last_print).count();
            std::string out = isatty(2) ? "\033[2J\033[H" : "";
            out += fmt::format("{:<24} {:<24} {:>10} {:>10} {:>10}\n", "channel", "type", "messages", "per s", "step");
            for (const auto& [ch, c] : chans)
              out += fmt::format("{:<24} {:<24} {:>10} {:>10.0f} {:>10}\n", ch, c.type, c.count,
                                 static_cast<double>(c.count - prev[ch]) / dt, c.last_step >= -1 ? std::to_string(c.last_step) : "");
            for (const auto& [m, s] : models)
              out += fmt::format("model {:<18} step {}/{} granted {:g} s {}{}\n", m, s.step, s.steps, s.granted,
                                 state_name(s.state),
                                 s.waiting.empty() ? "" : " waits for " + s.waiting[0].first + " step " + std::to_string(s.waiting[0].second));
            std::fputs(out.c_str(), stderr);
            for (const auto& [ch, c] : chans) prev[ch] = c.count;
            last_print = now;
          }
          if (o->duration > 0 && elapsed >= o->duration) break;
        }
        json j = json::object();
        for (const auto& [ch, c] : chans) j[ch] = {{"messages", c.count}, {"type", c.type}, {"last_step", c.last_step}};
        json jm = json::object();
        for (const auto& [m, s] : models)  // granted: null when unbounded (a model without inputs)
          jm[m] = {{"step", s.step}, {"steps", s.steps}, {"state", state_name(s.state)},
                   {"granted", std::isfinite(s.granted) ? json(s.granted) : json(nullptr)}};
        return json{{"channels", j}, {"models", jm}};
      };
    },
    .order = 50});

}  // namespace
}  // namespace builtscene::app
