// The distributed run (message wrapper + memq transport, models as threads) against the
// monolithic reference: the example's model functions called directly in one hand-written
// loop. They must agree to 1e-12 relative: the wrapper adds nothing to the numbers.
// Also: with control |A| stays within 1.5 m/s^2, without it exceeds it; a model that
// throws or exits stops the run with its name and keeps the log.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <map>
#include <thread>

#include "core/errors.hpp"
#include "couple/lcm_codec.hpp"
#include "couple/lcm_log.hpp"
#include "couple/launcher.hpp"
#include "couple/message_wrapper.hpp"
#include "couple/model_config.hpp"
#include "couple/monolithic.hpp"
#include "couple/status.hpp"
#include "couple/transport.hpp"
#include "test_util.hpp"

// The example's model functions, compiled straight into this test.
#include "../../examples/coupling/wind-structure-control/models/controller/controller_model.hpp"
#include "../../examples/coupling/wind-structure-control/models/structure/structure_model.hpp"
#include "../../examples/coupling/wind-structure-control/models/wind/wind_model.hpp"

using namespace builtscene::couple;
using nlohmann::json;

namespace {

struct Series {
  std::vector<double> U, P, Pc, D, V, A;
};

Series hand_written_loop(const ScenarioConfig& sc) {
  WindState* w = wind_init(sc.model("wind").parameters);
  StructureState* s = structure_init(sc.model("structure").parameters);
  ControllerState* c = controller_init(sc.model("controller").parameters);
  Series out;
  double D = 0, V = 0, A = 0;  // the structure's state before step 0
  const double dt = sc.model("wind").dt;
  for (int64_t n = 0; n < sc.model("wind").steps(); ++n) {
    const double t = static_cast<double>(n) * dt;
    double U, P, Pc, D1, V1, A1;
    wind(*w, n, t, U, P);
    controller(*c, n, t, D, V, A, U, P, Pc);
    structure(*s, n, t, U, P, Pc, D, V, A, D1, V1, A1);
    D = D1;
    V = V1;
    A = A1;
    out.U.push_back(U);
    out.P.push_back(P);
    out.Pc.push_back(Pc);
    out.D.push_back(D);
    out.V.push_back(V);
    out.A.push_back(A);
  }
  wind_free(w);
  structure_free(s);
  controller_free(c);
  return out;
}

// channel -> step -> decoded message, from a recorded log (re-published duplicates agree).
std::map<std::string, std::map<int64_t, json>> read_log(const std::filesystem::path& log, const ScenarioConfig& sc) {
  std::map<std::string, std::string> type;
  for (const auto& m : sc.models)
    for (const auto& p : m.publish) type[p.channel] = p.type;
  std::map<std::string, std::map<int64_t, json>> out;
  LcmLogReader r(log);
  while (auto e = r.next()) {
    auto it = type.find(e->channel);
    if (it == type.end()) continue;
    json v = LcmCodec(sc.types, it->second).decode(e->data);
    out[e->channel].emplace(v["step"].get<int64_t>(), v);
  }
  return out;
}

double rel(double a, double b) { return a == b ? 0 : std::abs(a - b) / std::max(std::abs(a), std::abs(b)); }

double compare(const Series& ref, std::map<std::string, std::map<int64_t, json>>& ch, std::size_t* rows) {
  double worst = 0;
  *rows = 0;
  for (std::size_t n = 0; n < ref.A.size(); ++n) {
    const auto step = static_cast<int64_t>(n);
    if (!ch["WIND"].count(step) || !ch["STRUCTURE"].count(step) || !ch["CONTROL"].count(step)) return INFINITY;
    worst = std::max({worst, rel(ref.U[n], ch["WIND"][step]["U"]), rel(ref.P[n], ch["WIND"][step]["P"]),
                      rel(ref.Pc[n], ch["CONTROL"][step]["Pc"]), rel(ref.D[n], ch["STRUCTURE"][step]["D"]),
                      rel(ref.V[n], ch["STRUCTURE"][step]["V"]), rel(ref.A[n], ch["STRUCTURE"][step]["A"])});
    ++*rows;
  }
  return worst;
}

double max_abs(const std::vector<double>& v) {
  double m = 0;
  for (double x : v) m = std::max(m, std::abs(x));
  return m;
}

}  // namespace

