// The hybrid platform (the source's Figure 5.4) end to end, every model its own process:
// the building's sub-models (structure, controller) exchange STRUCTURE and CONTROL over
// LCM udpm, the wind reaches them through the mediator. Each test runs in a private
// network namespace (multicast route on its loopback; the launcher's nats-server on
// 127.0.0.1 inside it), so parallel runs cannot hear each other.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "core/errors.hpp"
#include "couple/launcher.hpp"
#include "couple/model_config.hpp"
#include "couple/monolithic.hpp"
#include "test_util.hpp"

using namespace builtscene::couple;
using nlohmann::json;

namespace {

using builtscene::testing::shell_quote;

const std::string kBin = shell_quote(BUILTSCENE_BINARY);
const std::string kScenario = couple_test::kExample + "/scenario-hybrid.yaml";

double rel(double a, double b) { return a == b ? 0 : std::abs(a - b) / std::max(std::abs(a), std::abs(b)); }

// The largest relative difference of `got` against the monolithic reference over every
// member of the steps `got` holds; `missing` counts reference steps `got` lacks.
double worst_difference(std::map<std::string, std::map<int64_t, json>>& got, const std::vector<std::string>& channels,
                        std::size_t* compared, std::size_t* missing) {
  static const auto ref = run_monolithic(load_scenario(kScenario));
  double worst = 0;
  *compared = *missing = 0;
  for (const auto& ch : channels)
    for (const auto& [n, v] : ref.at(ch)) {
      if (n < 0) continue;
      if (!got[ch].count(n)) {
        ++*missing;
        continue;
      }
      for (const auto& [k, x] : v.items())
        if (k != "step") {
          worst = std::max(worst, rel(x.get<double>(), got[ch][n][k].get<double>()));
          ++*compared;
        }
    }
  return worst;
}

}  // namespace

TEST(Hybrid, ExampleOverLcmAndTheMediatorEqualsTheMonolithicReference) {
  const auto dir = couple_test::temp_dir("hybrid_example");
  UDPM_OR_SKIP(r, "TMPDIR=" + shell_quote(dir) + " " + kBin + " couple launch " + shell_quote(kScenario) +
                      " --record " + shell_quote(dir / "run.lcmlog") + " --json > " + shell_quote(dir / "out.json"));
  ASSERT_EQ(r->code, 0) << r->out;
  const json summary = json::parse(std::ifstream(dir / "out.json"));
  EXPECT_EQ(summary["steps"], 6000);
  EXPECT_EQ(summary["models"]["structure"], 6000);
  EXPECT_EQ(summary["transport"].get<std::string>().rfind("nats://127.0.0.1:", 0), 0u) << summary.dump();
  // The recorder hears the local channels through the bridge; all steps must be there.
  auto got = couple_test::read_log(dir / "run.lcmlog", load_scenario(kScenario));
  std::size_t compared = 0, missing = 0;
  const double worst = worst_difference(got, {"WIND", "STRUCTURE", "CONTROL"}, &compared, &missing);
  EXPECT_EQ(missing, 0u);
  EXPECT_EQ(compared, 6000u * 6);
  EXPECT_LE(worst, 1e-12);
  std::printf("hybrid vs monolithic: max relative difference %.3g, %.0f steps/s, nats-server CPU %.2f s\n", worst,
              summary["steps_per_second"].get<double>(), summary["mediator_cpu_seconds"].get<double>());
  EXPECT_EQ(couple_test::left_over(dir), "");
}

