// The prototype generator: the stub it writes builds with cmake (lcm-gen types, plugin
// glue) into a plugin the wrapper loads, and the model function receives every input
// variable and returns every output variable in the right places. The body the user
// would write is filled in here (y = 2 x + offset, ...) and checked through the codec.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include "couple/lcm_codec.hpp"
#include "couple/model_config.hpp"
#include "couple/model_function.hpp"
#include "couple/prototype_generator.hpp"
#include "test_util.hpp"

using namespace builtscene::couple;
using nlohmann::json;

namespace {

using builtscene::testing::shell_quote;

const char* kTypes = R"(package gen;
struct in_t { int64_t step; double x; int32_t n; float v[n]; string label; }
struct hist_t { int64_t step; double h; }
struct out_t { int64_t step; double y; double v_sum; double x; string label; double history_sum; }
)";

const char* kConfig = R"(name: scaler
dt: 0.5
end_time: 10
plugin: scaler
messages: types.lcm
parameters: {offset: 0.25}
subscribe:
  - channel: IN
    type: gen.in_t
  - channel: HIST
    type: gen.hist_t
    history: 3
    initial: {h: 0}
publish:
  - channel: OUT
    type: gen.out_t
)";

// What a user writes into the generated scaler.cpp.
const char* kBody = R"(#include "scaler_model.hpp"
struct ScalerState { double offset; };
ScalerState* scaler_init(const nlohmann::json& p) { return new ScalerState{p.at("offset").get<double>()}; }
void scaler_free(ScalerState* s) { delete s; }
void scaler(ScalerState& state, int64_t step, double t,
    const decltype(gen::in_t::x)& in_x, const decltype(gen::in_t::n)& n, const decltype(gen::in_t::v)& v,
    const decltype(gen::in_t::label)& in_label, const std::vector<gen::hist_t>& hist_history,
    decltype(gen::out_t::y)& y, decltype(gen::out_t::v_sum)& v_sum, decltype(gen::out_t::x)& x,
    decltype(gen::out_t::label)& label, decltype(gen::out_t::history_sum)& history_sum) {
  y = 2 * in_x + state.offset + 0 * t + 0 * static_cast<double>(step);
  v_sum = 0;
  for (int i = 0; i < n; ++i) v_sum += v[static_cast<size_t>(i)];
  x = in_x;
  label = in_label + "!";
  history_sum = 100 * hist_history[0].h + 10 * hist_history[1].h + hist_history[2].h;
}
)";

}  // namespace

