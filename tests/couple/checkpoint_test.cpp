// Recovery from a model's own checkpoint: a model with hidden state (a running sum),
// built from the generated prototype with its save/load hooks filled in, is killed
// mid-run over the mediator; the restarted process loads its last checkpoint and goes on
// from there (not from step 0), and the results equal the closed form and an
// uninterrupted run. The model writes each step it computes to a trace file: the
// independent evidence of where the second process started.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>

#include "couple/model_config.hpp"
#include "test_util.hpp"

using namespace builtscene::couple;
using nlohmann::json;

namespace {

using builtscene::testing::shell_quote;

const std::string kBin = shell_quote(BUILTSCENE_BINARY);

// y_n = sum over i <= n of x_i with x_i = 0.5 i + 1 (exact in binary floating point).
double closed_form(int64_t n) {
  const auto m = static_cast<double>(n);
  return 0.25 * m * (m + 1) + m + 1;
}

// What a user writes into the generated acc.cpp: the sum is hidden state, not a message.
const char* kAccBody = R"(#include "acc_model.hpp"
#include <cstdio>
#include <cstring>
struct AccState { double sum = 0; std::string trace; };
AccState* acc_init(const nlohmann::json& p) { return new AccState{0, p.at("trace").get<std::string>()}; }
void acc_free(AccState* s) { delete s; }
void acc(AccState& state, int64_t step, double t, const decltype(cp::x_t::x)& x, decltype(cp::y_t::y)& y) {
  (void)t;
  state.sum += x;
  y = state.sum;
  if (FILE* f = std::fopen(state.trace.c_str(), "a")) {
    std::fprintf(f, "%lld\n", static_cast<long long>(step));
    std::fclose(f);
  }
}
bool acc_save(const AccState& state, std::string& bytes) {
  bytes.assign(reinterpret_cast<const char*>(&state.sum), sizeof state.sum);
  return true;
}
bool acc_load(AccState& state, const std::string& bytes) {
  if (bytes.size() != sizeof state.sum) return false;
  std::memcpy(&state.sum, bytes.data(), sizeof state.sum);
  return true;
}
)";

std::vector<int64_t> read_trace(const std::filesystem::path& p) {
  std::vector<int64_t> steps;
  std::ifstream f(p);
  int64_t s;
  while (f >> s) steps.push_back(s);
  return steps;
}

}  // namespace

