// Event-driven models: a controller publishes a command only when its decision changes
// (most steps publish nothing); the plant and a slower logger hold the newest command
// (sample-and-hold). The truth is a hand-written loop of the same rules in this file; the
// distributed runs (memq threads, with and without lost deliveries; processes over a
// launched mediator) must equal it exactly, and over the mediator the recorded log must
// show that no model received a message stamped earlier than a time it had been granted.
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <set>
#include <thread>

#include "core/errors.hpp"
#include "couple/event_tracker.hpp"
#include "couple/launcher.hpp"
#include "couple/lcm_codec.hpp"
#include "couple/lcm_log.hpp"
#include "couple/message_wrapper.hpp"
#include "couple/model_function.hpp"
#include "couple/model_config.hpp"
#include "couple/status.hpp"
#include "couple/time_manager.hpp"
#include "test_util.hpp"

using namespace builtscene::couple;
using nlohmann::json;

namespace {

using builtscene::testing::shell_quote;

const std::string kBin = shell_quote(BUILTSCENE_BINARY);
constexpr int64_t kSteps = 1500;  // plant and controller (dt 0.01); the logger runs half as many (dt 0.02)

// plant:      x(n) = x(n-1) + 1 - 2 * level, level the newest CMD event up to step n
// controller: reads x(n-1) (lag 1, x(-1) = 0); switches level 0 -> 1 at x >= 10 and
//             1 -> 0 at x <= 2; publishes CMD only when it switches (initial level 0)
// logger:     dt 0.02, CMD with substeps 2: holds the newest event up to step 2m + 1
struct Truth {
  std::map<int64_t, int64_t> cmd;        // event step -> level (step -1: the initial publication)
  std::vector<int64_t> x, held_step;     // plant per step
  std::vector<int64_t> log_level, log_at;  // logger per step
};

Truth hand_written_loop() {
  Truth t;
  t.cmd[-1] = 0;
  int64_t x = 0, level = 0;
  for (int64_t n = 0; n < kSteps; ++n) {
    const int64_t seen = n == 0 ? 0 : t.x.back();
    if (level == 0 && seen >= 10) t.cmd[n] = level = 1;
    else if (level == 1 && seen <= 2) t.cmd[n] = level = 0;
    const auto held = std::prev(t.cmd.upper_bound(n));
    x = x + 1 - 2 * held->second;
    t.x.push_back(x);
    t.held_step.push_back(held->first);
  }
  for (int64_t m = 0; m < kSteps / 2; ++m) {
    const auto held = std::prev(t.cmd.upper_bound(2 * m + 1));
    t.log_level.push_back(held->second);
    t.log_at.push_back(held->first);
  }
  return t;
}

// Writes the scenario (three external JSON-lines models) into `d`.
std::filesystem::path write_scenario(const std::filesystem::path& d, const std::string& transport) {
  couple_test::write(d / "types.lcm", "package ev;\n"
                                      "struct cmd_t { int64_t step; int32_t level; }\n"
                                      "struct state_t { int64_t step; int64_t x; int64_t held_step; }\n"
                                      "struct log_t { int64_t step; int32_t level; int64_t at; }\n");
  const std::string loop = "import json, sys\nfor line in sys.stdin:\n    r = json.loads(line)\n"
                           "    if 'init' in r:\n        print(json.dumps({'ok': True}), flush=True)\n        continue\n";
  couple_test::write(d / "plant.py", "x = 0\n" + loop +
                                         "    c = r['inputs']['CMD'][0]\n    x = x + 1 - 2 * c['level']\n"
                                         "    print(json.dumps({'outputs': {'STATE': {'x': x, 'held_step': c['step']}}}), flush=True)\n");
  couple_test::write(d / "controller.py", "level = 0\n" + loop +
                                              "    x = r['inputs']['STATE'][0]['x']\n    out = {}\n"
                                              "    if (level == 0 and x >= 10) or (level == 1 and x <= 2):\n"
                                              "        level = 1 - level\n        out['CMD'] = {'level': level}\n"
                                              "    print(json.dumps({'outputs': out}), flush=True)\n");
  couple_test::write(d / "logger.py", loop +
                                          "    c = r['inputs']['CMD'][0]\n"
                                          "    print(json.dumps({'outputs': {'LOG': {'level': c['level'], 'at': c['step']}}}), flush=True)\n");
  const std::string head = "messages: types.lcm\n";
  couple_test::write(d / "plant.yaml", "name: plant\ndt: 0.01\nend_time: 15\n" + head + "command: [python3, plant.py]\n"
                                       "subscribe:\n  - {channel: CMD, type: ev.cmd_t}\n"
                                       "publish:\n  - {channel: STATE, type: ev.state_t}\n");
  couple_test::write(d / "controller.yaml", "name: controller\ndt: 0.01\nend_time: 15\n" + head +
                                                "command: [python3, controller.py]\n"
                                                "subscribe:\n  - {channel: STATE, type: ev.state_t, lag: 1, initial: {x: 0}}\n"
                                                "publish:\n  - {channel: CMD, type: ev.cmd_t, events: true, initial: {level: 0}}\n");
  couple_test::write(d / "logger.yaml", "name: logger\ndt: 0.02\nend_time: 15\n" + head + "command: [python3, logger.py]\n"
                                        "subscribe:\n  - {channel: CMD, type: ev.cmd_t, substeps: 2}\n"
                                        "publish:\n  - {channel: LOG, type: ev.log_t}\n");
  couple_test::write(d / "scenario.yaml", "name: events\ntransport: " + transport +
                                              "\ntimeout: 20\nmodels: [controller.yaml, plant.yaml, logger.yaml]\n");
  return d / "scenario.yaml";
}

// Compares a recorded log with the truth; returns the number of mismatches (0 = equal).
int mismatches(const std::filesystem::path& log, const ScenarioConfig& sc, const Truth& t, std::string* first) {
  auto got = couple_test::read_log(log, sc);
  int bad = 0;
  auto check = [&](bool ok, const std::string& what) {
    if (!ok && bad++ == 0) *first = what;
  };
  check(got["CMD"].size() == t.cmd.size(), "CMD has " + std::to_string(got["CMD"].size()) + " events, expected " +
                                               std::to_string(t.cmd.size()));
  for (const auto& [n, level] : t.cmd)
    check(got["CMD"].count(n) && got["CMD"][n]["level"] == level, "CMD event at step " + std::to_string(n));
  check(got["STATE"].size() == static_cast<std::size_t>(kSteps), "STATE steps");
  for (int64_t n = 0; n < kSteps; ++n)
    check(got["STATE"].count(n) && got["STATE"][n]["x"] == t.x[n] && got["STATE"][n]["held_step"] == t.held_step[n],
          "STATE step " + std::to_string(n));
  check(got["LOG"].size() == static_cast<std::size_t>(kSteps / 2), "LOG steps");
  for (int64_t m = 0; m < kSteps / 2; ++m)
    check(got["LOG"].count(m) && got["LOG"][m]["level"] == t.log_level[m] && got["LOG"][m]["at"] == t.log_at[m],
          "LOG step " + std::to_string(m));
  return bad;
}

}  // namespace

