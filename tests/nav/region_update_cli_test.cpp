// Location-aware point-cloud update (the source's section 2.6.3), end to end on a generated room
// (label: slow). Run A builds the map, its occupancy grid and the first cloud. Run B (another
// seed and path) starts from A's map with a region drawn on A's grid: the SLAM maps inside the
// region and only localizes outside it, and the cloud is updated only there. Checked against the
// world's ground truth, carried into the map with run A's first camera:
//   - the mode switches happen where ground truth crosses the region's border;
//   - the old cloud's points outside the region are kept exactly; the new points inside it lie
//     where a cloud built from run B's ground-truth poses puts the scene.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>

#include <nlohmann/json.hpp>

#include "../common/run_cli.hpp"
#include "io/point_cloud.hpp"
#include "io/trajectory.hpp"
#include "nav/region.hpp"
#include "ogm/ground_frame.hpp"
#include "ogm/map_server_io.hpp"
#include "../common/scratch_dir.hpp"

namespace builtscene {
namespace {

namespace fs = std::filesystem;
using testing::run_cli;
using testing::shell_quote;

// Points of a cloud on a 2 cm hash grid, for nearest-neighbour queries within a few cm.
class PointIndex {
 public:
  explicit PointIndex(const PointCloud& cloud) {
    for (const auto& p : cloud) cells_[cell(p.position.cast<double>())].push_back(p.position.cast<double>());
  }
  double nearest(const Eigen::Vector3d& q, double max) const {
    double best = max;
    const int r = static_cast<int>(std::ceil(max / kCell));
    const auto c = cell(q);
    for (int dx = -r; dx <= r; ++dx)
      for (int dy = -r; dy <= r; ++dy)
        for (int dz = -r; dz <= r; ++dz) {
          const auto it = cells_.find(std::array<long, 3>{c[0] + dx, c[1] + dy, c[2] + dz});
          if (it == cells_.end()) continue;
          for (const auto& p : it->second) best = std::min(best, (p - q).norm());
        }
    return best;
  }

