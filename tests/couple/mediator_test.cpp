// End-to-end runs over the mediator (a NATS server), every model in its own process, as
// a user runs them. The launcher's nats-server picks its own free port and keeps its
// files under TMPDIR, which each test points at its own folder: parallel test processes
// cannot collide, and pgrep on that folder finds anything left behind (server included).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include <regex>
#include <set>

#include "couple/lcm_codec.hpp"
#include "couple/lcm_log.hpp"
#include "couple/model_config.hpp"
#include "couple/monolithic.hpp"
#include "couple/status.hpp"
#include "test_util.hpp"

using namespace builtscene::couple;
using nlohmann::json;

namespace {

using builtscene::testing::shell_quote;

const std::string kBin = shell_quote(BUILTSCENE_BINARY);

double rel(double a, double b) { return a == b ? 0 : std::abs(a - b) / std::max(std::abs(a), std::abs(b)); }

// The largest relative difference between a recorded run and the monolithic reference,
// over every member of every step of every channel (all steps must be there).
double worst_difference(const std::filesystem::path& log, const std::string& scenario, std::size_t* compared) {
  const ScenarioConfig sc = load_scenario(scenario);
  auto ref = run_monolithic(sc);
  auto got = couple_test::read_log(log, sc);
  double worst = 0;
  *compared = 0;
  for (const std::string ch : {"WIND", "STRUCTURE", "CONTROL"}) {
    EXPECT_EQ(got[ch].size(), 6000u) << ch;
    for (const auto& [n, v] : ref[ch]) {
      if (n < 0) continue;
      if (!got[ch].count(n)) return INFINITY;
      for (const auto& [k, x] : v.items())
        if (k != "step") {
          worst = std::max(worst, rel(x.get<double>(), got[ch][n][k].get<double>()));
          ++*compared;
        }
    }
  }
  return worst;
}

// HLA conformance from the recorded log: no model receives a message stamped earlier than
// a time it was already granted. The log is in the order the (single) server delivered
// to the recorder, which keeps causality: a message a model had received before it
// reported a grant precedes that report. Only first copies count (the wrapper may
// re-send). Stamps are computed here from the configs: (s + lag) * dt_P + lookahead_P.
struct Conformance {
  std::size_t checked = 0, violations = 0;
  std::string first_violation;
  std::map<std::string, double> final_granted;
};
Conformance check_grants(const std::filesystem::path& log, const ScenarioConfig& sc) {
  struct Reader {
    std::string model;
    double dt, lookahead;  // of the producer
    int lag;
  };
  std::map<std::string, std::vector<Reader>> readers;  // channel -> consumers
  std::map<std::string, std::string> type_of;
  for (const auto& p : sc.models)
    for (const auto& pub : p.publish)
      type_of[pub.channel] = pub.type;
  for (const auto& p : sc.models)
    for (const auto& pub : p.publish)
      for (const auto& m : sc.models)
        for (const auto& sub : m.subscribe)
          if (sub.channel == pub.channel && m.name != p.name)
            readers[pub.channel].push_back({m.name, p.dt, p.lookahead, sub.lag});
  TypeRegistry types = sc.types;
  add_builtin_types(types);
  Conformance c;
  std::map<std::string, double> granted;
  std::set<std::pair<std::string, int64_t>> seen;
  LcmLogReader r(log);
  while (auto e = r.next()) {
    if (is_status_channel(e->channel)) {
      const auto s = decode_status(types, e->data.data(), e->data.size());
      granted[s.model] = std::max(granted[s.model], s.granted);
      continue;
    }
    auto it = readers.find(e->channel);
    if (it == readers.end()) continue;
    const int64_t step = LcmCodec(types, type_of.at(e->channel)).read_int64(e->data.data(), e->data.size(), "step");
    if (!seen.insert({e->channel, step}).second) continue;  // a re-sent copy
    for (const auto& rd : it->second) {
      const double stamp = static_cast<double>(step + rd.lag) * rd.dt + rd.lookahead;
      ++c.checked;
      if (granted.count(rd.model) && stamp < granted[rd.model] - 1e-9 * rd.dt) {
        if (c.violations++ == 0)
          c.first_violation = rd.model + " was granted " + std::to_string(granted[rd.model]) + " s, then got " +
                              e->channel + " step " + std::to_string(step) + " stamped " + std::to_string(stamp);
      }
    }
  }
  c.final_granted = granted;
  return c;
}

// Runs `cmd` with TMPDIR in `dir`; braces keep the caller's stdout redirection apart
// from run()'s 2>&1.
std::string in_tmp(const std::filesystem::path& dir, const std::string& cmd) {
  return "{ TMPDIR=" + shell_quote(dir) + " " + cmd + "; }";
}

// Runs a multi-line shell script (run() redirects only a single command's stderr).
couple_test::RunResult run_script(const std::filesystem::path& dir, const std::string& script) {
  couple_test::write(dir / "run.sh", script);
  return couple_test::run("sh " + shell_quote(dir / "run.sh"));
}

}  // namespace

