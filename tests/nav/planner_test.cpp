#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <queue>
#include <random>

#include "core/errors.hpp"
#include "nav/astar_planner.hpp"

namespace builtscene {
namespace {

OccupancyGrid free_grid(int w, int h, double res = 0.05) { return OccupancyGrid(w, h, res, {0, 0}, 0); }

void fill_rect(OccupancyGrid& g, int c0, int r0, int c1, int r1, std::int8_t v = 100) {
  for (int r = r0; r <= r1; ++r)
    for (int c = c0; c <= c1; ++c) g.at({c, r}) = v;
}

// Reference: plain Dijkstra over the same step costs (no heuristic, no shared search code).
double dijkstra_cost(const AStarPlanner& p, const Costmap& cm, GridIndex s, GridIndex t) {
  const int w = cm.width(), h = cm.height();
  std::vector<double> d(static_cast<std::size_t>(w * h), std::numeric_limits<double>::infinity());
  using E = std::pair<double, int>;
  std::priority_queue<E, std::vector<E>, std::greater<>> q;
  d[static_cast<std::size_t>(s.row * w + s.col)] = 0;
  q.push({0, s.row * w + s.col});
  while (!q.empty()) {
    auto [dist, i] = q.top();
    q.pop();
    if (dist > d[static_cast<std::size_t>(i)]) continue;
    const GridIndex c{i % w, i / w};
    if (c == t) return dist;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const GridIndex n{c.col + dx, c.row + dy};
        if ((!dx && !dy) || n.col < 0 || n.row < 0 || n.col >= w || n.row >= h || !p.can_step(c, n)) continue;
        const double nd = dist + p.step_cost(c, n);
        auto& dn = d[static_cast<std::size_t>(n.row * w + n.col)];
        if (nd < dn) {
          dn = nd;
          q.push({nd, n.row * w + n.col});
        }
      }
  }
  return std::numeric_limits<double>::infinity();
}

TEST(Costmap, InflationFollowsTheDecayFormula) {
  OccupancyGrid g = free_grid(61, 61);
  g.at({30, 30}) = 100;
  CostmapOptions o;
  o.robot_radius = 0.2;
  o.inflation_radius = 0.8;
  o.cost_scaling = 3.0;
  const Costmap cm(g, o);
  EXPECT_EQ(cm.cost({30, 30}), Costmap::kLethal);
  for (int dc = 1; dc <= 30; ++dc) {
    const double d = dc * 0.05;
    const int expected = d <= 0.2 ? 253 : d <= 0.8 ? static_cast<int>(std::lround(252 * std::exp(-3.0 * (d - 0.2)))) : 0;
    EXPECT_EQ(cm.cost({30 + dc, 30}), expected) << d;
  }
  // A diagonal cell 3 cells away each way: d = 0.05 * sqrt(18) = 0.212 > 0.2.
  EXPECT_NEAR(cm.obstacle_distance({33, 33}), 0.05 * std::sqrt(18.0), 1e-5);
  EXPECT_LT(cm.cost({33, 33}), 253);
}

TEST(AStar, OpenFloorPathIsTheOctileDistance) {
  const OccupancyGrid g = free_grid(200, 100);
  const Costmap cm(g, {});
  const AStarPlanner p(cm);
  const auto r = p.plan(GridIndex{10, 10}, GridIndex{150, 60});
  ASSERT_TRUE(r.found);
  const double expected = 0.05 * (90 + 50 * std::sqrt(2.0));  // 50 diagonal + 90 straight steps
  EXPECT_NEAR(r.length_m, expected, 1e-9);
  EXPECT_NEAR(r.cost, expected, 1e-9);
}

TEST(AStar, AgreesWithDijkstraAndStaysOutOfInflatedCells) {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 5; ++trial) {
    OccupancyGrid g = free_grid(120, 90);
    std::uniform_int_distribution<int> cx(0, 110), cy(0, 80), len(3, 25);
    for (int k = 0; k < 25; ++k) {  // random walls and blocks
      const int c = cx(rng), r = cy(rng);
      if (k % 2) fill_rect(g, c, r, std::min(119, c + len(rng)), std::min(89, r + 1));
      else fill_rect(g, c, r, std::min(119, c + 1), std::min(89, r + len(rng)));
    }
    fill_rect(g, 0, 0, 119, 0);
    fill_rect(g, 0, 89, 119, 89);
    CostmapOptions o;
    o.robot_radius = 0.1;
    o.inflation_radius = 0.4;
    const Costmap cm(g, o);
    const AStarPlanner p(cm);
    int planned = 0;
    for (int q = 0; q < 20; ++q) {
      const GridIndex s{cx(rng), cy(rng)}, t{cx(rng), cy(rng)};
      if (!cm.traversable(s, false) || !cm.traversable(t, false)) continue;
      const auto r = p.plan(s, t);
      const double ref = dijkstra_cost(p, cm, s, t);
      EXPECT_EQ(r.found, std::isfinite(ref));
      if (!r.found) continue;
      ++planned;
      EXPECT_LE(r.cost, ref * 1.08);  // the bound; an admissible heuristic gives equality
      EXPECT_NEAR(r.cost, ref, 1e-9 * ref);
      for (std::size_t k = 0; k < r.cells.size(); ++k) {
        EXPECT_LT(cm.cost(r.cells[k]), Costmap::kInscribed);
        if (k) {
          EXPECT_LE(std::max(std::abs(r.cells[k].col - r.cells[k - 1].col), std::abs(r.cells[k].row - r.cells[k - 1].row)), 1);
        }
      }
    }
    EXPECT_GT(planned, 5);
  }
}

TEST(AStar, BadStartsAndGoalsAreInputErrors) {
  OccupancyGrid g = free_grid(100, 100);
  fill_rect(g, 40, 0, 41, 99);  // a wall across the map: the right half is unreachable
  const Costmap cm(g, {});
  const AStarPlanner p(cm);
  EXPECT_THROW(p.plan(Eigen::Vector2d(-1, 1), Eigen::Vector2d(1, 1)), InputError);           // start off the map
  EXPECT_THROW(p.plan(Eigen::Vector2d(1, 1), Eigen::Vector2d(2.02, 1)), InputError);         // goal in the wall
  EXPECT_THROW(p.plan(Eigen::Vector2d(1, 1), Eigen::Vector2d(1.9, 1)), InputError);          // within robot radius
  const auto r = p.plan(Eigen::Vector2d(1, 1), Eigen::Vector2d(4, 4));
  EXPECT_FALSE(r.found);  // unreachable is reported by the result; the CLI turns it into exit 2
  try {
    p.plan(Eigen::Vector2d(1, 1), Eigen::Vector2d(9, 1));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--goal"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("off the map"), std::string::npos);
  }
}

}  // namespace
}  // namespace builtscene
