// `slam --ogm-out --lcm` on a generated room (label: slow): the occupancy grid the SLAM builds
// live, carried into the world's frame with the reported ground frame and the trajectory's
// alignment to ground truth, lands on the world's truth map; the LCM log holds every batch.
#include <gtest/gtest.h>

#include <fstream>

#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>

#include "../common/run_cli.hpp"
#include "builtscene/poses_and_laser_scans_t.hpp"
#include "io/trajectory.hpp"
#include "ogm/map_server_io.hpp"
#include "../common/scratch_dir.hpp"

namespace builtscene {
namespace {

namespace fs = std::filesystem;
using testing::run_cli;
using testing::shell_quote;

SE3 se3_from_json(const nlohmann::json& t, const nlohmann::json& q) {
  return SE3(Eigen::Quaterniond(q[3].get<double>(), q[0].get<double>(), q[1].get<double>(), q[2].get<double>()),
             Eigen::Vector3d(t[0].get<double>(), t[1].get<double>(), t[2].get<double>()));
}

TEST(SlamOgmCli, LiveGridLandsOnTheTruthMapAndEveryBatchIsPublished) {
  const fs::path d = testing::scratch_dir("slam_ogm");
  auto r = run_cli("synth rgbd --scene lab-room --frames 200 --seed 4 --out " + shell_quote(d / "seq"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_cli("slam --json --sync-mapping --dataset " + shell_quote(d / "seq") + " --trajectory " + shell_quote(d / "t.txt") +
              " --keyframes " + shell_quote(d / "kf.txt") + " --ogm-out " + shell_quote(d / "map") + " --ogm-every 5 --ogm-frames " + shell_quote(d / "frames") + " --lcm " +
              shell_quote("file://" + (d / "live.lcmlog").string() + "?mode=w"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto slam = nlohmann::json::parse(r.out);
  ASSERT_GE(slam["tracked_frames"].get<int>(), 190) << r.out;
  const auto& ogm = slam["ogm"];
  ASSERT_TRUE(ogm.contains("T_gw")) << r.out;

  // The SLAM world -> ground truth world, from the keyframes' alignment.
  r = run_cli("eval ate --json --gt " + shell_quote(d / "seq" / "groundtruth.txt") + " --est " + shell_quote(d / "kf.txt"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto ate = nlohmann::json::parse(r.out);
  ASSERT_LT(ate["rmse"].get<double>(), 0.05);
  const SE3 T_tw = se3_from_json(ate["transform"]["t"], ate["transform"]["q_xyzw"]);
  const auto& g = ogm["T_gw"];
  const SE3 T_gw(Eigen::Quaterniond(g[6].get<double>(), g[3].get<double>(), g[4].get<double>(), g[5].get<double>()),
                 Eigen::Vector3d(g[0].get<double>(), g[1].get<double>(), g[2].get<double>()));
  const SE3 T_tg = T_tw * T_gw.inverse();

  // Occupied cells of the live grid, carried to the truth map (z-up world, floor at 0), must
  // have a truth-occupied cell within 2 cells (1 of mapping tolerance, 1 of resampling).
  const OccupancyGrid live = load_map_server(d / "map.yaml");
  const OccupancyGrid truth = load_map_server(d / "seq" / "truth_map.yaml");
  int occupied = 0, confirmed = 0;
  for (int row = 0; row < live.height(); ++row)
    for (int col = 0; col < live.width(); ++col) {
      if (live.at({col, row}) < 65) continue;
      const Eigen::Vector2d c = live.center_of({col, row});
      const Eigen::Vector3d p = T_tg * Eigen::Vector3d(c.x(), c.y(), 0.5);
      ++occupied;
      bool near = false;
      for (int dy = -2; dy <= 2 && !near; ++dy)
        for (int dx = -2; dx <= 2 && !near; ++dx)
          near = truth.value_at({p.x() + dx * truth.resolution(), p.y() + dy * truth.resolution()}) >= 65;
      confirmed += near;
    }
  ASSERT_GT(occupied, 100);
  EXPECT_GE(static_cast<double>(confirmed) / occupied, 0.90) << confirmed << " of " << occupied;

  // Every batch went out over LCM; the last is the full rebuild with every keyframe.
  lcm::LogFile log((d / "live.lcmlog").string(), "r");
  ASSERT_TRUE(log.good());
  int messages = 0, full = 0;
  builtscene::poses_and_laser_scans_t last;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    if (e->channel != "POSES_AND_LASER_SCANS") continue;
    ASSERT_EQ(last.decode(e->data, 0, e->datalen), e->datalen);
    ++messages;
    full += last.full;
  }
  EXPECT_EQ(messages, ogm["batches"].get<int>());
  EXPECT_EQ(full, ogm["full_batches"].get<int>());
  EXPECT_TRUE(last.full);
  EXPECT_EQ(static_cast<std::size_t>(last.num_keyframes), read_tum_trajectory(d / "kf.txt").size());
  EXPECT_EQ(slam["keyframes"].get<std::size_t>(), read_tum_trajectory(d / "kf.txt").size());
  // --ogm-frames: one picture per keyframe batch of one (the full rebuilds draw none).
  std::size_t pictures = 0;
  for (const auto& e : fs::directory_iterator(d / "frames")) pictures += e.path().extension() == ".png";
  EXPECT_EQ(static_cast<int>(pictures), ogm["batches"].get<int>() - ogm["full_batches"].get<int>());
  fs::remove_all(d);
}

}  // namespace
}  // namespace builtscene
