// End-to-end runs over LCM udpm with every model in its own process, as a user runs
// them (`builtscene couple launch`). Each test runs in a private network namespace
// (unshare -n, as root) whose loopback carries the multicast route LCM needs, so the
// tests work on a fresh machine without one and parallel runs cannot hear each other.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <regex>
#include <nlohmann/json.hpp>

#include "couple/lcm_codec.hpp"
#include "couple/lcm_log.hpp"
#include "couple/model_config.hpp"
#include "couple/monolithic.hpp"
#include "test_util.hpp"

using namespace builtscene::couple;
using nlohmann::json;

namespace {

using builtscene::testing::shell_quote;

const std::string kBin = shell_quote(BUILTSCENE_BINARY);

using couple_test::left_over;
using couple_test::read_log;

double rel(double a, double b) { return a == b ? 0 : std::abs(a - b) / std::max(std::abs(a), std::abs(b)); }

}  // namespace

TEST(Udpm, ExampleRunEqualsTheMonolithicReferenceWithAndWithoutControl) {
  for (const std::string file : {"scenario.yaml", "scenario-no-control.yaml"}) {
    const auto dir = couple_test::temp_dir("udpm_example");
    const std::string scenario = couple_test::kExample + "/" + file;
    UDPM_OR_SKIP(r, kBin + " couple launch " + shell_quote(scenario) + " --record " + shell_quote(dir / "run.lcmlog") +
                        " --json > " + shell_quote(dir / "out.json"));
    ASSERT_EQ(r->code, 0) << r->out;
    const json summary = json::parse(std::ifstream(dir / "out.json"));
    EXPECT_EQ(summary["steps"], 6000);
    EXPECT_EQ(summary["models"]["structure"], 6000);
    EXPECT_GT(summary["steps_per_second"].get<double>(), 0);

    const ScenarioConfig sc = load_scenario(scenario);
    auto ref = run_monolithic(sc);
    auto got = read_log(dir / "run.lcmlog", sc);
    double worst = 0, max_a = 0;
    std::size_t compared = 0;
    for (const std::string ch : {"WIND", "STRUCTURE", "CONTROL"}) {
      ASSERT_EQ(got[ch].size(), 6000u) << ch;
      for (const auto& [n, v] : ref[ch]) {
        if (n < 0) continue;
        for (const auto& [k, x] : v.items())
          if (k != "step") {
            worst = std::max(worst, rel(x.get<double>(), got[ch][n][k].get<double>()));
            ++compared;
          }
        if (ch == "STRUCTURE") max_a = std::max(max_a, std::abs(got[ch][n]["A"].get<double>()));
      }
    }
    EXPECT_EQ(compared, 6000u * 6);
    EXPECT_LE(worst, 1e-12) << file;
    if (file == "scenario.yaml")
      EXPECT_LE(max_a, 1.5 + 1e-9);
    else
      EXPECT_GT(max_a, 1.5);
    std::printf("%s: max |A| = %.6f m/s^2, distributed vs monolithic max relative difference %.3g\n", file.c_str(),
                max_a, worst);
  }
}

TEST(Udpm, LcmLogplayerReplaysTheRecordedLogToLcmLogger) {
  const auto dir = couple_test::temp_dir("replay");
  const std::string log = (dir / "run.lcmlog").string(), replayed = (dir / "replayed.lcmlog").string();
  UDPM_OR_SKIP(r, kBin + " couple launch " + shell_quote(couple_test::kExample + "/scenario.yaml") + " --record " +
                      shell_quote(log) + " --json > /dev/null\n"
                      "lcm-logger -f " + shell_quote(replayed) + " & L=$!\nsleep 0.5\n"
                      "lcm-logplayer -s 0.25 -e 'WIND|STRUCTURE|CONTROL' " + shell_quote(log) +
                      "\nsleep 0.5\nkill -INT $L\nwait $L || true\n");
  ASSERT_EQ(r->code, 0) << r->out;
  const ScenarioConfig sc = load_scenario(couple_test::kExample + "/scenario.yaml");
  auto original = read_log(log, sc);
  auto replay = read_log(replayed, sc);  // written by LCM's own logger
  // lcm-logplayer must read our log and publish its messages unchanged. UDP drops some of
  // the ~18,000 it sends in 4 s when lcm-logger is short of CPU (LCM's tools do not
  // retransmit; on an idle machine 99.8 % arrive), so at least half must arrive and
  // every one that does must be the recorded one, member for member.
  for (const std::string ch : {"WIND", "STRUCTURE", "CONTROL"}) {
    EXPECT_EQ(original[ch].size(), 6000u) << ch;
    EXPECT_GE(replay[ch].size(), 0.5 * static_cast<double>(original[ch].size())) << ch;
    std::printf("%s: %zu of %zu messages replayed\n", ch.c_str(), replay[ch].size(), original[ch].size());
    std::size_t equal = 0;
    for (const auto& [n, v] : replay[ch]) equal += original[ch].count(n) && original[ch][n] == v;
    EXPECT_EQ(equal, replay[ch].size()) << ch;
  }
}