TEST(PrototypeGenerator, StubBuildsWithCmakeAndTheWrapperCallsIt) {
  const auto d = couple_test::temp_dir("generator");
  couple_test::write(d / "types.lcm", kTypes);
  couple_test::write(d / "scaler.yaml", kConfig);
  const auto gen = couple_test::run(shell_quote(BUILTSCENE_BINARY) + " couple new-model --config " +
                                    shell_quote(d / "scaler.yaml") + " --out " + shell_quote(d / "stub") + " --json");
  ASSERT_EQ(gen.code, 0) << gen.out;
  // The prototype names the model and lists every variable (x and label clash with outputs).
  std::ifstream h(d / "stub" / "scaler_model.hpp");
  std::stringstream ss;
  ss << h.rdbuf();
  const std::string header = ss.str();
  for (const char* part : {"void scaler(ScalerState& state, int64_t step, double t", "in_x", "& n", "& v", "in_label",
                           "const std::vector<gen::hist_t>& hist_history", "& y", "& v_sum", "& x", "& label",
                           "& history_sum"})
    EXPECT_NE(header.find(part), std::string::npos) << part << "\n" << header;
  // The untouched stub builds, as does the filled-in one (the user's edit).
  auto build = [&](const std::string& tag) {
    return couple_test::run("cd " + shell_quote(d / "stub") + " && timeout 120 cmake -S . -B build-" + tag +
                            " -DCMAKE_BUILD_TYPE=Release > /dev/null && timeout 120 cmake --build build-" + tag);
  };
  const auto plain = build("plain");
  ASSERT_EQ(plain.code, 0) << plain.out;
  couple_test::write(d / "stub" / "scaler.cpp", kBody);
  const auto filled = build("filled");
  ASSERT_EQ(filled.code, 0) << filled.out;

  ModelConfig cfg = load_model_config(d / "scaler.yaml");
  cfg.plugin = (d / "stub" / "build-filled" / "libscaler.so").string();
  TypeRegistry types;
  types.parse_file(d / "types.lcm");
  auto fn = load_model_function(cfg, types);
  LcmCodec in(types, "gen.in_t"), hist(types, "gen.hist_t"), out(types, "gen.out_t");
  const Bytes a = in.encode({{"step", 4}, {"x", 1.5}, {"n", 3}, {"v", {1.0, 2.0, 4.5}}, {"label", "abc"}});
  const Bytes h0 = hist.encode({{"step", 4}, {"h", 3.0}}), h1 = hist.encode({{"step", 3}, {"h", 2.0}}),
              h2 = hist.encode({{"step", 2}, {"h", 1.0}});
  std::vector<Bytes> outputs(1);
  fn->step(4, 2.0, {{&a}, {&h0, &h1, &h2}}, outputs);
  const json o = out.decode(outputs[0]);
  EXPECT_EQ(o["step"], 4);
  EXPECT_DOUBLE_EQ(o["y"].get<double>(), 3.25);
  EXPECT_DOUBLE_EQ(o["v_sum"].get<double>(), 7.5);
  EXPECT_DOUBLE_EQ(o["x"].get<double>(), 1.5);
  EXPECT_EQ(o["label"], "abc!");
  EXPECT_DOUBLE_EQ(o["history_sum"].get<double>(), 321.0);
}

TEST(PrototypeGenerator, PythonStubSpeaksJsonLines) {
  const auto d = couple_test::temp_dir("generator_py");
  couple_test::write(d / "types.lcm", kTypes);
  couple_test::write(d / "scaler.yaml", kConfig);
  ASSERT_EQ(couple_test::run(shell_quote(BUILTSCENE_BINARY) + " couple new-model --config " +
                             shell_quote(d / "scaler.yaml") + " --out " + shell_quote(d / "stub")).code,
            0);
  const auto r = couple_test::run(
      "printf '%s\\n' '{\"init\": {\"offset\": 1}}' "
      "'{\"step\": 0, \"t\": 0, \"inputs\": {\"IN\": [{\"x\": 1, \"n\": 0, \"v\": [], \"label\": \"a\"}], "
      "\"HIST\": [{\"h\": 0}, {\"h\": 0}, {\"h\": 0}]}}' '{\"save\": true}' '{\"load\": null}' | python3 " +
      shell_quote(d / "stub" / "scaler.py"));
  ASSERT_EQ(r.code, 0) << r.out;
  std::istringstream lines(r.out);
  std::string l1, l2, l3, l4;
  std::getline(lines, l1);
  std::getline(lines, l2);
  std::getline(lines, l3);
  std::getline(lines, l4);
  // The stub answers the checkpoint requests but says it keeps no checkpoints until the
  // user fills in save()/load() and sets CHECKPOINTS.
  EXPECT_EQ(json::parse(l1), json({{"ok", true}, {"checkpoint", false}}));
  EXPECT_EQ(json::parse(l3), json({{"state", nullptr}}));
  EXPECT_EQ(json::parse(l4), json({{"ok", true}}));
  const json reply = json::parse(l2);
  ASSERT_TRUE(reply.contains("outputs")) << l2;
  for (const char* k : {"y", "v_sum", "x", "label", "history_sum"}) EXPECT_TRUE(reply["outputs"]["OUT"].contains(k)) << k;
}
