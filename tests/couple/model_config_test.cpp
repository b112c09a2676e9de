// Model and scenario configuration: the bad-input cases of issue 10 give one clear
// message naming the file, line and field, before anything starts.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include "core/errors.hpp"
#include "couple/model_config.hpp"
#include "test_util.hpp"

using builtscene::InputError;
using namespace builtscene::couple;
using couple_test::write;

namespace {

const char* kTypes = R"(package t;
struct a_t { int64_t step; double x; }
struct b_t { int64_t step; double y; }
)";

std::string model(const std::string& name, const std::string& extra, double dt = 0.1) {
  return "name: " + name + "\ndt: " + std::to_string(dt) + "\nend_time: 1.0\nplugin: none\nmessages: types.lcm\n" + extra;
}

// Loads a scenario of the given model files; returns the error message ("" if it loads).
std::string load(const std::string& tag, const std::vector<std::pair<std::string, std::string>>& models,
                 const std::string& scenario_extra = "") {
  const auto d = couple_test::temp_dir(tag);
  write(d / "types.lcm", kTypes);
  std::string sc = "name: s\ntransport: memq://x\n" + scenario_extra + "models:\n";
  for (const auto& [file, text] : models) {
    write(d / file, text);
    sc += "  - " + file + "\n";
  }
  write(d / "scenario.yaml", sc);
  try {
    load_scenario(d / "scenario.yaml");
    return "";
  } catch (const InputError& e) {
    return e.what();
  }
}

bool has(const std::string& s, const std::string& part) { return s.find(part) != std::string::npos; }

const std::string kPubA = "publish:\n  - channel: A\n    type: t.a_t\n";
const std::string kPubB = "publish:\n  - channel: B\n    type: t.b_t\n";

}  // namespace

TEST(ModelConfig, AValidPairLoads) {
  EXPECT_EQ(load("ok", {{"p.yaml", model("p", kPubA)},
                        {"q.yaml", model("q", kPubB + "subscribe:\n  - channel: A\n    type: t.a_t\n")}}),
            "");
}

TEST(ModelConfig, MalformedYamlNamesFileAndLine) {
  const auto e = load("yaml", {{"p.yaml", "name: p\ndt: 0.1\nsubscribe: [a, b\nend_time: 1\n"}});
  EXPECT_TRUE(has(e, "p.yaml:")) << e;
  EXPECT_TRUE(has(e, "YAML syntax error")) << e;
}

TEST(ModelConfig, UnknownFieldAndBadValueNameTheField) {
  auto e = load("field", {{"p.yaml", model("p", kPubA + "subscrbe: []\n")}});
  EXPECT_TRUE(has(e, "p.yaml:9")) << e;
  EXPECT_TRUE(has(e, "'subscrbe'")) << e;
  e = load("value", {{"p.yaml", "name: p\ndt: fast\nend_time: 1\nplugin: x\n" + kPubA}});
  EXPECT_TRUE(has(e, "p.yaml:2")) << e;
  EXPECT_TRUE(has(e, "'dt'")) << e;
  e = load("history", {{"p.yaml", model("p", kPubA)},
                       {"q.yaml", model("q", kPubB + "subscribe:\n  - channel: A\n    type: t.a_t\n    history: 0\n")}});
  EXPECT_TRUE(has(e, "q.yaml:12")) << e;
  EXPECT_TRUE(has(e, "subscribe[0].history")) << e;
}

TEST(ModelConfig, UnknownTypeIsNamedWithTheKnownOnes) {
  const auto e = load("type", {{"p.yaml", model("p", "publish:\n  - channel: A\n    type: t.c_t\n")}});
  EXPECT_TRUE(has(e, "p.yaml:7")) << e;
  EXPECT_TRUE(has(e, "unknown message type 't.c_t'")) << e;
  EXPECT_TRUE(has(e, "t.a_t")) << e;
}

TEST(ModelConfig, TwoModelsDisagreeingOnAChannelType) {
  const auto e = load("disagree", {{"p.yaml", model("p", kPubA)},
                                   {"q.yaml", model("q", kPubB + "subscribe:\n  - channel: A\n    type: t.b_t\n")}});
  EXPECT_TRUE(has(e, "q.yaml:10")) << e;
  EXPECT_TRUE(has(e, "channel 'A'")) << e;
  EXPECT_TRUE(has(e, "'t.b_t'")) << e;
  EXPECT_TRUE(has(e, "'t.a_t'")) << e;
}

TEST(ModelConfig, ChannelWithoutProducerAndTwoProducers) {
  auto e = load("noprod", {{"q.yaml", model("q", kPubB + "subscribe:\n  - channel: A\n    type: t.a_t\n")}});
  EXPECT_TRUE(has(e, "no model publishes channel 'A'")) << e;
  e = load("twoprod", {{"p.yaml", model("p", kPubA)}, {"q.yaml", model("q", kPubA)}});
  EXPECT_TRUE(has(e, "already published by model 'p'")) << e;
}