TEST(Hybrid, LocalChannelsTravelOnlyOverLcmAndTheOthersThroughTheMediator) {
  // Second tools watch both sides of an unrecorded run: lcm-logger on the building's
  // multicast group (port 7668, group 0), the spy on the mediator (a nats-server with
  // JetStream this script starts on a fixed port: the namespace is private).
  const auto dir = couple_test::temp_dir("hybrid_routes");
  const std::string d = dir.string(), err = d + "/spy.err";
  // Every background process is stopped on any way out (set -e) and keeps no handle on
  // the test's output pipe.
  UDPM_OR_SKIP(r, "nats-server -a 127.0.0.1 -p 4222 -js -sd " + shell_quote(d + "/js") + " -l " +
                  shell_quote(d + "/server.log") + " > /dev/null 2>&1 & N=$!\n"
                  "trap 'kill $N $L $S 2>/dev/null || true' EXIT\n"
                  "for i in $(seq 100); do grep -q 'Server is ready' " + shell_quote(d + "/server.log") +
                  " 2>/dev/null && break; sleep 0.1; done\n"
                  "lcm-logger --lcm-url='udpm://239.255.76.67:7668?ttl=0' -f " + shell_quote(d + "/local.lcmlog") +
                  " > /dev/null 2>&1 & L=$!\n" +
                  kBin + " couple spy --url nats://127.0.0.1:4222 --scenario " + shell_quote(kScenario) +
                  " --duration 120 --json > " + shell_quote(d + "/spy.json") + " 2> " + shell_quote(err) + " & S=$!\n"
                  "for i in $(seq 300); do grep -q listening " + shell_quote(err) +
                  " && break; sleep 0.1; done\nsleep 0.3\n" +
                  kBin + " couple launch " + shell_quote(kScenario) + " --nats nats://127.0.0.1:4222 --json > " +
                  shell_quote(d + "/out.json") + "\n"
                  "sleep 0.5\nkill -INT $S\nwait $S\nkill -INT $L\nwait $L || true\nkill $N\nwait $N || true\n");
  ASSERT_EQ(r->code, 0) << r->out;
  const json spy = json::parse(std::ifstream(dir / "spy.json"));
  // (a few more than 6000: the wrapper re-sends a step a consumer reports waiting for)
  EXPECT_GE(spy["channels"]["WIND"]["messages"].get<int>(), 6000) << spy.dump();
  EXPECT_EQ(spy["channels"]["WIND"]["last_step"].get<int>(), 5999) << spy.dump();
  for (const std::string m : {"wind", "structure", "controller"})
    EXPECT_GT(spy["channels"]["BUILTSCENE_STATUS." + m]["messages"].get<int>(), 0) << spy.dump();
  EXPECT_FALSE(spy["channels"].contains("STRUCTURE")) << spy.dump();
  EXPECT_FALSE(spy["channels"].contains("CONTROL")) << spy.dump();
  // The spy shows each model's granted time: the wind has no inputs (unbounded: null);
  // the building's sub-models were granted past their last step (or, done, unbounded).
  ASSERT_TRUE(spy["models"].contains("wind")) << spy.dump();
  EXPECT_TRUE(spy["models"]["wind"]["granted"].is_null()) << spy.dump();
  for (const std::string m : {"structure", "controller"}) {
    const json g = spy["models"][m]["granted"];
    EXPECT_TRUE(g.is_null() || g.get<double>() >= 59.99 - 1e-9) << m << ": " << spy.dump();
    EXPECT_EQ(spy["models"][m]["step"], 6000) << spy.dump();
  }
  // lcm-logger is a plain UDP listener (no re-sends): on a loaded machine the kernel may
  // drop datagrams while it is descheduled (as in Udpm.LcmLogplayer...), so at least half
  // the steps must be there, each equal to the reference; the wind never appears on LCM.
  auto local = couple_test::read_log(dir / "local.lcmlog", load_scenario(kScenario));
  EXPECT_EQ(local.count("WIND"), 0u);
  EXPECT_GE(local["STRUCTURE"].size(), 3000u);
  EXPECT_GE(local["CONTROL"].size(), 3000u);
  std::size_t compared = 0, missing = 0;
  EXPECT_LE(worst_difference(local, {"STRUCTURE", "CONTROL"}, &compared, &missing), 1e-12);
  EXPECT_EQ(compared, 3 * local["STRUCTURE"].size() + local["CONTROL"].size());  // D, V, A and Pc of each
  EXPECT_EQ(missing, 12000 - local["STRUCTURE"].size() - local["CONTROL"].size());
  std::printf("lcm-logger heard %zu STRUCTURE and %zu CONTROL messages on the local group\n",
              local["STRUCTURE"].size(), local["CONTROL"].size());
  EXPECT_EQ(couple_test::left_over(dir), "");
}

