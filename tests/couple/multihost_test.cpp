// Several hosts on one machine. Two hosts: two Linux network namespaces joined by a veth pair
// (10.200.0.1 and 10.200.0.2, addresses that exist only inside them). Host A runs the
// mediator (nats-server on 10.200.0.1) and the wind; host B runs the building (structure
// and controller), whose local channels go over LCM on B's own loopback (ttl=0, a
// multicast route to lo), while the wind reaches it through the mediator across the veth.
// Each host has its own `couple launch --only ...`; B records. Nothing leaves the two
// namespaces. Three hosts: namespaces on a Linux bridge (see on_three_bridged_hosts), the
// example over the mediator with one model per host. Skips, saying why, where namespaces
// cannot be made (not root).
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "couple/model_config.hpp"
#include "couple/monolithic.hpp"
#include "test_util.hpp"

using namespace builtscene::couple;
using nlohmann::json;

namespace {

using builtscene::testing::shell_quote;

const std::string kBin = shell_quote(BUILTSCENE_BINARY);

double rel(double a, double b) { return a == b ? 0 : std::abs(a - b) / std::max(std::abs(a), std::abs(b)); }

// Runs `script` with two fresh namespaces $A and $B (veth bsa 10.200.0.1/24 in A,
// bsb 10.200.0.2/24 in B, loopbacks up with a multicast route); removes them afterwards
// whatever happens. nullopt (and why) where `ip netns` is not permitted.
std::optional<couple_test::RunResult> on_two_hosts(const std::filesystem::path& dir, const std::string& script,
                                                   std::string* why) {
  const std::string tag = std::to_string(::getpid());
  const auto probe = couple_test::run("ip netns add bsprobe" + tag + " && ip netns del bsprobe" + tag + " && echo ok");
  if (probe.code != 0 || probe.out.find("ok") == std::string::npos) {
    *why = "the multi-host test makes hosts as network namespaces (ip netns, needs root and iproute2); "
           "creating one failed: " + probe.out;
    return std::nullopt;
  }
  couple_test::write(dir / "hosts.sh",
                     "A=bshostA" + tag + "\nB=bshostB" + tag + "\n"
                     "cleanup() { ip netns pids $A 2>/dev/null | xargs -r kill -9; ip netns pids $B 2>/dev/null | xargs -r kill -9;\n"
                     "  ip netns del $A 2>/dev/null; ip netns del $B 2>/dev/null; }\n"
                     "trap cleanup EXIT\nset -e\n"
                     "ip netns add $A\nip netns add $B\n"
                     "ip -n $A link add bsa type veth peer name bsb netns $B\n"
                     "ip -n $A addr add 10.200.0.1/24 dev bsa\nip -n $B addr add 10.200.0.2/24 dev bsb\n"
                     "for H in $A $B; do ip -n $H link set lo up; ip -n $H route add 224.0.0.0/4 dev lo; done\n"
                     "ip -n $A link set bsa up\nip -n $B link set bsb up\n"
                     "set +e\n" + script);
  return couple_test::run("sh " + shell_quote(dir / "hosts.sh"));
}

// Runs `script` with three fresh hosts $A, $B, $C (10.200.1.1, .2, .3) joined by a Linux
// bridge: each host's veth peer is a port of bridge `bsbr` in a fourth namespace $S (the
// switch), so no interface of the machine's own namespace is touched. Removed afterwards.
std::optional<couple_test::RunResult> on_three_bridged_hosts(const std::filesystem::path& dir, const std::string& script,
                                                            std::string* why) {
  const std::string tag = std::to_string(::getpid());
  const auto probe = couple_test::run("ip netns add bsprobe" + tag + " && ip netns del bsprobe" + tag + " && echo ok");
  if (probe.code != 0 || probe.out.find("ok") == std::string::npos) {
    *why = "the multi-host test makes hosts as network namespaces (ip netns, needs root and iproute2); "
           "creating one failed: " + probe.out;
    return std::nullopt;
  }
  couple_test::write(dir / "hosts.sh",
                     "A=bs3A" + tag + "\nB=bs3B" + tag + "\nC=bs3C" + tag + "\nS=bs3S" + tag + "\n"
                     "cleanup() { for H in $A $B $C $S; do ip netns pids $H 2>/dev/null | xargs -r kill -9; done;\n"
                     "  for H in $A $B $C $S; do ip netns del $H 2>/dev/null; done; }\n"
                     "trap cleanup EXIT\nset -e\n"
                     "for H in $S $A $B $C; do ip netns add $H; done\n"
                     "ip -n $S link add bsbr type bridge\nip -n $S link set bsbr up\n"
                     "i=0\nfor H in $A $B $C; do i=$((i+1))\n"
                     "  ip -n $H link add bsh$i type veth peer name bsp$i netns $S\n"
                     "  ip -n $S link set bsp$i master bsbr\n  ip -n $S link set bsp$i up\n"
                     "  ip -n $H addr add 10.200.1.$i/24 dev bsh$i\n  ip -n $H link set bsh$i up\n"
                     "  ip -n $H link set lo up\n  ip -n $H route add 224.0.0.0/4 dev lo\ndone\n"
                     "set +e\n" + script);
  return couple_test::run("sh " + shell_quote(dir / "hosts.sh"));
}

}  // namespace