TEST(Mediator, ExampleOverALaunchedServerEqualsTheMonolithicReference) {
  const auto dir = couple_test::temp_dir("mediator_example");
  const std::string scenario = couple_test::kExample + "/scenario-mediator.yaml";
  const auto r = couple_test::run(in_tmp(dir, kBin + " couple launch " + shell_quote(scenario) + " --record " +
                                                  shell_quote(dir / "run.lcmlog") + " --json > " +
                                                  shell_quote(dir / "out.json")));
  ASSERT_EQ(r.code, 0) << r.out;
  const json summary = json::parse(std::ifstream(dir / "out.json"));
  EXPECT_EQ(summary["steps"], 6000);
  EXPECT_EQ(summary["models"]["structure"], 6000);
  EXPECT_EQ(summary["transport"].get<std::string>().rfind("nats://127.0.0.1:", 0), 0u) << summary.dump();
  EXPECT_GT(summary["mediator_cpu_seconds"].get<double>(), 0) << summary.dump();
  std::size_t compared = 0;
  const double worst = worst_difference(dir / "run.lcmlog", scenario, &compared);
  EXPECT_EQ(compared, 6000u * 6);
  EXPECT_LE(worst, 1e-12);
  // Time management: conformance, and the cycles ran to the end (no deadlock): every
  // model with inputs was finally granted past its last step.
  const auto conf = check_grants(dir / "run.lcmlog", load_scenario(scenario));
  EXPECT_EQ(conf.violations, 0u) << conf.first_violation;
  EXPECT_EQ(conf.checked, 6000u * 4);  // WIND -> structure, controller; CONTROL -> structure; STRUCTURE -> controller
  EXPECT_GE(conf.final_granted.at("structure"), 59.99 - 1e-9);
  EXPECT_GE(conf.final_granted.at("controller"), 59.99 - 1e-9);
  EXPECT_TRUE(std::isinf(conf.final_granted.at("wind")));
  std::printf("mediator vs monolithic: max relative difference %.3g, %.0f steps/s, nats-server CPU %.2f s\n", worst,
              summary["steps_per_second"].get<double>(), summary["mediator_cpu_seconds"].get<double>());
  // The server was stopped and its folder (JetStream storage) removed.
  EXPECT_EQ(couple_test::left_over(dir), "");
  int server_dirs = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir))
    server_dirs += e.path().filename().string().rfind("builtscene-mediator-", 0) == 0;
  EXPECT_EQ(server_dirs, 0);
}