TEST(Checkpoint, AKilledModelResumesFromItsCheckpointAndTheResultsAreIdentical) {
  const auto d = couple_test::temp_dir("checkpoint");
  couple_test::write(d / "types.lcm", "package cp;\nstruct x_t { int64_t step; double x; }\nstruct y_t { int64_t step; double y; }\n");
  couple_test::write(d / "src.py",
                     "import json,sys\nfor line in sys.stdin:\n    r=json.loads(line)\n"
                     "    print(json.dumps({'ok':True} if 'init' in r else {'outputs':{'X':{'x':0.5*r['step']+1}}}), flush=True)\n");
  const std::string head = "dt: 0.01\nend_time: 20\nmessages: types.lcm\n";
  couple_test::write(d / "src.yaml", "name: src\n" + head + "command: [python3, " + (d / "src.py").string() +
                                         "]\npublish:\n  - {channel: X, type: cp.x_t}\n");
  const std::string acc_yaml = "name: acc\n" + head + "plugin: " + (d / "stub" / "build" / "libacc.so").string() +
                               "\ncheckpoint_every: 500\nparameters: {trace: TRACE}\n"
                               "subscribe:\n  - {channel: X, type: cp.x_t}\npublish:\n  - {channel: Y, type: cp.y_t}\n";
  couple_test::write(d / "acc.yaml", acc_yaml);
  // The stub from the generator, with the body (and the optional hooks) filled in.
  const auto gen = couple_test::run(kBin + " couple new-model --config " + shell_quote(d / "acc.yaml") + " --out " +
                                    shell_quote(d / "stub"));
  ASSERT_EQ(gen.code, 0) << gen.out;
  std::stringstream header;
  header << std::ifstream(d / "stub" / "acc_model.hpp").rdbuf();
  EXPECT_NE(header.str().find("bool acc_save(const AccState& state, std::string& bytes);"), std::string::npos)
      << header.str();
  EXPECT_NE(header.str().find("bool acc_load(AccState& state, const std::string& bytes);"), std::string::npos);
  couple_test::write(d / "stub" / "acc.cpp", kAccBody);
  const auto build = couple_test::run("cd " + shell_quote(d / "stub") +
                                      " && timeout 120 cmake -S . -B build -DCMAKE_BUILD_TYPE=Release > /dev/null"
                                      " && timeout 120 cmake --build build");
  ASSERT_EQ(build.code, 0) << build.out;

  auto run = [&](const std::string& tag, const std::string& extra) {
    couple_test::write(d / ("acc-" + tag + ".yaml"),
                       std::regex_replace(acc_yaml, std::regex("TRACE"), (d / (tag + ".trace")).string()));
    couple_test::write(d / ("scenario-" + tag + ".yaml"),
                       "name: cp\ntransport: mediator\ntimeout: 10\nmodels: [src.yaml, acc-" + tag + ".yaml]\n");
    return couple_test::run("{ TMPDIR=" + shell_quote(d) + " " + kBin + " couple launch " +
                            shell_quote(d / ("scenario-" + tag + ".yaml")) + " --record " +
                            shell_quote(d / (tag + ".lcmlog")) + " --json " + extra + " > " +
                            shell_quote(d / (tag + ".json")) + "; }");
  };
  const auto a = run("a", "");
  ASSERT_EQ(a.code, 0) << a.out;
  const auto b = run("b", "--kill acc@1234");
  ASSERT_EQ(b.code, 0) << b.out;
  EXPECT_EQ(json::parse(std::ifstream(d / "b.json"))["restarts"]["acc"], 1);
  EXPECT_NE(b.out.find("acc: resumed from its checkpoint at step 1000"), std::string::npos) << b.out;

  // The first process computed 0..1233 and was killed before 1234; the second started at
  // the last checkpoint before that (1000), not at 0.
  std::vector<int64_t> want;
  for (int64_t s = 0; s < 1234; ++s) want.push_back(s);
  for (int64_t s = 1000; s < 2000; ++s) want.push_back(s);
  EXPECT_EQ(read_trace(d / "b.trace"), want);
  EXPECT_EQ(read_trace(d / "a.trace").size(), 2000u);

  const ScenarioConfig sc = load_scenario(d / "scenario-a.yaml");
  auto ya = couple_test::read_log(d / "a.lcmlog", sc)["Y"], yb = couple_test::read_log(d / "b.lcmlog", sc)["Y"];
  ASSERT_EQ(ya.size(), 2000u);
  ASSERT_EQ(yb.size(), 2000u);
  std::size_t exact = 0;
  for (int64_t n = 0; n < 2000; ++n)
    exact += ya[n]["y"].get<double>() == closed_form(n) && yb[n]["y"].get<double>() == closed_form(n);
  EXPECT_EQ(exact, 2000u);
  EXPECT_EQ(couple_test::left_over(d), "");
}