TEST(EventDriven, TheTruthHasFewEventsAndBothLevels) {
  // The scenario is only a test of events if most steps have none and the hold matters.
  const Truth t = hand_written_loop();
  EXPECT_GT(t.cmd.size(), 50u);
  EXPECT_LT(t.cmd.size(), static_cast<std::size_t>(kSteps / 4));
  std::set<int64_t> levels;
  for (const auto& [n, l] : t.cmd) levels.insert(l);
  EXPECT_EQ(levels.size(), 2u);
}

TEST(EventDriven, EventTrackerKnowsCompletenessOnlyFromCounts) {
  EventTracker e(-1);  // the producer publishes an initial event at step -1
  EXPECT_EQ(e.complete(), -1);
  e.on_count(10, 3);  // 3 events before step 10; none has arrived
  EXPECT_EQ(e.complete(), -1);
  EXPECT_TRUE(e.on_event(7));
  EXPECT_TRUE(e.on_event(-1));
  EXPECT_FALSE(e.on_event(7));  // a duplicate
  EXPECT_EQ(e.complete(), -1);  // the event of step 2 (say) is still on its way
  EXPECT_TRUE(e.on_event(2));
  EXPECT_EQ(e.complete(), 10);
  EXPECT_FALSE(e.on_event(2));  // before the complete step: a re-sent copy
  EXPECT_TRUE(e.on_event(12));  // ahead of the counts
  e.on_count(11, 3);            // step 10 had no event
  EXPECT_EQ(e.complete(), 11);
  e.on_count(9, 2);  // an old report arriving late changes nothing
  EXPECT_EQ(e.complete(), 11);
  e.on_count(20, 4);  // 12 is the fourth
  EXPECT_EQ(e.complete(), 20);
}