TEST(ModelConfig, CycleWithoutInitialDataIsADeadlockFoundBeforeStart) {
  const std::string sub_b = "subscribe:\n  - channel: B\n    type: t.b_t\n";
  const std::string sub_a = "subscribe:\n  - channel: A\n    type: t.a_t\n";
  auto e = load("cycle", {{"p.yaml", model("p", kPubA + sub_b)}, {"q.yaml", model("q", kPubB + sub_a)}});
  EXPECT_TRUE(has(e, "deadlock")) << e;
  EXPECT_TRUE(has(e, "waits for channel")) << e;
  // A lag alone needs data for step -1:
  e = load("lag", {{"p.yaml", model("p", kPubA + sub_b + "    lag: 1\n")}, {"q.yaml", model("q", kPubB + sub_a)}});
  EXPECT_TRUE(has(e, "needs step -1 of channel 'B'")) << e;
  // ... which initial values or an initial publish provide.
  EXPECT_EQ(load("lag_init", {{"p.yaml", model("p", kPubA + sub_b + "    lag: 1\n    initial: {y: 2.5}\n")},
                              {"q.yaml", model("q", kPubB + sub_a)}}),
            "");
  EXPECT_EQ(load("lag_pub", {{"p.yaml", model("p", kPubA + sub_b + "    lag: 1\n")},
                             {"q.yaml", model("q", kPubB + "    initial: {y: 1}\n" + sub_a)}}),
            "");
  e = load("bad_init", {{"p.yaml", model("p", kPubA + sub_b + "    lag: 1\n    initial: {z: 2.5}\n")},
                        {"q.yaml", model("q", kPubB + sub_a)}});
  EXPECT_TRUE(has(e, "no member 'z'")) << e;
}

TEST(ModelConfig, TimeStepRatiosMustMatchTheProducers) {
  const std::string sub = "subscribe:\n  - channel: A\n    type: t.a_t\n";
  auto e = load("ratio_bad", {{"p.yaml", model("p", kPubA, 0.1)}, {"q.yaml", model("q", kPubB + sub, 0.05)}});
  EXPECT_TRUE(has(e, "dt")) << e;
  EXPECT_EQ(load("ratio_every", {{"p.yaml", model("p", kPubA, 0.1)},
                                 {"q.yaml", model("q", kPubB + sub + "    every: 2\n", 0.05)}}),
            "");
  EXPECT_EQ(load("ratio_sub", {{"p.yaml", model("p", kPubA, 0.05)},
                               {"q.yaml", model("q", kPubB + sub + "    substeps: 2\n", 0.1)}}),
            "");
}

TEST(Subscription, ExpectedStepFollowsRatiosAndLag) {
  Subscription s;
  EXPECT_EQ(s.expected_step(5), 5);
  s.every = 3;  // producer steps 0,1,.. cover our steps 0-2, 3-5, ...
  EXPECT_EQ(s.expected_step(0), 0);
  EXPECT_EQ(s.expected_step(2), 0);
  EXPECT_EQ(s.expected_step(3), 1);
  s.every = 1;
  s.substeps = 4;  // producer runs 4 steps per ours: we need the last of them
  EXPECT_EQ(s.expected_step(0), 3);
  EXPECT_EQ(s.expected_step(2), 11);
  s.lag = 1;
  EXPECT_EQ(s.expected_step(2), 10);
}

TEST(ModelConfig, TheExampleLoads) {
  const auto sc = load_scenario(couple_test::kExample + "/scenario.yaml");
  EXPECT_EQ(sc.models.size(), 3u);
  EXPECT_EQ(sc.model("structure").steps(), 6000);
}

namespace {
// A hybrid scenario: p publishes A, q reads A and publishes B; `models` and `local` as given.
std::string load_hybrid(const std::string& tag, const std::string& models, const std::string& local,
                        ScenarioConfig* out = nullptr) {
  const auto d = couple_test::temp_dir(tag);
  write(d / "types.lcm", kTypes);
  write(d / "p.yaml", model("p", kPubA));
  write(d / "q.yaml", model("q", kPubB + "subscribe:\n  - channel: A\n    type: t.a_t\n"));
  write(d / "scenario.yaml", "name: s\ntransport: memq://x\n" + local + "models:\n" + models);
  try {
    const ScenarioConfig sc = load_scenario(d / "scenario.yaml");
    if (out) *out = sc;
    return "";
  } catch (const InputError& e) {
    return e.what();
  }
}
const std::string kGrouped = "  - {config: p.yaml, group: g1}\n  - {config: q.yaml, group: g1}\n";
}  // namespace