TEST(MultiHost, MediatorExampleOnThreeBridgedHostsEqualsTheMonolithicReference) {
  const auto dir = couple_test::temp_dir("multihost3");
  const std::string d = dir.string(), scenario = couple_test::kExample + "/scenario-mediator.yaml";
  const std::string nats = "nats://10.200.1.1:4222";
  auto launch = [&](const std::string& host, const std::string& model, const std::string& extra) {
    return "ip netns exec $" + host + " env TMPDIR=" + shell_quote(d) + " " + kBin + " couple launch " +
           shell_quote(scenario) + " --nats " + nats + " --only " + model + extra + " --json > " +
           shell_quote(d + "/" + model + ".json");
  };
  std::string why;
  // nats-server and the wind on A, the structure on B, the controller on C (recording);
  // every data message crosses the bridge twice (producer -> A -> consumer).
  const auto r = on_three_bridged_hosts(dir,
      "ip netns exec $A nats-server -a 10.200.1.1 -p 4222 -js -sd " + shell_quote(d + "/js") + " -l " +
      shell_quote(d + "/server.log") + " > /dev/null 2>&1 & N=$!\n"
      "for i in $(seq 100); do grep -q 'Server is ready' " + shell_quote(d + "/server.log") +
      " 2>/dev/null && break; sleep 0.1; done\n"
      "for H in $B $C; do ip netns exec $H timeout 5 bash -c 'exec 3<>/dev/tcp/10.200.1.1/4222' || echo no-route-from-$H; done\n" +
      launch("A", "wind", "") + " & LA=$!\n" + launch("B", "structure", "") + " & LB=$!\n" +
      launch("C", "controller", " --record " + shell_quote(d + "/run.lcmlog")) +
      "\nRC=$?\nwait $LA\nRA=$?\nwait $LB\nRB=$?\n"
      "kill $N\nwait $N\necho rc=$RA,$RB,$RC\n",
      &why);
  if (!r) GTEST_SKIP() << why;
  EXPECT_NE(r->out.find("rc=0,0,0"), std::string::npos) << r->out;
  EXPECT_EQ(r->out.find("no-route-from"), std::string::npos) << r->out;
  for (const std::string m : {"wind", "structure", "controller"}) {
    const json j = json::parse(std::ifstream(dir / (m + ".json")));
    EXPECT_EQ(j["models"][m], 6000) << j.dump();
    EXPECT_EQ(j["transport"], nats) << j.dump();
  }
  const ScenarioConfig sc = load_scenario(scenario);
  const auto ref = run_monolithic(sc);
  auto got = couple_test::read_log(dir / "run.lcmlog", sc);
  double worst = 0;
  std::size_t compared = 0;
  for (const std::string ch : {"WIND", "STRUCTURE", "CONTROL"}) {
    ASSERT_EQ(got[ch].size(), 6000u) << ch;
    for (const auto& [n, v] : ref.at(ch)) {
      if (n < 0) continue;
      for (const auto& [k, x] : v.items())
        if (k != "step") {
          worst = std::max(worst, rel(x.get<double>(), got[ch][n][k].get<double>()));
          ++compared;
        }
    }
  }
  EXPECT_EQ(compared, 6000u * 6);
  EXPECT_LE(worst, 1e-12);
  std::printf("three bridged hosts (netns): mediator + wind on A, structure on B, controller on C: "
              "max relative difference %.3g\n", worst);
  EXPECT_EQ(couple_test::left_over(dir), "");
}