TEST(Mediator, NatsOptionUsesARunningServer) {
  const auto dir = couple_test::temp_dir("mediator_existing");
  const std::string scenario = couple_test::kExample + "/scenario-mediator.yaml";
  // Our own server on a port it picks; the launcher must use it and leave it running.
  const std::string ports = (dir / "ports").string();
  std::filesystem::create_directories(ports);
  const auto r = run_script(dir,
      "nats-server -a 127.0.0.1 -p -1 --ports_file_dir " + shell_quote(ports) + " -l " +
      shell_quote(dir / "server.log") + " & S=$!\nfor i in $(seq 100); do ls " + shell_quote(ports) +
      "/*.ports >/dev/null 2>&1 && break; sleep 0.1; done\n"
      "URL=$(sed 's/.*\\[\"\\([^\"]*\\)\".*/\\1/' " + shell_quote(ports) + "/*.ports)\n" +
      in_tmp(dir, kBin + " couple launch " + shell_quote(scenario) + " --nats \"$URL?prefix=run1\" --record " +
                      shell_quote(dir / "run.lcmlog") + " --json > " + shell_quote(dir / "out.json")) +
      "\nrc=$?\nkill -0 $S && echo server-still-running\nkill $S\nwait $S\nexit $rc\n");
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("server-still-running"), std::string::npos) << r.out;
  // This server has no JetStream: the run goes on without recovery, and says so.
  EXPECT_NE(r.out.find("running without recovery"), std::string::npos) << r.out;
  const json summary = json::parse(std::ifstream(dir / "out.json"));
  EXPECT_NE(summary["transport"].get<std::string>().find("?prefix=run1"), std::string::npos) << summary.dump();
  EXPECT_FALSE(summary.contains("mediator_cpu_seconds"));  // not started by the launcher
  std::size_t compared = 0;
  EXPECT_LE(worst_difference(dir / "run.lcmlog", scenario, &compared), 1e-12);
  EXPECT_EQ(compared, 6000u * 6);
  EXPECT_EQ(couple_test::left_over(dir), "");
}

TEST(Mediator, CtrlCStopsTheModelsAndTheServer) {
  const auto d = couple_test::temp_dir("mediator_sigint");
  couple_test::write(d / "types.lcm", "package t;\nstruct x_t { int64_t step; double x; }\n");
  couple_test::write(d / "p.py",
                     "import json,sys\nfor line in sys.stdin:\n    r=json.loads(line)\n"
                     "    print(json.dumps({'ok':True} if 'init' in r else {'outputs':{'X':{'x':r['t']}}}), flush=True)\n");
  couple_test::write(d / "c.py",
                     "import json,sys\nfor line in sys.stdin:\n    r=json.loads(line)\n"
                     "    print(json.dumps({'ok':True} if 'init' in r else {'outputs':{'Y':{'x':r['t']}}}), flush=True)\n");
  const std::string head = "dt: 0.1\nend_time: 100000\nmessages: types.lcm\n";
  couple_test::write(d / "p.yaml", "name: p\n" + head + "command: [python3, " + (d / "p.py").string() +
                                       "]\npublish:\n  - {channel: X, type: t.x_t}\n");
  couple_test::write(d / "c.yaml", "name: c\n" + head + "command: [python3, " + (d / "c.py").string() +
                                       "]\nsubscribe:\n  - {channel: X, type: t.x_t}\npublish:\n  - {channel: Y, type: t.x_t}\n");
  couple_test::write(d / "scenario.yaml", "name: s\ntransport: mediator\ntimeout: 5\nmodels: [p.yaml, c.yaml]\n");
  const std::string log = (d / "run.lcmlog").string();
  const auto r = run_script(d,
      in_tmp(d, kBin + " couple launch " + shell_quote(d / "scenario.yaml") + " --record " + shell_quote(log)) +
      " & P=$!\nfor i in $(seq 300); do [ $(stat -c %s " + shell_quote(log) +
      " 2>/dev/null || echo 0) -gt 65536 ] && break; sleep 0.1; done\n"
      "kill -INT $P\nwait $P\necho rc=$?\n");
  EXPECT_NE(r.out.find("interrupted"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("rc=1"), std::string::npos) << r.out;
  const ScenarioConfig sc = load_scenario(d / "scenario.yaml");
  auto got = couple_test::read_log(log, sc);
  EXPECT_GT(got["X"].size() + got["Y"].size(), 0u);
  EXPECT_EQ(couple_test::left_over(d), "");  // models and nats-server gone
}

TEST(Mediator, AnUnreachableServerIsAClearError) {
  const auto dir = couple_test::temp_dir("mediator_unreachable");
  // Port 1 on loopback: nothing listens there (tcpmux is never served here).
  const auto r = couple_test::run(kBin + " couple launch " + shell_quote(couple_test::kExample) +
                                  "/scenario-mediator.yaml --nats nats://127.0.0.1:1");
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("cannot connect to the mediator (NATS server) at nats://127.0.0.1:1"), std::string::npos)
      << r.out;
  const auto bad = couple_test::run(kBin + " couple launch " + shell_quote(couple_test::kExample) +
                                    "/scenario-mediator.yaml --nats udpm://239.255.76.67:7667");
  EXPECT_EQ(bad.code, 2) << bad.out;
  EXPECT_NE(bad.out.find("--nats 'udpm://239.255.76.67:7667': expected nats://HOST:PORT"), std::string::npos)
      << bad.out;
}