TEST(Checkpoint, AKilledExternalJsonLinesModelResumesFromItsCheckpoint) {
  // The same running sum as an external python3 program with the protocol's save/load
  // requests: its state (the sum) travels as JSON through the mediator.
  const auto d = couple_test::temp_dir("checkpoint_ext");
  couple_test::write(d / "types.lcm", "package cp;\nstruct x_t { int64_t step; double x; }\nstruct y_t { int64_t step; double y; }\n");
  couple_test::write(d / "src.py",
                     "import json,sys\nfor line in sys.stdin:\n    r=json.loads(line)\n"
                     "    print(json.dumps({'ok':True} if 'init' in r else {'outputs':{'X':{'x':0.5*r['step']+1}}}), flush=True)\n");
  couple_test::write(d / "acc.py",
                     "import json,sys\ntotal = 0.0\ntrace = None\nfor line in sys.stdin:\n    r = json.loads(line)\n"
                     "    if 'init' in r:\n        trace = r['init']['trace']\n        reply = {'ok': True, 'checkpoint': True}\n"
                     "    elif 'save' in r:\n        reply = {'state': {'sum': total}}\n"
                     "    elif 'load' in r:\n        total = r['load']['sum']\n        reply = {'ok': True}\n"
                     "    else:\n        total += r['inputs']['X'][0]['x']\n"
                     "        open(trace, 'a').write('%d\\n' % r['step'])\n"
                     "        reply = {'outputs': {'Y': {'y': total}}}\n"
                     "    print(json.dumps(reply), flush=True)\n");
  const std::string head = "dt: 0.01\nend_time: 20\nmessages: types.lcm\n";
  couple_test::write(d / "src.yaml", "name: src\n" + head + "command: [python3, src.py]\npublish:\n  - {channel: X, type: cp.x_t}\n");
  auto run = [&](const std::string& tag, const std::string& extra) {
    couple_test::write(d / ("acc-" + tag + ".yaml"),
                       "name: acc\n" + head + "command: [python3, acc.py]\ncheckpoint_every: 500\nparameters: {trace: " +
                           (d / (tag + ".trace")).string() +
                           "}\nsubscribe:\n  - {channel: X, type: cp.x_t}\npublish:\n  - {channel: Y, type: cp.y_t}\n");
    couple_test::write(d / ("scenario-" + tag + ".yaml"),
                       "name: cp\ntransport: mediator\ntimeout: 10\nmodels: [src.yaml, acc-" + tag + ".yaml]\n");
    return couple_test::run("{ TMPDIR=" + shell_quote(d) + " " + kBin + " couple launch " +
                            shell_quote(d / ("scenario-" + tag + ".yaml")) + " --record " +
                            shell_quote(d / (tag + ".lcmlog")) + " --json " + extra + " > " +
                            shell_quote(d / (tag + ".json")) + "; }");
  };
  const auto a = run("a", "");
  ASSERT_EQ(a.code, 0) << a.out;
  const auto b = run("b", "--kill acc@1234");
  ASSERT_EQ(b.code, 0) << b.out;
  EXPECT_EQ(json::parse(std::ifstream(d / "b.json"))["restarts"]["acc"], 1);
  EXPECT_NE(b.out.find("acc: resumed from its checkpoint at step 1000"), std::string::npos) << b.out;
  std::vector<int64_t> want;
  for (int64_t s = 0; s < 1234; ++s) want.push_back(s);
  for (int64_t s = 1000; s < 2000; ++s) want.push_back(s);
  EXPECT_EQ(read_trace(d / "b.trace"), want);
  const ScenarioConfig sc = load_scenario(d / "scenario-a.yaml");
  auto ya = couple_test::read_log(d / "a.lcmlog", sc)["Y"], yb = couple_test::read_log(d / "b.lcmlog", sc)["Y"];
  ASSERT_EQ(ya.size(), 2000u);
  ASSERT_EQ(yb.size(), 2000u);
  std::size_t exact = 0;
  for (int64_t n = 0; n < 2000; ++n)
    exact += ya[n]["y"].get<double>() == closed_form(n) && yb[n]["y"].get<double>() == closed_form(n);
  EXPECT_EQ(exact, 2000u);
  EXPECT_EQ(couple_test::left_over(d), "");
}

TEST(Checkpoint, AnExternalModelThatCannotSaveStopsTheRunWithItsName) {
  const auto d = couple_test::temp_dir("checkpoint_ext_bad");
  couple_test::write(d / "types.lcm", "package cp;\nstruct y_t { int64_t step; double y; }\n");
  // Says it checkpoints but answers a save request without a state.
  couple_test::write(d / "bad.py",
                     "import json,sys\nfor line in sys.stdin:\n    r = json.loads(line)\n"
                     "    reply = {'ok': True, 'checkpoint': True} if 'init' in r else {'nope': 1} if 'save' in r "
                     "else {'outputs': {'Y': {'y': 1.0}}}\n    print(json.dumps(reply), flush=True)\n");
  couple_test::write(d / "bad.yaml", "name: bad\ndt: 0.1\nend_time: 10\nmessages: types.lcm\ncommand: [python3, bad.py]\n"
                                     "checkpoint_every: 10\npublish:\n  - {channel: Y, type: cp.y_t}\n");
  couple_test::write(d / "scenario.yaml", "name: cp\ntransport: mediator\ntimeout: 10\nmodels: [bad.yaml]\n");
  const auto r = couple_test::run("{ TMPDIR=" + shell_quote(d) + " " + kBin + " couple launch " +
                                  shell_quote(d / "scenario.yaml") + "; }");
  EXPECT_EQ(r.code, 1) << r.out;
  EXPECT_NE(r.out.find("model 'bad' could not save its checkpoint: no 'state' in its reply {\"nope\":1}"), std::string::npos)
      << r.out;
  EXPECT_EQ(couple_test::left_over(d), "");
}