TEST(DistributedRun, MemqRunEqualsTheHandWrittenMonolithicLoop) {
  for (const std::string file : {"scenario.yaml", "scenario-no-control.yaml"}) {
    ScenarioConfig sc = load_scenario(couple_test::kExample + "/" + file);
    sc.transport = "memq://distributed_run_test";
    const auto dir = couple_test::temp_dir("memq");
    LaunchOptions lo;
    lo.record = dir / "run.lcmlog";
    lo.show_progress = false;
    const LaunchResult r = launch(sc, lo);
    EXPECT_EQ(r.steps, 6000);
    const Series ref = hand_written_loop(sc);
    auto ch = read_log(lo.record, sc);
    std::size_t rows = 0;
    EXPECT_LE(compare(ref, ch, &rows), 1e-12) << file;
    EXPECT_EQ(rows, 6000u);
    if (file == "scenario.yaml") {
      EXPECT_LE(max_abs(ref.A), 1.5 + 1e-9);
      EXPECT_GT(max_abs(ref.Pc), 0.0);
    } else {
      EXPECT_GT(max_abs(ref.A), 1.5);
      EXPECT_EQ(max_abs(ref.Pc), 0.0);
    }
  }
}

TEST(DistributedRun, LosingMessagesIsRecoveredByRepublishing) {
  // 3% of all deliveries (data and status) are lost, as on a lossy UDP network. Consumers
  // report what they wait for; producers re-send it. The result must still be exact.
  ScenarioConfig sc = load_scenario(couple_test::kExample + "/scenario.yaml");
  for (auto& m : sc.models) m.end_time = 5;  // 500 steps
  sc.transport = "memq://lossy?drop=0.03&seed=5";
  sc.timeout_seconds = 20;
  const auto dir = couple_test::temp_dir("lossy");
  LaunchOptions lo;
  lo.record = dir / "run.lcmlog";
  launch(sc, lo);
  ScenarioConfig ref_sc = sc;
  const Series ref = hand_written_loop(ref_sc);
  auto ch = read_log(lo.record, sc);  // the recorder loses messages too and asks for them again
  double worst = 0;
  std::size_t seen = 0;
  for (std::size_t n = 0; n < ref.A.size(); ++n)
    if (ch["STRUCTURE"].count(static_cast<int64_t>(n))) {
      worst = std::max(worst, rel(ref.A[n], ch["STRUCTURE"][static_cast<int64_t>(n)]["A"]));
      ++seen;
    }
  EXPECT_EQ(ref.A.size(), 500u);
  EXPECT_EQ(seen, 500u);
  EXPECT_LE(worst, 1e-12);
}

TEST(DistributedRun, GenericMonolithicRunnerEqualsTheHandWrittenLoop) {
  const ScenarioConfig sc = load_scenario(couple_test::kExample + "/scenario.yaml");
  auto rec = run_monolithic(sc);
  const Series ref = hand_written_loop(sc);
  std::size_t rows = 0;
  EXPECT_LE(compare(ref, rec, &rows), 1e-12);
  EXPECT_EQ(rows, 6000u);
}

