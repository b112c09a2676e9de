// `builtscene plan` end to end on a map_server map written by the test.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include <nlohmann/json.hpp>

#include "../common/run_cli.hpp"
#include "../common/scratch_dir.hpp"
#include "ogm/map_server_io.hpp"

namespace builtscene {
namespace {

namespace fs = std::filesystem;
using testing::line_count;
using testing::run_cli;
using testing::shell_quote;

// 10 m x 6 m room (5 cm cells) with a wall at x = 5 m from y = 0 to y = 4.5 m: the way from
// the left half to the right half goes through the 1.5 m gap at the top.
fs::path write_room() {
  OccupancyGrid g(200, 120, 0.05, {0, 0}, 0);
  for (int r = 0; r < 120; ++r)
    for (int c = 0; c < 200; ++c)
      if (r == 0 || c == 0 || r == 119 || c == 199 || (c == 100 && r < 90)) g.at({c, r}) = 100;
  const auto dir = testing::scratch_dir("plan_cli");
  save_map_server(g, dir / "room.yaml");
  return dir;
}

TEST(PlanCli, PlansAroundTheWallAndWritesPathAndPicture) {
  const auto dir = write_room();
  const auto r = run_cli("plan --json --map " + shell_quote(dir / "room.yaml") +
                         " --start 2,1 --goal 8,1 --robot-radius 0.2 --out " + shell_quote(dir / "path.csv") +
                         " --png " + shell_quote(dir / "path.png"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  // Lower bound: via the wall's top end (5, 4.5) kept 0.2 m clear: two legs of at least
  // hypot(3, 3.7) each. The straight line (6 m) is blocked.
  const double lower = 2 * std::hypot(3.0, 3.7);
  EXPECT_GT(j["length_m"].get<double>(), lower - 0.1);
  EXPECT_LT(j["length_m"].get<double>(), lower * 1.25);
  EXPECT_GT(j["cells_expanded"].get<int>(), 0);
  EXPECT_TRUE(j.contains("ms"));
  std::ifstream csv(dir / "path.csv");
  std::string header, line;
  std::getline(csv, header);
  EXPECT_EQ(header, "x,y");
  double max_y = 0;
  int rows = 0;
  while (std::getline(csv, line)) {
    const double y = std::stod(line.substr(line.find(',') + 1));
    max_y = std::max(max_y, y);
    ++rows;
  }
  EXPECT_GT(rows, 10);
  EXPECT_GT(max_y, 4.5 + 0.2);  // went over the wall's end with clearance
  EXPECT_TRUE(fs::exists(dir / "path.png"));
}

TEST(PlanCli, BadStartGoalAndMapAreExitTwoWithOneLine) {
  const auto dir = write_room();
  const std::string map = " --map " + shell_quote(dir / "room.yaml");
  struct Case {
    std::string args, expect;
  };
  const std::vector<Case> cases{
      {map + " --start 20,1 --goal 8,1", "off the map"},
      {map + " --start 2,1 --goal 5.02,2", "inside an obstacle"},
      {map + " --start 2,1 --goal 8,abc", "--goal"},
      {" --map " + shell_quote(dir / "none.yaml") + " --start 2,1 --goal 8,1", "none.yaml"},
      {map + " --start 2,1 --goal 8,1 --robot-radius 0.8", "unreachable"},  // 1.5 m gap < 1.6 m robot
  };
  for (const auto& c : cases) {
    const auto r = run_cli("plan --json" + c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.err;
    EXPECT_EQ(line_count(r.err), 1) << r.err;
    EXPECT_NE(r.err.find(c.expect), std::string::npos) << r.err;
    EXPECT_TRUE(r.out.empty());
  }
}

}  // namespace
}  // namespace builtscene