TEST(Mediator, AStalledModelIsReportedByName) {
  const auto d = couple_test::temp_dir("mediator_stall");
  couple_test::write(d / "types.lcm", "package t;\nstruct x_t { int64_t step; double x; }\n");
  auto py = [](const std::string& out, const std::string& at_step_5) {
    return "import json,sys,time\nfor line in sys.stdin:\n    r=json.loads(line)\n"
           "    if 'init' not in r and r['step']==5:\n        " + at_step_5 + "\n"
           "    print(json.dumps({'ok':True} if 'init' in r else {'outputs':{'" + out + "':{'x':r['t']}}}), flush=True)\n";
  };
  couple_test::write(d / "src.py", py("X", "pass"));
  couple_test::write(d / "sink.py", py("Y", "time.sleep(1000)"));
  couple_test::write(d / "end.py", py("Z", "pass"));
  const std::string head = "dt: 0.1\nend_time: 2\nmessages: types.lcm\n";
  couple_test::write(d / "src.yaml", "name: src\n" + head + "command: [python3, " + (d / "src.py").string() +
                                         "]\npublish:\n  - {channel: X, type: t.x_t}\n");
  couple_test::write(d / "sink.yaml", "name: sink\n" + head + "command: [python3, " + (d / "sink.py").string() +
                                          "]\nsubscribe:\n  - {channel: X, type: t.x_t}\npublish:\n  - {channel: Y, type: t.x_t}\n");
  couple_test::write(d / "end.yaml", "name: end\n" + head + "command: [python3, " + (d / "end.py").string() +
                                         "]\nsubscribe:\n  - {channel: Y, type: t.x_t}\npublish:\n  - {channel: Z, type: t.x_t}\n");
  // The stall timeout counts from the launch: 2 s was shorter than three python3 start-ups
  // (through a pyenv shim) on a loaded 2-core machine, and the report then came at step 0,
  // before 'sink' had blocked (one clean-clone CI run, 2026-12-01).
  couple_test::write(d / "scenario.yaml", "name: p\ntransport: mediator\ntimeout: 5\nmodels: [src.yaml, sink.yaml, end.yaml]\n");
  const auto r = couple_test::run(in_tmp(d, kBin + " couple launch " + shell_quote(d / "scenario.yaml")));
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("no model advanced for 5 s"), std::string::npos) << r.out;
  // 'sink' is stuck computing step 5; 'end' waits for a step of it (5, or the one of
  // its last status report: a wrapper reports every 32 steps or every 20 ms blocked).
  EXPECT_TRUE(std::regex_search(
      r.out, std::regex("model 'end' at step ([0-5]) waits for channel 'Y' step \\1 \\(published by model 'sink'\\)")))
      << r.out;
  EXPECT_EQ(couple_test::left_over(d), "");
}