namespace {
// A two-model scenario whose second model is a Python program (JSON lines) that fails.
std::filesystem::path failing_scenario(const std::string& tag, const std::string& failure) {
  const auto d = couple_test::temp_dir(tag);
  couple_test::write(d / "types.lcm", "package t;\nstruct x_t { int64_t step; double x; }\n");
  couple_test::write(d / "src.py",
                     "import json,sys\nfor line in sys.stdin:\n    r=json.loads(line)\n"
                     "    out={'ok':True} if 'init' in r else {'outputs':{'X':{'x':r['t']}}}\n"
                     "    print(json.dumps(out), flush=True)\n");
  couple_test::write(d / "sink.py",
                     "import json,sys\nfor line in sys.stdin:\n    r=json.loads(line)\n"
                     "    if 'init' not in r and r['step']==5:\n        " + failure + "\n"
                     "    out={'ok':True} if 'init' in r else {'outputs':{'Y':{'x':2*r['inputs']['X'][0]['x']}}}\n"
                     "    print(json.dumps(out), flush=True)\n");
  couple_test::write(d / "src.yaml", "name: src\ndt: 0.1\nend_time: 2\ncommand: [python3, src.py]\nmessages: types.lcm\n"
                                     "publish:\n  - {channel: X, type: t.x_t}\n");
  couple_test::write(d / "sink.yaml", "name: sink\ndt: 0.1\nend_time: 2\ncommand: [python3, sink.py]\nmessages: types.lcm\n"
                                      "subscribe:\n  - {channel: X, type: t.x_t}\npublish:\n  - {channel: Y, type: t.x_t}\n");
  couple_test::write(d / "scenario.yaml", "name: f\ntransport: memq://" + tag + "\ntimeout: 5\nmodels: [src.yaml, sink.yaml]\n");
  return d;
}
}  // namespace

TEST(DistributedRun, ExternalJsonLinesModelsRun) {
  const auto d = failing_scenario("pyok", "pass");
  const ScenarioConfig sc = load_scenario(d / "scenario.yaml");
  LaunchOptions lo;
  lo.record = d / "run.lcmlog";
  launch(sc, lo);
  auto ch = read_log(lo.record, sc);
  ASSERT_EQ(ch["Y"].size(), 20u);
  EXPECT_DOUBLE_EQ(ch["Y"][7]["x"].get<double>(), 2 * 0.7000000000000001);
}

TEST(DistributedRun, AModelThatThrowsStopsTheRunWithItsNameAndKeepsTheLog) {
  for (const std::string failure :
       {"print(json.dumps({'error': 'bad input 42'}), flush=True)\n        continue", "sys.exit(3)"}) {
    const auto d = failing_scenario("pyfail", failure);
    const ScenarioConfig sc = load_scenario(d / "scenario.yaml");
    LaunchOptions lo;
    lo.record = d / "run.lcmlog";
    try {
      launch(sc, lo);
      FAIL() << "a failing model was not reported";
    } catch (const builtscene::Failure& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find("model 'sink'"), std::string::npos) << msg;
      EXPECT_NE(msg.find("step 5"), std::string::npos) << msg;
      if (failure[0] == 'p') {
        EXPECT_NE(msg.find("bad input 42"), std::string::npos) << msg;
      } else {
        EXPECT_NE(msg.find("exited with code 3"), std::string::npos) << msg;
      }
      EXPECT_NE(msg.find("log kept"), std::string::npos) << msg;
    }
    auto ch = read_log(lo.record, sc);
    EXPECT_EQ(ch["Y"].size(), 5u);  // steps 0-4 were recorded
  }
}

namespace {
// Which channels an in-process bus carried during a run (a listener attached before it).
struct BusListener {
  std::unique_ptr<Transport> endpoint;
  std::map<std::string, int> count;
  explicit BusListener(const std::string& url) : endpoint(make_transport(url)) {
    endpoint->subscribe("", [this](const std::string& ch, const uint8_t*, std::size_t) { ++count[ch]; });
  }
  void drain() {
    while (endpoint->handle(0) > 0) {
    }
  }
};
}  // namespace