 private:
  static constexpr double kCell = 0.02;
  static std::array<long, 3> cell(const Eigen::Vector3d& p) {
    return {std::lround(std::floor(p.x() / kCell)), std::lround(std::floor(p.y() / kCell)), std::lround(std::floor(p.z() / kCell))};
  }
  std::map<std::array<long, 3>, std::vector<Eigen::Vector3d>> cells_;
};

TEST(RegionUpdateCli, SlamInsideLocalizationOutsideAndOnlyTheRegionsPointsReplaced) {
  const fs::path d = testing::scratch_dir("region_update");
  constexpr int kFrames = 300;
  for (const char* run : {"A", "B"}) {
    const auto r = run_cli(std::string("synth rgbd --scene lab-room --frames ") + std::to_string(kFrames) + " --seed " +
                           (run[0] == 'A' ? "1" : "2") + " --out " + shell_quote(d / run));
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  // Run A: map, grid, first cloud.
  auto r = run_cli("slam --json --sync-mapping --dataset " + shell_quote(d / "A") + " --trajectory " + shell_quote(d / "tA.txt") +
                   " --map-out " + shell_quote(d / "A.bsmap") + " --ogm-out " + shell_quote(d / "grid"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_GE(nlohmann::json::parse(r.out)["tracked_frames"].get<int>(), kFrames * 95 / 100) << r.out;
  const fs::path grid = d / "grid.yaml";
  r = run_cli("cloud --json --dataset " + shell_quote(d / "A") + " --poses " + shell_quote(d / "tA.txt") + " --world " +
              shell_quote(grid) + " --out " + shell_quote(d / "old.ply"));
  ASSERT_EQ(r.exit_code, 0) << r.err;

  // Ground truth in the grid's frame: map world -> truth world from run A's first camera.
  const Trajectory slamA = read_tum_trajectory(d / "tA.txt"), truthA = read_tum_trajectory(d / "A" / "groundtruth.txt");
  ASSERT_NEAR(slamA.front().timestamp, truthA.front().timestamp, 1e-6);
  const SE3 T_tw = truthA.front().pose * slamA.front().pose.inverse();
  const auto T_gw = read_ground_frame(grid);
  ASSERT_TRUE(T_gw.has_value());
  const GroundFrame ground(*T_gw);
  const Trajectory truthB = read_tum_trajectory(d / "B" / "groundtruth.txt");
  std::vector<Pose2D> onGrid;
  for (const auto& p : truthB) onGrid.push_back(ground.to_2d(T_tw.inverse() * p.pose));

  // The region: run B's true positions over frames 120-200, with a 1 m margin (the camera looks
  // at what is around it, not at the floor under its own path).
  double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
  for (int i = 120; i <= 200; ++i) {
    x0 = std::min(x0, onGrid[i].x), x1 = std::max(x1, onGrid[i].x);
    y0 = std::min(y0, onGrid[i].y), y1 = std::max(y1, onGrid[i].y);
  }
  constexpr double kMargin = 1.0;
  const Region region = Region::rectangle(x0 - kMargin, y0 - kMargin, x1 + kMargin, y1 + kMargin);
  const std::string region_text = std::to_string(x0 - kMargin) + "," + std::to_string(y0 - kMargin) + "," +
                                  std::to_string(x1 + kMargin) + "," + std::to_string(y1 + kMargin);
  std::vector<long> crossings;  // first frame on the other side of the border, from ground truth
  for (std::size_t i = 1; i < onGrid.size(); ++i)
    if (region.contains({onGrid[i].x, onGrid[i].y}) != region.contains({onGrid[i - 1].x, onGrid[i - 1].y}))
      crossings.push_back(static_cast<long>(i));
  ASSERT_FALSE(crossings.empty());

  // Run B from A's map, SLAM mode inside the region only.
  r = run_cli("slam --json --sync-mapping --dataset " + shell_quote(d / "B") + " --map-in " + shell_quote(d / "A.bsmap") +
              " --mode localize --slam-region " + region_text + " --world " + shell_quote(grid) + " --trajectory " + shell_quote(d / "tB.txt"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto slamB = nlohmann::json::parse(r.out);
  ASSERT_GE(slamB["tracked_frames"].get<int>(), kFrames * 95 / 100) << r.out;
  std::vector<long> switches;
  std::vector<std::string> to_modes;
  for (const auto& s : slamB["mode_switches"]) {
    if (s["reason"] != "region") continue;
    switches.push_back(s["frame"].get<long>());
    to_modes.push_back(s["to"].get<std::string>());
  }
  // Every border crossing has a switch within 3 frames, and every switch a crossing (the rule
  // acts on the previous frame's pose, and the SLAM's pose is a few mm off near the border).
  auto near_any = [](long f, const std::vector<long>& set) {
    return std::any_of(set.begin(), set.end(), [f](long g) { return std::abs(f - g) <= 3; });
  };
  for (long c : crossings) EXPECT_TRUE(near_any(c, switches)) << "no mode switch near the crossing at frame " << c;
  for (std::size_t k = 0; k < switches.size(); ++k) {
    const long s = switches[k];
    EXPECT_TRUE(near_any(s, crossings)) << "mode switch at frame " << s << " with no crossing";
    // Into SLAM mode when ground truth enters the region, into localization when it leaves.
    const long c = *std::min_element(crossings.begin(), crossings.end(),
                                     [s](long a, long b) { return std::abs(a - s) < std::abs(b - s); });
    EXPECT_EQ(to_modes[k], region.contains({onGrid[c].x, onGrid[c].y}) ? "slam" : "localize") << "frame " << s;
  }
  EXPECT_GT(slamB["keyframes"].get<int>(), slamB["map_in"]["keyframes"].get<int>()) << "no keyframe made inside the region";

  // The update: only run B's frames inside the region, the old cloud replaced there only.
  r = run_cli("cloud --json --dataset " + shell_quote(d / "B") + " --poses " + shell_quote(d / "tB.txt") + " --world " +
              shell_quote(grid) + " --region " + region_text + " --cloud-in " + shell_quote(d / "old.ply") + " --out " +
              shell_quote(d / "new.ply"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const PointCloud old_cloud = read_ply(d / "old.ply"), new_cloud = read_ply(d / "new.ply");
  auto inside = [&](const ColoredPoint& p) { return region.contains({p.position.x(), p.position.y()}); };
  PointCloud old_outside, new_outside, new_inside;
  for (const auto& p : old_cloud)
    if (!inside(p)) old_outside.push_back(p);
  for (const auto& p : new_cloud) (inside(p) ? new_inside : new_outside).push_back(p);
  ASSERT_EQ(new_outside.size(), old_outside.size());
  for (std::size_t i = 0; i < old_outside.size(); ++i) {
    EXPECT_EQ(new_outside[i].position, old_outside[i].position);
    if (new_outside[i].position != old_outside[i].position) break;
  }
  ASSERT_GT(new_inside.size(), 1000u);

  // The same region from run B's ground-truth poses, in the truth world (z up): the new points,
  // carried there, lie on it.
  r = run_cli("cloud --json --dataset " + shell_quote(d / "B") + " --poses " + shell_quote(d / "B" / "groundtruth.txt") +
              " --world zup --out " + shell_quote(d / "truthB.ply"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const PointIndex truth(read_ply(d / "truthB.ply"));
  const SE3 T_tg = T_tw * T_gw->inverse();
  std::vector<double> dist;
  for (const auto& p : new_inside) dist.push_back(truth.nearest(T_tg * p.position.cast<double>(), 0.2));
  std::sort(dist.begin(), dist.end());
  const double median = dist[dist.size() / 2], p90 = dist[dist.size() * 9 / 10];
  EXPECT_LT(median, 0.02) << "median distance of the updated points to the truth cloud, m";
  EXPECT_LT(p90, 0.05) << "90th percentile, m";
  RecordProperty("median_m", std::to_string(median));
  fs::remove_all(d);
}

}  // namespace
}  // namespace builtscene