TEST(EventDriven, TheGrantOnAnEventChannelFollowsTheProducersCounts) {
  const auto d = couple_test::temp_dir("ev_grant");
  const ScenarioConfig sc = load_scenario(write_scenario(d, "memq://ev_grant"));
  TimeManager plant(sc, "plant");  // CMD: events, lag 0, producer dt 0.01, initial event at -1
  std::string holder;
  // Nothing heard: the initial event (stamp -0.01) may still come.
  EXPECT_NEAR(plant.granted(), -0.01, 1e-15);
  EXPECT_FALSE(plant.may_advance(0, &holder));
  EXPECT_EQ(holder, "controller");
  plant.on_message("CMD", -1);
  EXPECT_FALSE(plant.may_advance(0));  // step 0 may have an event
  // The controller completed 5 steps with 2 events (the initial one and step 3's).
  plant.on_status("controller", 5, false, {{"CMD", 2}});
  EXPECT_NEAR(plant.granted(), -0.01, 1e-15);  // step 3's event is on its way
  EXPECT_FALSE(plant.may_advance(0));
  plant.on_message("CMD", 3);
  EXPECT_NEAR(plant.granted(), 0.05, 1e-15);
  EXPECT_TRUE(plant.may_advance(4));
  EXPECT_FALSE(plant.may_advance(5));
  EXPECT_EQ(plant.events_complete("CMD"), 5);
  // Finished with no more events: everything is granted.
  plant.on_status("controller", kSteps, true, {{"CMD", 2}});
  EXPECT_TRUE(std::isinf(plant.granted()));
  TimeManager logger(sc, "logger");  // substeps 2: its step m needs CMD up to step 2m + 1
  logger.on_message("CMD", -1);
  logger.on_status("controller", 3, false, {{"CMD", 1}});
  EXPECT_TRUE(logger.may_advance(0));   // needs events up to step 1
  EXPECT_FALSE(logger.may_advance(1));  // up to step 3
}

TEST(EventDriven, BadEventConfigsAreClearErrors) {
  const auto d = couple_test::temp_dir("ev_bad");
  write_scenario(d, "memq://ev_bad");
  auto expect_error = [&](const std::string& file, const std::string& text, const std::string& want) {
    couple_test::write(d / file, text);
    try {
      load_scenario(d / "scenario.yaml");
      ADD_FAILURE() << "loaded: " << text;
    } catch (const builtscene::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(want), std::string::npos) << e.what();
    }
  };
  const std::string logger = "name: logger\ndt: 0.02\nend_time: 15\nmessages: types.lcm\ncommand: [python3, logger.py]\n"
                             "publish:\n  - {channel: LOG, type: ev.log_t}\nsubscribe:\n";
  expect_error("logger.yaml", logger + "  - {channel: CMD, type: ev.cmd_t, substeps: 2, history: 2}\n",
               "logger.yaml:9: field 'subscribe[0].history': channel 'CMD' is event-driven (held until the next event): history must be 1");
  couple_test::write(d / "logger.yaml", logger + "  - {channel: CMD, type: ev.cmd_t, substeps: 2}\n");
  expect_error("controller.yaml", "name: controller\ndt: 0.01\nend_time: 15\nmessages: types.lcm\ncommand: [python3, c.py]\n"
                                  "subscribe:\n  - {channel: STATE, type: ev.state_t, lag: 1, initial: {x: 0}}\n"
                                  "publish:\n  - {channel: CMD, type: ev.cmd_t, events: true}\n",
               "channel 'CMD' is event-driven: give 'initial' values for subscription 'CMD' (held until the first event)");
  expect_error("controller.yaml", "name: controller\ndt: 0.01\nend_time: 15\nmessages: types.lcm\ncommand: [python3, c.py]\n"
                                  "publish:\n  - {channel: CMD, type: ev.cmd_t, events: maybe}\n",
               "controller.yaml:7: field 'publish[0].events' has a bad value 'maybe'");
}