TEST(ModelConfig, HybridGroupsGetOneMulticastPortEach) {
  ScenarioConfig sc;
  ASSERT_EQ(load_hybrid("hybrid_ok", "  - {config: p.yaml, group: g1}\n  - {config: q.yaml, group: g2}\n",
                        "local:\n  transport: udpm://239.255.76.67:7700?ttl=0\n  channels: [A, B]\n", &sc),
            "");
  EXPECT_TRUE(sc.is_local("A"));
  EXPECT_FALSE(sc.is_local("BUILTSCENE_STATUS"));
  EXPECT_EQ(sc.model("q").group, "g2");
  EXPECT_EQ(sc.local_url("g1"), "udpm://239.255.76.67:7700?ttl=0");
  EXPECT_EQ(sc.local_url("g2"), "udpm://239.255.76.67:7701?ttl=0");
  EXPECT_THROW(sc.local_url("g3"), InputError);
}

TEST(ModelConfig, HybridBadInputNamesTheFileAndField) {
  const std::string local = "local:\n  channels: [A]\n";
  auto e = load_hybrid("hybrid_nogroup", "  - p.yaml\n  - {config: q.yaml, group: g1}\n", local);
  EXPECT_TRUE(has(e, "scenario.yaml:4: field 'local.channels': channel 'A' is local but its producer 'p' is in no group"))
      << e;
  e = load_hybrid("hybrid_unknown", kGrouped, "local:\n  channels: [A, C]\n");
  EXPECT_TRUE(has(e, "scenario.yaml:") && has(e, "field 'local.channels': no model publishes channel 'C'")) << e;
  e = load_hybrid("hybrid_status", kGrouped, "local:\n  channels: [BUILTSCENE_STATUS]\n");
  EXPECT_TRUE(has(e, "the status channel always goes through the mediator")) << e;
  e = load_hybrid("hybrid_url", kGrouped, "local:\n  transport: nats://127.0.0.1:4222\n  channels: [A]\n");
  EXPECT_TRUE(has(e, "scenario.yaml:4: field 'local.transport'")) << e;
  e = load_hybrid("hybrid_empty", kGrouped, "local:\n  channels: []\n");
  EXPECT_TRUE(has(e, "field 'local.channels' must be a non-empty list")) << e;
  e = load_hybrid("hybrid_key", kGrouped, "local:\n  channel: [A]\n");
  EXPECT_TRUE(has(e, "unknown field 'local.channel'")) << e;
  e = load_hybrid("hybrid_entry", "  - {config: p.yaml, grup: g1}\n  - q.yaml\n", local);
  EXPECT_TRUE(has(e, "scenario.yaml:6: unknown field 'models[0].grup'")) << e;
  e = load_hybrid("hybrid_ports", kGrouped, "local:\n  transport: udpm://239.255.76.67:65535?ttl=0\n  channels: [A]\n");
  EXPECT_EQ(e, "");  // one group fits in the last port
  e = load_hybrid("hybrid_ports2", "  - {config: p.yaml, group: g1}\n  - {config: q.yaml, group: g2}\n",
                  "local:\n  transport: udpm://239.255.76.67:65535?ttl=0\n  channels: [A]\n");
  EXPECT_TRUE(has(e, "2 groups need ports up to 65536")) << e;
}

TEST(ModelConfig, CheckpointEveryMustBeAWholeNonNegativeNumberOfSteps) {
  auto e = load("ckpt_neg", {{"p.yaml", model("p", kPubA + "checkpoint_every: -5\n")}});
  EXPECT_TRUE(has(e, "p.yaml:") && has(e, "field 'checkpoint_every' must not be negative")) << e;
  e = load("ckpt_text", {{"p.yaml", model("p", kPubA + "checkpoint_every: often\n")}});
  EXPECT_TRUE(has(e, "p.yaml:") && has(e, "field 'checkpoint_every' has a bad value")) << e;
  EXPECT_EQ(load("ckpt_ok", {{"p.yaml", model("p", kPubA + "checkpoint_every: 3\n")}}), "");
}

TEST(ModelConfig, ModelsPerProcessMustBeAPositiveCount) {
  const auto p = model("p", "publish:\n  - {channel: A, type: t.a_t}\n");
  EXPECT_EQ(load("mpp_ok", {{"p.yaml", p}}, "models_per_process: 4\n"), "");
  const std::string e = load("mpp_bad", {{"p.yaml", p}}, "models_per_process: 0\n");
  EXPECT_NE(e.find("scenario.yaml:3: field 'models_per_process' must be at least 1"), std::string::npos) << e;
}