TEST(DistributedRun, HybridRunEqualsTheHandWrittenLoopAndKeepsLocalChannelsOffTheMediator) {
  // scenario-hybrid.yaml with both buses in process: the mediator's role on one memq bus,
  // the building group's LCM on another.
  ScenarioConfig sc = load_scenario(couple_test::kExample + "/scenario-hybrid.yaml");
  for (auto& m : sc.models) m.end_time = 10;  // 1000 steps
  sc.transport = "memq://hybrid_main";
  sc.local_transport = "memq://hybrid_local";
  ASSERT_EQ(sc.local_url("building"), "memq://hybrid_local-building");
  const Series ref = hand_written_loop(sc);
  {
    // Recorded: the local channels are bridged to the main bus for the recorder.
    const auto dir = couple_test::temp_dir("hybrid_memq");
    LaunchOptions lo;
    lo.record = dir / "run.lcmlog";
    lo.show_progress = false;
    launch(sc, lo);
    auto ch = read_log(lo.record, sc);
    std::size_t rows = 0;
    EXPECT_LE(compare(ref, ch, &rows), 1e-12);
    EXPECT_EQ(rows, 1000u);
  }
  // Not recorded: STRUCTURE and CONTROL only on the group's bus, WIND only on the main one.
  BusListener main("memq://hybrid_main"), local("memq://hybrid_local-building");
  LaunchOptions lo;
  lo.show_progress = false;
  const LaunchResult r = launch(sc, lo);
  EXPECT_EQ(r.model_steps.at("structure"), 1000);
  main.drain();
  local.drain();
  EXPECT_GE(main.count["WIND"], 1000);
  EXPECT_GT(main.count["BUILTSCENE_STATUS.structure"], 0);  // statuses go through the mediator
  EXPECT_EQ(local.count["BUILTSCENE_STATUS.structure"], 0);
  EXPECT_EQ(main.count["STRUCTURE"], 0);
  EXPECT_EQ(main.count["CONTROL"], 0);
  EXPECT_GE(local.count["STRUCTURE"], 1000);
  EXPECT_GE(local.count["CONTROL"], 1000);
  EXPECT_EQ(local.count["WIND"], 0);
}

namespace {
// Models on the test's own terms: each reads the `x` of its inputs' newest messages and
// publishes one t.x_t computed by `f` (the tests know the exact values to expect).
class LambdaModel final : public ModelFunction {
 public:
  using F = std::function<double(int64_t n, const std::vector<double>& inputs)>;
  LambdaModel(const ScenarioConfig& sc, F f) : codec_(sc.types, "t.x_t"), f_(std::move(f)) {}
  void step(int64_t n, double, const std::vector<std::vector<const Bytes*>>& inputs, std::vector<Bytes>& outputs) override {
    std::vector<double> xs;
    for (const auto& in : inputs) xs.push_back(codec_.decode(*in.at(0))["x"].get<double>());
    outputs.at(0) = codec_.encode({{"step", n}, {"x", f_(n, xs)}});
  }

 private:
  LcmCodec codec_;
  F f_;
};

// K sources X_i = 1000 i + n, a slow source S = n (its step takes `slow_ms`) and a sink
// Y = the sum of all of them, 60 steps of 0.1 s; written as YAML, loaded like any scenario.
ScenarioConfig fan_in_scenario(const std::string& tag, int sources) {
  const auto d = couple_test::temp_dir(tag);
  couple_test::write(d / "types.lcm", "package t;\nstruct x_t { int64_t step; double x; }\n");
  const std::string head = "dt: 0.1\nend_time: 6\ncommand: [unused]\nmessages: types.lcm\n";
  std::string models, subs;
  for (int i = 0; i < sources; ++i) {
    const std::string k = std::to_string(i);
    couple_test::write(d / ("src_" + k + ".yaml"),
                       "name: src_" + k + "\n" + head + "publish:\n  - {channel: X_" + k + ", type: t.x_t}\n");
    models += "  - src_" + k + ".yaml\n";
    subs += "  - {channel: X_" + k + ", type: t.x_t}\n";
  }
  couple_test::write(d / "slow.yaml", "name: slow\n" + head + "publish:\n  - {channel: S, type: t.x_t}\n");
  couple_test::write(d / "sink.yaml", "name: sink\n" + head + "subscribe:\n" + subs +
                                          "  - {channel: S, type: t.x_t}\npublish:\n  - {channel: Y, type: t.x_t}\n");
  couple_test::write(d / "scenario.yaml", "name: " + tag + "\ntransport: memq://" + tag + "\ntimeout: 60\nmodels:\n" + models +
                                              "  - slow.yaml\n  - sink.yaml\n");
  return load_scenario(d / "scenario.yaml");
}
}  // namespace