TEST(EventDriven, ThreadedRunEqualsTheHandWrittenLoop) {
  const Truth t = hand_written_loop();
  for (const std::string transport : {"memq://ev_clean", "memq://ev_lossy?drop=0.03&seed=11"}) {
    const auto d = couple_test::temp_dir("ev_threads");
    const ScenarioConfig sc = load_scenario(write_scenario(d, transport));
    LaunchOptions lo;
    lo.record = d / "run.lcmlog";
    lo.show_progress = false;
    const LaunchResult r = launch(sc, lo);
    EXPECT_EQ(r.model_steps.at("plant"), kSteps) << transport;
    EXPECT_EQ(r.model_steps.at("logger"), kSteps / 2) << transport;
    std::string first;
    EXPECT_EQ(mismatches(lo.record, sc, t, &first), 0) << transport << ": first mismatch: " << first;
  }
}

TEST(EventDriven, OverTheMediatorNoModelReceivesAMessageBeforeItsGrant) {
  const Truth t = hand_written_loop();
  const auto d = couple_test::temp_dir("ev_mediator");
  const auto scenario = write_scenario(d, "mediator");
  const std::string log = (d / "run.lcmlog").string();
  const auto r = couple_test::run("{ TMPDIR=" + shell_quote(d) + " " + kBin + " couple launch " + shell_quote(scenario) +
                                  " --record " + shell_quote(log) + " --json > " + shell_quote(d / "out.json") + "; }");
  ASSERT_EQ(r.code, 0) << r.out;
  const ScenarioConfig sc = load_scenario(scenario);
  std::string first;
  EXPECT_EQ(mismatches(log, sc, t, &first), 0) << "first mismatch: " << first;
  // Conformance from the log (one server: causal order): every first copy of a message,
  // stamped (s + lag) * dt_P from the configs, against the grants each reader reported before.
  struct Reader {
    std::string model;
    int lag;
    double dt;
  };
  const std::map<std::string, std::vector<Reader>> readers = {
      {"CMD", {{"plant", 0, 0.01}, {"logger", 0, 0.01}}}, {"STATE", {{"controller", 1, 0.01}}}};
  const std::map<std::string, std::string> type = {{"CMD", "ev.cmd_t"}, {"STATE", "ev.state_t"}};
  std::map<std::string, double> granted;
  std::set<std::pair<std::string, int64_t>> seen;
  std::size_t checked = 0, violations = 0;
  LcmLogReader rd(log);
  while (auto e = rd.next()) {
    if (is_status_channel(e->channel)) {
      const auto s = decode_status(sc.types, e->data.data(), e->data.size());
      auto [g, fresh] = granted.emplace(s.model, s.granted);  // grants start below 0 here (the initial event)
      if (!fresh) g->second = std::max(g->second, s.granted);
      continue;
    }
    auto it = readers.find(e->channel);
    if (it == readers.end()) continue;
    const int64_t step = LcmCodec(sc.types, type.at(e->channel)).read_int64(e->data.data(), e->data.size(), "step");
    if (!seen.insert({e->channel, step}).second) continue;
    for (const auto& reader : it->second) {
      const double stamp = static_cast<double>(step + reader.lag) * reader.dt;
      ++checked;
      if (granted.count(reader.model) && stamp < granted[reader.model] - 1e-9 && violations++ < 3)
        ADD_FAILURE() << reader.model << " was granted " << granted[reader.model]
                      << " s, then got " << e->channel << " step " << step << " stamped " << stamp;
    }
  }
  EXPECT_EQ(violations, 0u);
  EXPECT_EQ(checked, 2 * t.cmd.size() + static_cast<std::size_t>(kSteps));
  // The event consumers were granted to the end (the controller's counts reached them).
  EXPECT_GE(granted["plant"], 14.99 - 1e-9);
  EXPECT_GE(granted["logger"], 14.99 - 1e-9);
  EXPECT_EQ(couple_test::left_over(d), "");
}