TEST(Mediator, KilledModelsAreRestartedAndTheResultsAreBitIdentical) {
  const auto dir = couple_test::temp_dir("mediator_kill");
  const std::string scenario = couple_test::kExample + "/scenario-mediator.yaml";
  const std::string launch = kBin + " couple launch " + shell_quote(scenario);
  // The uninterrupted run, then one where the structure is killed at step 3000 and the
  // controller at step 4500 (each resumes by replaying its inputs from JetStream).
  const auto a = run_script(dir, in_tmp(dir, launch + " --record " + shell_quote(dir / "a.lcmlog") + " > /dev/null") +
                                     "\n" + kBin + " couple export " + shell_quote(dir / "a.lcmlog") + " --scenario " +
                                     shell_quote(scenario) + " --csv " + shell_quote(dir / "a") + " > /dev/null\n");
  ASSERT_EQ(a.code, 0) << a.out;
  const auto b = run_script(dir, in_tmp(dir, launch + " --kill structure@3000 --kill controller@4500 --record " +
                                                 shell_quote(dir / "b.lcmlog") + " --json > " +
                                                 shell_quote(dir / "b.json")) +
                                     "\n" + kBin + " couple export " + shell_quote(dir / "b.lcmlog") + " --scenario " +
                                     shell_quote(scenario) + " --csv " + shell_quote(dir / "b") + " > /dev/null\n");
  ASSERT_EQ(b.code, 0) << b.out;
  EXPECT_NE(b.out.find("model 'structure' was killed by signal Killed at step"), std::string::npos) << b.out;
  EXPECT_NE(b.out.find("model 'controller' was killed by signal Killed at step"), std::string::npos) << b.out;
  const json summary = json::parse(std::ifstream(dir / "b.json"));
  EXPECT_EQ(summary["restarts"]["structure"], 1) << summary.dump();
  EXPECT_EQ(summary["restarts"]["controller"], 1) << summary.dump();
  EXPECT_EQ(summary["models"]["structure"], 6000);
  for (const std::string ch : {"WIND", "STRUCTURE", "CONTROL"}) {
    const auto fa = dir / "a" / (ch + ".csv"), fb = dir / "b" / (ch + ".csv");
    ASSERT_TRUE(std::filesystem::exists(fb)) << fb;
    EXPECT_EQ(couple_test::run("wc -l < " + shell_quote(fa)).out, "6001\n") << ch;  // header + 6000 steps
    EXPECT_EQ(couple_test::run("cmp " + shell_quote(fa) + " " + shell_quote(fb)).code, 0) << ch << " differs";
  }
  // And the interrupted run still equals the monolithic reference.
  std::size_t compared = 0;
  EXPECT_LE(worst_difference(dir / "b.lcmlog", scenario, &compared), 1e-12);
  EXPECT_EQ(couple_test::left_over(dir), "");
}

TEST(Mediator, BadKillOptionsAreClearErrors) {
  const std::string launch = kBin + " couple launch " + shell_quote(couple_test::kExample);
  auto r = couple_test::run(launch + "/scenario-mediator.yaml --kill nobody@5");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("no model named 'nobody'"), std::string::npos) << r.out;
  r = couple_test::run(launch + "/scenario-mediator.yaml --kill structure@soon");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--kill 'structure@soon': expected MODEL@STEP"), std::string::npos) << r.out;
  r = couple_test::run(launch + "/scenario-mediator.yaml --kill structure@6000");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("the step must be in 0..5999"), std::string::npos) << r.out;
  r = couple_test::run(launch + "/scenario.yaml --kill structure@5");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--kill needs the mediator"), std::string::npos) << r.out;
}

TEST(Mediator, SeveralModelsPerProcessEqualTheMonolithicReferenceAndRestartTogether) {
  // Two processes: wind + structure (threads of one), controller. The structure's kill at
  // step 3000 takes the wind with it (one process); both restart and resume.
  const auto dir = couple_test::temp_dir("mediator_per_process");
  const std::string scenario = couple_test::kExample + "/scenario-mediator.yaml";
  const auto r = couple_test::run(in_tmp(dir, kBin + " couple launch " + shell_quote(scenario) +
                                                  " --models-per-process 2 --kill structure@3000 --record " +
                                                  shell_quote(dir / "run.lcmlog") + " --json > " +
                                                  shell_quote(dir / "out.json")));
  ASSERT_EQ(r.code, 0) << r.out;
  EXPECT_NE(r.out.find("model 'wind' (its process also hosts 'structure') was killed by signal Killed"), std::string::npos)
      << r.out;
  const json summary = json::parse(std::ifstream(dir / "out.json"));
  EXPECT_EQ(summary["restarts"]["structure"], 1) << summary.dump();
  EXPECT_EQ(summary["restarts"]["wind"], 1) << summary.dump();
  EXPECT_FALSE(summary["restarts"].contains("controller")) << summary.dump();
  std::size_t compared = 0;
  EXPECT_LE(worst_difference(dir / "run.lcmlog", scenario, &compared), 1e-12);
  EXPECT_EQ(compared, 6000u * 6);
  EXPECT_EQ(couple_test::left_over(dir), "");
  // A bad value is a clear error naming the option.
  const auto bad = couple_test::run(kBin + " couple launch " + shell_quote(scenario) + " --models-per-process 0");
  EXPECT_EQ(bad.code, 2) << bad.out;
  EXPECT_NE(bad.out.find("--models-per-process"), std::string::npos) << bad.out;
}