TEST(MultiHost, HybridExampleOnTwoNamespacedHostsEqualsTheMonolithicReference) {
  const auto dir = couple_test::temp_dir("multihost");
  const std::string d = dir.string(), scenario = couple_test::kExample + "/scenario-hybrid.yaml";
  const std::string nats = "nats://10.200.0.1:4222";
  std::string why;
  const auto r = on_two_hosts(dir,
      "ip netns exec $A nats-server -a 10.200.0.1 -p 4222 -js -sd " + shell_quote(d + "/js") + " -l " +
      shell_quote(d + "/server.log") + " > /dev/null 2>&1 & N=$!\n"
      "for i in $(seq 100); do grep -q 'Server is ready' " + shell_quote(d + "/server.log") +
      " 2>/dev/null && break; sleep 0.1; done\n"
      // host B must reach the server across the veth (bash's /dev/tcp: no ping needed)
      "ip netns exec $B timeout 5 bash -c 'exec 3<>/dev/tcp/10.200.0.1/4222' || echo no-route-to-A\n"
      "ip netns exec $A env TMPDIR=" + shell_quote(d) + " " + kBin + " couple launch " + shell_quote(scenario) +
      " --nats " + nats + " --only wind --json > " + shell_quote(d + "/a.json") + " & LA=$!\n"
      "ip netns exec $B env TMPDIR=" + shell_quote(d) + " " + kBin + " couple launch " + shell_quote(scenario) +
      " --nats " + nats + " --only structure --only controller --record " + shell_quote(d + "/run.lcmlog") +
      " --json > " + shell_quote(d + "/b.json") + "\n"
      "RB=$?\nwait $LA\nRA=$?\nkill $N\nwait $N\necho rc=$RA,$RB\n",
      &why);
  if (!r) GTEST_SKIP() << why;
  EXPECT_NE(r->out.find("rc=0,0"), std::string::npos) << r->out;
  EXPECT_EQ(r->out.find("no-route-to-A"), std::string::npos) << r->out;
  const json a = json::parse(std::ifstream(dir / "a.json")), b = json::parse(std::ifstream(dir / "b.json"));
  EXPECT_EQ(a["models"]["wind"], 6000) << a.dump();
  EXPECT_EQ(b["models"]["structure"], 6000) << b.dump();
  EXPECT_EQ(b["models"]["controller"], 6000) << b.dump();
  EXPECT_EQ(b["transport"], nats);

  const ScenarioConfig sc = load_scenario(scenario);
  const auto ref = run_monolithic(sc);
  auto got = couple_test::read_log(dir / "run.lcmlog", sc);
  double worst = 0;
  std::size_t compared = 0;
  for (const std::string ch : {"WIND", "STRUCTURE", "CONTROL"}) {
    ASSERT_EQ(got[ch].size(), 6000u) << ch;
    for (const auto& [n, v] : ref.at(ch)) {
      if (n < 0) continue;
      for (const auto& [k, x] : v.items())
        if (k != "step") {
          worst = std::max(worst, rel(x.get<double>(), got[ch][n][k].get<double>()));
          ++compared;
        }
    }
  }
  EXPECT_EQ(compared, 6000u * 6);
  EXPECT_LE(worst, 1e-12);
  std::printf("two hosts (netns): wind on A with the mediator, building on B: max relative difference %.3g\n", worst);
  EXPECT_EQ(couple_test::left_over(dir), "");
}

TEST(MultiHost, OnlyOptionBadInputIsAClearError) {
  const std::string launch = kBin + " couple launch " + shell_quote(couple_test::kExample + "/scenario-hybrid.yaml");
  auto r = couple_test::run(launch + " --only wind");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("--only needs --nats nats://HOST:PORT"), std::string::npos) << r.out;
  r = couple_test::run(launch + " --only windy --nats nats://127.0.0.1:1");
  EXPECT_EQ(r.code, 2) << r.out;
  EXPECT_NE(r.out.find("scenario-hybrid.yaml: no model named 'windy'"), std::string::npos) << r.out;
}