TEST(EventDriven, ConsumersThatStartAfterTheInitialEventStillGetIt) {
  // Processes start in any order: here the controller runs first and publishes its initial
  // event (step -1) and its first step before the plant and the logger subscribe, so both
  // miss the event on the bus and must have it re-sent. Before the fix the controller had
  // already dropped it (it kept events from its consumers' first regular step on) and the
  // late consumers waited for it for ever (the mediator run above hung or failed in 14 of 25).
  const Truth t = hand_written_loop();
  const auto d = couple_test::temp_dir("ev_late");
  const ScenarioConfig sc = load_scenario(write_scenario(d, "memq://ev_late"));
  std::map<int64_t, std::pair<int64_t, int64_t>> state;  // step -> (x, held_step), heard on the bus
  auto listener = make_transport("memq://ev_late");
  const LcmCodec codec(sc.types, "ev.state_t");
  listener->subscribe("STATE", [&](const std::string&, const uint8_t* p, std::size_t n) {
    state.emplace(codec.read_int64(p, n, "step"), std::make_pair(codec.read_int64(p, n, "x"), codec.read_int64(p, n, "held_step")));
  });
  std::atomic<bool> stop{false};
  std::atomic<int> running{0};
  std::vector<std::unique_ptr<Transport>> transports;
  std::vector<std::unique_ptr<MessageWrapper>> wrappers;
  std::vector<std::thread> threads;
  const auto cwd = std::filesystem::current_path();
  std::filesystem::current_path(d);  // the models' commands are relative to the scenario
  auto start = [&](const std::string& name) {
    transports.push_back(make_transport("memq://ev_late"));
    WrapperOptions wo;
    wo.stop = &stop;
    wo.linger_seconds = 1.0;
    wrappers.push_back(std::make_unique<MessageWrapper>(sc, name, *transports.back(),
                                                        load_model_function(sc.model(name), sc.types), wo));
    ++running;
    threads.emplace_back([&running, w = wrappers.back().get()] {
      w->run();
      --running;
    });
  };
  start("controller");
  // The controller computes step 0 from its initial STATE and then waits for the plant.
  for (int i = 0; i < 1000 && wrappers[0]->steps_done() < 1; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  EXPECT_EQ(wrappers[0]->steps_done(), 1);
  start("plant");
  start("logger");
  // Only a guard against hanging (the old behaviour): stop whatever still runs after 60 s.
  for (int i = 0; i < 6000 && running > 0; ++i) listener->handle(10);
  stop = true;
  for (auto& th : threads) th.join();
  listener->handle(0);
  std::filesystem::current_path(cwd);
  EXPECT_EQ(wrappers[1]->steps_done(), kSteps) << "the plant did not finish";
  EXPECT_EQ(wrappers[2]->steps_done(), kSteps / 2) << "the logger did not finish";
  ASSERT_EQ(state.size(), static_cast<std::size_t>(kSteps));
  int bad = 0;
  for (int64_t n = 0; n < kSteps; ++n)
    if ((state[n].first != t.x[n] || state[n].second != t.held_step[n]) && bad++ < 3)
      ADD_FAILURE() << "STATE step " << n << ": x " << state[n].first << " (truth " << t.x[n] << "), held "
                    << state[n].second << " (truth " << t.held_step[n] << ")";
}
