// The time manager's grants, against values worked out by hand from the stamp rule
// stamp(s) = (s + lag) * dt_producer + lookahead_producer (see time_manager.hpp).
#include <gtest/gtest.h>

#include <cmath>

#include "core/errors.hpp"
#include "couple/time_manager.hpp"
#include "test_util.hpp"

using namespace builtscene::couple;

namespace {

ScenarioConfig example() { return load_scenario(couple_test::kExample + "/scenario.yaml"); }

// p (dt 0.1, lookahead L) publishes A; q (dt 0.05) reads A every 2 of its steps.
ScenarioConfig ratio_pair(const std::string& tag, double lookahead) {
  const auto d = couple_test::temp_dir(tag);
  couple_test::write(d / "types.lcm", "package t;\nstruct a_t { int64_t step; double x; }\n");
  couple_test::write(d / "p.yaml", "name: p\ndt: 0.1\nend_time: 1.0\nlookahead: " + std::to_string(lookahead) +
                                       "\nplugin: none\nmessages: types.lcm\npublish:\n  - {channel: A, type: t.a_t}\n");
  couple_test::write(d / "q.yaml", "name: q\ndt: 0.05\nend_time: 1.0\nplugin: none\nmessages: types.lcm\n"
                                   "subscribe:\n  - {channel: A, type: t.a_t, every: 2}\npublish:\n  - {channel: B, type: t.a_t}\n");
  couple_test::write(d / "s.yaml", "name: s\ntransport: memq://x\nmodels: [p.yaml, q.yaml]\n");
  return load_scenario(d / "s.yaml");
}

}  // namespace

TEST(TimeManager, AModelWithoutInputsIsGrantedEverything) {
  const auto sc = example();
  TimeManager wind(sc, "wind");
  EXPECT_TRUE(std::isinf(wind.granted()));
  EXPECT_TRUE(wind.may_advance(0));
  EXPECT_TRUE(wind.may_advance(5999));
}

TEST(TimeManager, TheStructureControllerCycleIsBrokenByTheLagWithInitialData) {
  const auto sc = example();
  TimeManager ctrl(sc, "controller");  // STRUCTURE with lag 1 (initial data), WIND
  std::string holder;
  // Step 0 needs STRUCTURE step -1 (the initial values) and WIND step 0 (stamp 0).
  EXPECT_DOUBLE_EQ(ctrl.granted(), 0.0);
  EXPECT_FALSE(ctrl.may_advance(0, &holder));
  EXPECT_EQ(holder, "wind");
  ctrl.on_message("WIND", 0);
  EXPECT_TRUE(ctrl.may_advance(0));
  // STRUCTURE step 0 is stamped (0 + 1) * 0.01 = 0.01; WIND step 1 is stamped 0.01.
  EXPECT_NEAR(ctrl.granted(), 0.01, 1e-15);
  ctrl.on_message("WIND", 1);
  EXPECT_FALSE(ctrl.may_advance(1, &holder));  // needs STRUCTURE step 0, not here
  EXPECT_EQ(holder, "structure");
  ctrl.on_message("STRUCTURE", 0);
  EXPECT_TRUE(ctrl.may_advance(1));
  EXPECT_NEAR(ctrl.granted(), 0.02, 1e-15);

  TimeManager st(sc, "structure");  // WIND and CONTROL with lag 0; its own STRUCTURE is local
  st.on_message("WIND", 0);
  EXPECT_FALSE(st.may_advance(0, &holder));
  EXPECT_EQ(holder, "controller");
  st.on_message("CONTROL", 0);
  EXPECT_TRUE(st.may_advance(0));
  EXPECT_THROW(st.stamp("STRUCTURE", 0), builtscene::InputError);
}

TEST(TimeManager, AStatusDoesNotGrantPastAMessageStillOnItsWay) {
  const auto sc = example();
  TimeManager ctrl(sc, "controller");
  // The wind reports 10 steps done, but its step 0 has not arrived (another subscription
  // may deliver out of order): the grant stays at that message's stamp.
  ctrl.on_status("wind", 10, false);
  ctrl.on_status("structure", 3, false);
  EXPECT_DOUBLE_EQ(ctrl.granted(), 0.0);
  for (int s = 0; s < 10; ++s) ctrl.on_message("WIND", s);
  // STRUCTURE: nothing received, so its step 0 (stamp 0.01) bounds the grant.
  EXPECT_NEAR(ctrl.granted(), 0.01, 1e-15);
  for (int s = 0; s < 3; ++s) ctrl.on_message("STRUCTURE", s);
  // min(wind: stamp(10) = 0.10, structure: stamp(3) = 0.04)
  EXPECT_NEAR(ctrl.granted(), 0.04, 1e-15);
  EXPECT_TRUE(ctrl.may_advance(3));   // needs STRUCTURE 2 (0.03) and WIND 3 (0.03)
  EXPECT_FALSE(ctrl.may_advance(4));  // needs STRUCTURE 3 (0.04)
  // A gap: step 5 without 4 does not move the grant past step 4's stamp.
  ctrl.on_message("STRUCTURE", 4 + 1);
  EXPECT_NEAR(ctrl.granted(), 0.04, 1e-15);
  // Finished producers bound nothing once all their steps are in.
  ctrl.on_status("wind", 6000, true);
  for (int s = 10; s < 6000; ++s) ctrl.on_message("WIND", s);
  ctrl.on_message("STRUCTURE", 3);
  ctrl.on_message("STRUCTURE", 4);
  EXPECT_NEAR(ctrl.granted(), 0.07, 1e-15);  // STRUCTURE 0..5 here: stamp(6) = 0.07
}

TEST(TimeManager, LookaheadAndRatiosShiftTheStamps) {
  const auto sc = ratio_pair("tm_ratio", 0.25);
  TimeManager q(sc, "q");
  // A step s of p is stamped s * 0.1 + 0.25; q's step n needs p step floor(n / 2).
  EXPECT_NEAR(q.stamp("A", 3), 0.55, 1e-12);
  EXPECT_NEAR(q.granted(), 0.25, 1e-12);
  EXPECT_FALSE(q.may_advance(0));
  q.on_message("A", 0);
  EXPECT_NEAR(q.granted(), 0.35, 1e-12);
  EXPECT_TRUE(q.may_advance(0));
  EXPECT_TRUE(q.may_advance(1));   // still p step 0
  EXPECT_FALSE(q.may_advance(2));  // p step 1
  const auto bad = couple_test::temp_dir("tm_bad");
  couple_test::write(bad / "types.lcm", "package t;\nstruct a_t { int64_t step; double x; }\n");
  couple_test::write(bad / "p.yaml", "name: p\ndt: 0.1\nend_time: 1.0\nlookahead: -1\nplugin: none\n"
                                     "messages: types.lcm\npublish:\n  - {channel: A, type: t.a_t}\n");
  try {
    load_model_config(bad / "p.yaml");
    FAIL() << "a negative lookahead loaded";
  } catch (const builtscene::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("p.yaml:4: field 'lookahead' must not be negative"), std::string::npos)
        << e.what();
  }
}