namespace {
std::filesystem::path python_scenario(const std::string& tag, const std::string& at_step_5, double end_time = 2) {
  const auto d = couple_test::temp_dir(tag);
  couple_test::write(d / "types.lcm", "package t;\nstruct x_t { int64_t step; double x; }\n");
  auto py = [](const std::string& out, const std::string& hook) {
    return "import json,sys,time\nfor line in sys.stdin:\n    r=json.loads(line)\n"
           "    if 'init' not in r and r['step']==5:\n        " + hook + "\n"
           "    out={'ok':True} if 'init' in r else {'outputs':{'" + out + "':{'x':r['t']}}}\n"
           "    print(json.dumps(out), flush=True)\n";
  };
  couple_test::write(d / "src.py", py("X", "pass"));
  couple_test::write(d / "sink.py", py("Y", at_step_5));
  couple_test::write(d / "end.py", py("Z", "pass"));
  const std::string head = "dt: 0.1\nend_time: " + std::to_string(end_time) + "\nmessages: types.lcm\n";
  couple_test::write(d / "src.yaml", "name: src\n" + head + "command: [python3, " + (d / "src.py").string() + "]\npublish:\n  - {channel: X, type: t.x_t}\n");
  couple_test::write(d / "sink.yaml", "name: sink\n" + head + "command: [python3, " + (d / "sink.py").string() + "]\n"
                                      "subscribe:\n  - {channel: X, type: t.x_t}\npublish:\n  - {channel: Y, type: t.x_t}\n");
  couple_test::write(d / "end.yaml", "name: end\n" + head + "command: [python3, " + (d / "end.py").string() + "]\n"
                                     "subscribe:\n  - {channel: Y, type: t.x_t}\npublish:\n  - {channel: Z, type: t.x_t}\n");
  couple_test::write(d / "scenario.yaml", "name: p\ntransport: udpm://239.255.76.67:7667?ttl=0\ntimeout: 2\n"
                                          "models: [src.yaml, sink.yaml, end.yaml]\n");
  return d;
}
}  // namespace

TEST(Udpm, AModelProcessThatExitsStopsTheOthersAndTheLogIsKept) {
  const auto d = python_scenario("exit", "sys.exit(3)");
  UDPM_OR_SKIP(r, kBin + " couple launch " + shell_quote(d / "scenario.yaml") + " --record " +
                      shell_quote(d / "run.lcmlog"));
  EXPECT_EQ(r->code, 1) << r->out;
  EXPECT_NE(r->out.find("model 'sink' (external program python3) exited with code 3 at step 5"), std::string::npos)
      << r->out;
  EXPECT_NE(r->out.find("the other models were stopped"), std::string::npos) << r->out;
  const ScenarioConfig sc = load_scenario(d / "scenario.yaml");
  EXPECT_EQ(read_log(d / "run.lcmlog", sc)["Y"].size(), 5u);
  EXPECT_EQ(left_over(d), "");  // no model process left
}

TEST(Udpm, AStalledModelIsNamedWithTheChannelAndStepOthersWaitFor) {
  const auto d = python_scenario("stall", "time.sleep(1000)");
  UDPM_OR_SKIP(r, kBin + " couple launch " + shell_quote(d / "scenario.yaml") + " --record " +
                      shell_quote(d / "run.lcmlog"));
  EXPECT_EQ(r->code, 1) << r->out;
  EXPECT_NE(r->out.find("no model advanced for 2 s"), std::string::npos) << r->out;
  // 'end' waits for the step 'sink' never delivers (5, or an earlier one it missed while
  // starting up and that the stuck 'sink' cannot re-send).
  EXPECT_TRUE(std::regex_search(
      r->out, std::regex("model 'end' at step ([0-5]) waits for channel 'Y' step \\1 \\(published by model 'sink'\\)")))
      << r->out;
  EXPECT_TRUE(std::filesystem::file_size(d / "run.lcmlog") > 0);
  EXPECT_EQ(left_over(d), "");
}