TEST(Hybrid, AKilledSubModelRestartsWithItsGroupAndTheResultsAreIdentical) {
  // The controller reads STRUCTURE over LCM (no history): killed at step 3000 (kill -9),
  // the launcher restarts the whole building (structure too); both replay the wind from
  // the mediator and re-send their local steps to each other. Compared with an
  // uninterrupted run (exported CSVs byte for byte) and the monolithic reference.
  const auto dir = couple_test::temp_dir("hybrid_kill");
  const std::string d = dir.string(),
                    launch = "TMPDIR=" + shell_quote(d) + " " + kBin + " couple launch " + shell_quote(kScenario);
  auto csv = [&](const std::string& tag) {
    return kBin + " couple export " + shell_quote(d + "/" + tag + ".lcmlog") + " --scenario " + shell_quote(kScenario) +
           " --csv " + shell_quote(d + "/" + tag) + " > /dev/null\n";
  };
  UDPM_OR_SKIP(r, launch + " --record " + shell_quote(d + "/a.lcmlog") + " > /dev/null\n" + csv("a") + launch +
                      " --kill controller@3000 --record " + shell_quote(d + "/b.lcmlog") + " --json > " +
                      shell_quote(d + "/b.json") + "\n" + csv("b"));
  ASSERT_EQ(r->code, 0) << r->out;
  EXPECT_NE(r->out.find("model 'controller' was killed by signal Killed at step"), std::string::npos) << r->out;
  EXPECT_NE(r->out.find("restarting its group 'building'"), std::string::npos) << r->out;
  const json summary = json::parse(std::ifstream(dir / "b.json"));
  EXPECT_EQ(summary["restarts"]["controller"], 1) << summary.dump();
  EXPECT_EQ(summary["restarts"]["structure"], 1) << summary.dump();
  EXPECT_FALSE(summary["restarts"].contains("wind")) << summary.dump();
  for (const std::string ch : {"WIND", "STRUCTURE", "CONTROL"}) {
    const auto fa = dir / "a" / (ch + ".csv"), fb = dir / "b" / (ch + ".csv");
    ASSERT_TRUE(std::filesystem::exists(fb)) << fb;
    EXPECT_EQ(couple_test::run("wc -l < " + shell_quote(fa)).out, "6001\n") << ch;
    EXPECT_EQ(couple_test::run("cmp " + shell_quote(fa) + " " + shell_quote(fb)).code, 0) << ch << " differs";
  }
  auto got = couple_test::read_log(dir / "b.lcmlog", load_scenario(kScenario));
  std::size_t compared = 0, missing = 0;
  EXPECT_LE(worst_difference(got, {"WIND", "STRUCTURE", "CONTROL"}, &compared, &missing), 1e-12);
  EXPECT_EQ(missing, 0u);
  EXPECT_EQ(couple_test::left_over(dir), "");
}

TEST(Hybrid, KillingASubModelWhoseGroupIsSplitOverLaunchersIsRefused) {
  // Only the controller runs under this launcher (the structure on another host's): its
  // group cannot restart together, so the kill is refused before anything starts.
  LaunchOptions lo;
  lo.only = {"controller"};
  lo.nats = "nats://127.0.0.1:1";
  lo.kills = {{"controller", 100}};
  try {
    launch(load_scenario(kScenario), lo);
    FAIL() << "launched";
  } catch (const builtscene::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--kill controller@100: model 'controller' reads the local channel 'STRUCTURE' "
                                         "(LCM, no history) and not every model of its group 'building' runs under "
                                         "this launcher"),
              std::string::npos)
        << e.what();
  }
}