TEST(DistributedRun, AFinishedProducerServesALateSlowConsumerForAsLongAsItReports) {
  // The 100-building stall at small scale: the sources finish at once, the sink is paced by
  // a slow source (60 steps of 30 ms) and loses 20 % of what it receives, so it asks for
  // the lost X_i steps long after the sources finished. The sources linger 0.5 s; before
  // the fix that counted from the sink's first report, they left while the sink was alive
  // and still asking, and it waited for ever. Now they serve it while it keeps reporting.
  const int K = 8;
  const ScenarioConfig sc = fan_in_scenario("late_sink", K);
  std::map<int64_t, double> y;  // the sink's results, step -> Y
  std::atomic<bool> stop{false};
  std::vector<std::unique_ptr<Transport>> transports;
  std::vector<std::unique_ptr<MessageWrapper>> wrappers;
  for (const auto& m : sc.models) {
    LambdaModel::F f;
    if (m.name == "slow") {
      f = [](int64_t n, const std::vector<double>&) {
        std::this_thread::sleep_for(std::chrono::milliseconds(30));
        return static_cast<double>(n);
      };
    } else if (m.name == "sink") {
      f = [&y](int64_t n, const std::vector<double>& xs) {
        double sum = 0;
        for (double x : xs) sum += x;
        y[n] = sum;
        return sum;
      };
    } else {
      const int i = std::stoi(m.name.substr(4));
      f = [i](int64_t n, const std::vector<double>&) { return 1000.0 * i + static_cast<double>(n); };
    }
    transports.push_back(make_transport(m.name == "sink" ? "memq://late_sink?drop=0.2&seed=11" : "memq://late_sink"));
    WrapperOptions wo;
    wo.stop = &stop;
    wo.linger_seconds = 0.5;
    wrappers.push_back(std::make_unique<MessageWrapper>(sc, m.name, *transports.back(),
                                                        std::make_unique<LambdaModel>(sc, f), wo));
  }
  std::atomic<int> running{static_cast<int>(wrappers.size())};
  std::vector<std::thread> threads;
  for (auto& w : wrappers)
    threads.emplace_back([&running, wp = w.get()] {
      wp->run();
      --running;
    });
  // Only a guard against hanging (the old behaviour): stop whatever still runs after 60 s.
  for (int i = 0; i < 6000 && running > 0; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  stop = true;
  for (auto& t : threads) t.join();
  EXPECT_EQ(wrappers.back()->steps_done(), 60) << "the sink did not finish";
  ASSERT_EQ(y.size(), 60u);
  for (int64_t n = 0; n < 60; ++n) {
    double truth = static_cast<double>(n);  // S
    for (int i = 0; i < K; ++i) truth += 1000.0 * i + static_cast<double>(n);
    EXPECT_EQ(y[n], truth) << "step " << n;
  }
  for (const auto& w : wrappers) EXPECT_FALSE(w->stopped());
}

TEST(DistributedRun, ABlockedModelNamesEveryMissingInput) {
  // Nothing has been published: the sink's status must name each of its inputs at step 0
  // (its producers re-send at once instead of one input per round trip).
  const ScenarioConfig sc = fan_in_scenario("blocked_sink", 3);
  auto bus = make_transport("memq://blocked_sink");
  std::vector<ModelStatus> seen;
  bus->subscribe(status_channel("sink"), [&](const std::string&, const uint8_t* d, std::size_t n) {
    seen.push_back(decode_status(sc.types, d, n));
  });
  auto tr = make_transport("memq://blocked_sink");
  std::atomic<bool> stop{false};
  WrapperOptions wo;
  wo.stop = &stop;
  MessageWrapper sink(sc, "sink", *tr, std::make_unique<LambdaModel>(sc, [](int64_t, const std::vector<double>&) { return 0.0; }), wo);
  std::thread t([&] { sink.run(); });
  const ModelStatus* waiting = nullptr;
  for (int i = 0; i < 500 && !waiting; ++i) {
    bus->handle(10);
    for (const auto& s : seen)
      if (s.state == ModelState::kWaiting) waiting = &s;
  }
  stop = true;
  t.join();
  ASSERT_NE(waiting, nullptr) << "no waiting status from the sink";
  const std::vector<std::pair<std::string, int64_t>> expected = {{"X_0", 0}, {"X_1", 0}, {"X_2", 0}, {"S", 0}};
  EXPECT_EQ(waiting->waiting, expected);
}