TEST(Udpm, CtrlCStopsEveryModelCleanlyAndKeepsTheLog) {
  const auto d = python_scenario("sigint", "pass", 100000);  // far too long to finish
  UDPM_OR_SKIP(r, kBin + " couple launch " + shell_quote(d / "scenario.yaml") + " --record " +
                      shell_quote(d / "run.lcmlog") + " & P=$!\n"
                      // interrupt once the run is well under way (the log has grown)
                      "for i in $(seq 300); do [ $(stat -c %s " + shell_quote(d / "run.lcmlog") +
                      " 2>/dev/null || echo 0) -gt 262144 ] && break; sleep 0.1; done\n"
                      "kill -INT $P\nset +e\nwait $P\necho rc=$?\n");
  EXPECT_NE(r->out.find("interrupted"), std::string::npos) << r->out;
  EXPECT_NE(r->out.find("rc=1"), std::string::npos) << r->out;
  // The log is kept and readable, with the data recorded so far (on a loaded machine the
  // models may still be starting when the interrupt comes, so any data channel counts).
  const ScenarioConfig sc = load_scenario(d / "scenario.yaml");
  auto log = read_log(d / "run.lcmlog", sc);
  EXPECT_GT(log["X"].size() + log["Y"].size() + log["Z"].size(), 0u);
  EXPECT_EQ(left_over(d), "");
}

TEST(Udpm, ALauncherKilledBySigkillTakesEveryModelProcessWithIt) {
  // SIGKILL gives the launcher no chance to stop its models; the kernel must (each model
  // process asks for SIGTERM when its parent dies, each external program for SIGKILL).
  const auto d = python_scenario("sigkill", "pass", 100000);  // far too long to finish
  const std::string pattern = shell_quote("[" + d.string().substr(0, 1) + "]" + d.string().substr(1));
  UDPM_OR_SKIP(r, kBin + " couple launch " + shell_quote(d / "scenario.yaml") + " --record " +
                      shell_quote(d / "run.lcmlog") + " > " + shell_quote(d / "launch.log") + " 2>&1 & P=$!\n"
                      // (its output goes to a file: orphans holding the test's pipe would hang the test)
                      "for i in $(seq 300); do [ $(stat -c %s " + shell_quote(d / "run.lcmlog") +
                      " 2>/dev/null || echo 0) -gt 65536 ] && break; sleep 0.1; done\n"
                      "echo models=$(pgrep -fc -- " + pattern + ")\n"
                      "kill -KILL $P\nset +e\nwait $P\n"
                      // the models get SIGTERM at once; give a loaded machine 20 s to let them exit
                      "for i in $(seq 200); do pgrep -f -- " + pattern + " >/dev/null || break; sleep 0.1; done\n");
  // The launcher, its 3 run-model processes and their 3 python programs were running.
  EXPECT_NE(r->out.find("models=7"), std::string::npos) << r->out;
  EXPECT_EQ(left_over(d), "");
  couple_test::run("pkill -KILL -f -- " + pattern);  // a failed run must not leave them behind
}

TEST(Udpm, SpyShowsTheLiveChannelsAndSteps) {
  const auto dir = couple_test::temp_dir("spy");
  const std::string scenario = couple_test::kExample + "/scenario.yaml";
  const std::string err = (dir / "spy.err").string();
  // The spy runs until Ctrl-C; the models start once it says it is listening.
  UDPM_OR_SKIP(r, kBin + " couple spy --scenario " + shell_quote(scenario) + " --duration 120 --json > " +
                      shell_quote(dir / "spy.json") + " 2> " + shell_quote(err) + " & S=$!\n"
                      "for i in $(seq 300); do grep -q listening " + shell_quote(err) + " && break; sleep 0.1; done\n" +
                      kBin + " couple launch " + shell_quote(scenario) + " > /dev/null\nkill -INT $S\nwait $S\n");
  ASSERT_EQ(r->code, 0) << r->out;
  const json spy = json::parse(std::ifstream(dir / "spy.json"));
  // The run publishes steps 0..5999 on each channel. The spy is a plain UDP multicast listener: on a loaded machine the
  // kernel may drop datagrams while it is descheduled, so it must see nearly all of them
  // and the highest step, not necessarily every one.
  for (const std::string ch : {"WIND", "STRUCTURE", "CONTROL"}) {
    EXPECT_GE(spy["channels"][ch]["messages"].get<int>(), 5700) << spy.dump();
    EXPECT_GE(spy["channels"][ch]["last_step"].get<int>(), 5990) << spy.dump();
    EXPECT_LE(spy["channels"][ch]["last_step"].get<int>(), 5999) << spy.dump();
  }
  EXPECT_EQ(spy["channels"]["STRUCTURE"]["type"], "wsc.response_t");
}
