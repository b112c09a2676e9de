// `localize` with its per-frame outputs (label: slow), on the generated basement corridor: a map
// built in SLAM mode on one robot run, then localization on a second run of another seed. Every
// output is checked against the world's ground truth, carried into the map's frame with the
// first camera of the first run (the map frame is the SLAM's first camera). The runs are
// rendered without sensor noise: with Kinect noise the SLAM's corridor map is stretched by ~9 %
// (ATE with sim3 alignment: scale 1.09; issue 4 is open on it), which would test the SLAM's
// accuracy rather than these outputs.
//   --ogm/--poses2d: the 2D pose on the grid is where ground truth puts the robot;
//   --poi/--poi-events/--lcm: one event per point of interest, at the frame where ground truth
//     enters its radius, as a JSON line and as an LCM message;
//   --markers-out: every floor tag that ground truth puts in view is measured, at its surveyed
//     position.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>

#include "../common/run_cli.hpp"
#include "builtscene/poi_event_t.hpp"
#include "io/trajectory.hpp"
#include "io/tum_dataset.hpp"
#include "markers/marker_measurements.hpp"
#include "ogm/ground_frame.hpp"
#include "ogm/map_server_io.hpp"
#include "../common/scratch_dir.hpp"

namespace builtscene {
namespace {

namespace fs = std::filesystem;
using testing::run_cli;
using testing::shell_quote;

struct Row2d {
  std::size_t frame;
  double x, y;
};

std::vector<Row2d> read_poses2d(const fs::path& p) {
  std::ifstream f(p);
  std::string line;
  std::getline(f, line);
  EXPECT_EQ(line, "frame,time,x,y,theta,beams,beams_on_map");
  std::vector<Row2d> rows;
  while (std::getline(f, line)) {
    std::stringstream s(line);
    std::string cell;
    std::vector<double> v;
    while (std::getline(s, cell, ',')) v.push_back(std::stod(cell));
    EXPECT_EQ(v.size(), 7u) << line;
    if (v.size() == 7) rows.push_back({static_cast<std::size_t>(v[0]), v[2], v[3]});
  }
  return rows;
}

TEST(LocalizeOutputsCli, PoseOnTheGridPoiEventsAndMarkersAgreeWithGroundTruth) {
  const fs::path d = testing::scratch_dir("localize_outputs");
  constexpr int kFrames = 400;
  for (const char* seed : {"1", "2"}) {
    const auto r = run_cli("synth rgbd --scene corridor-loop --motion robot --frames " + std::to_string(kFrames) +
                           " --seed " + seed + " --noise none --out " + shell_quote(d / ("run" + std::string(seed))));
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  // The map, with its occupancy grid, from the first run.
  auto r = run_cli("slam --json --sync-mapping --dataset " + shell_quote(d / "run1") + " --trajectory " +
                   shell_quote(d / "t1.txt") + " --map-out " + shell_quote(d / "map.bsmap") + " --ogm-out " +
                   shell_quote(d / "grid"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ASSERT_GE(nlohmann::json::parse(r.out)["tracked_frames"].get<int>(), kFrames * 95 / 100) << r.out;
  // Map world -> truth world from the first frame of run 1: the robot drives a straight line,
  // so aligning positions alone (eval ate) leaves the roll about that line undetermined.
  const Trajectory slam1 = read_tum_trajectory(d / "t1.txt"), truth1 = read_tum_trajectory(d / "run1" / "groundtruth.txt");
  ASSERT_FALSE(slam1.empty());
  ASSERT_NEAR(slam1.front().timestamp, truth1.front().timestamp, 1e-6);
  const SE3 T_tw = truth1.front().pose * slam1.front().pose.inverse();
  const auto T_gw = read_ground_frame(d / "grid.yaml");
  ASSERT_TRUE(T_gw.has_value());
  const GroundFrame ground(*T_gw);

  // Where ground truth puts the second run's robot on the grid, per frame.
  const TumDataset run2 = TumDataset::open(d / "run2", {});
  const Trajectory truth2 = read_tum_trajectory(d / "run2" / "groundtruth.txt");
  ASSERT_EQ(truth2.size(), static_cast<std::size_t>(kFrames));
  std::vector<Pose2D> expected;
  for (const auto& p : truth2) expected.push_back(ground.to_2d(T_tw.inverse() * p.pose));

  // Two points of interest on the second run's true path, 0.3 m in radius; the frame each is
  // first entered, from ground truth.
  const std::vector<std::size_t> poi_frames{120, 330};
  constexpr double kRadius = 0.3;
  {
    std::ofstream pois(d / "pois.csv");
    pois << "name,x,y,radius\n";
    for (std::size_t k = 0; k < poi_frames.size(); ++k)
      pois << "poi" << k << ',' << expected[poi_frames[k]].x << ',' << expected[poi_frames[k]].y << ',' << kRadius << '\n';
  }
  std::vector<std::size_t> entered(poi_frames.size(), 0);
  for (std::size_t k = 0; k < poi_frames.size(); ++k)
    for (std::size_t i = 0; i < expected.size(); ++i)
      if (std::hypot(expected[i].x - expected[poi_frames[k]].x, expected[i].y - expected[poi_frames[k]].y) <= kRadius) {
        entered[k] = i;
        break;
      }

  r = run_cli("localize --json --dataset " + shell_quote(d / "run2") + " --map " + shell_quote(d / "map.bsmap") +
              " --trajectory " + shell_quote(d / "t2.txt") + " --ogm " + shell_quote(d / "grid.yaml") + " --poses2d " +
              shell_quote(d / "poses2d.csv") + " --ogm-png " + shell_quote(d / "track.png") + " --poi " +
              shell_quote(d / "pois.csv") + " --poi-events " + shell_quote(d / "events.jsonl") + " --lcm " +
              shell_quote("file://" + (d / "events.lcmlog").string() + "?mode=w") + " --markers-out " +
              shell_quote(d / "measured.csv") + " --sizes-from " + shell_quote(d / "run2" / "markers.csv"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto loc = nlohmann::json::parse(r.out);
  ASSERT_GE(loc["tracked_frames"].get<int>(), kFrames * 95 / 100) << r.out;
  EXPECT_TRUE(fs::exists(d / "track.png"));

  // 2D pose on the grid against ground truth.
  const auto rows = read_poses2d(d / "poses2d.csv");
  ASSERT_EQ(rows.size(), loc["tracked_frames"].get<std::size_t>());
  double sq = 0;
  for (const auto& row : rows) sq += std::pow(row.x - expected[row.frame].x, 2) + std::pow(row.y - expected[row.frame].y, 2);
  const double rmse_2d = std::sqrt(sq / static_cast<double>(rows.size()));
  EXPECT_LT(rmse_2d, 0.05) << "2D pose RMSE on the grid, m";
  RecordProperty("pose2d_rmse_m", std::to_string(rmse_2d));

  // One event per point of interest, within a few frames of where ground truth enters it, in
  // the JSON summary, the JSON-lines file and the LCM log alike.
  const auto& events = loc["poi_events"];
  ASSERT_EQ(events.size(), poi_frames.size()) << events.dump();
  std::ifstream lines(d / "events.jsonl");
  std::string line;
  std::size_t k = 0;
  for (; std::getline(lines, line); ++k) {
    ASSERT_LT(k, poi_frames.size());
    const auto e = nlohmann::json::parse(line);
    EXPECT_EQ(e, events[k]);
    EXPECT_EQ(e["poi"].get<std::string>(), "poi" + std::to_string(k));
    EXPECT_NEAR(static_cast<double>(e["frame"].get<std::size_t>()), static_cast<double>(entered[k]), 4.0) << line;
  }
  EXPECT_EQ(k, poi_frames.size());
  lcm::LogFile log((d / "events.lcmlog").string(), "r");
  ASSERT_TRUE(log.good());
  std::vector<std::string> lcm_pois;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    if (e->channel != "POI_EVENTS") continue;
    builtscene::poi_event_t msg;
    ASSERT_EQ(msg.decode(e->data, 0, e->datalen), e->datalen);
    lcm_pois.push_back(msg.poi);
    EXPECT_EQ(static_cast<std::size_t>(msg.frame), events[lcm_pois.size() - 1]["frame"].get<std::size_t>());
  }
  EXPECT_EQ(lcm_pois, (std::vector<std::string>{"poi0", "poi1"}));

  // Markers: the tags that ground truth puts in view (centre inside the image with a margin,
  // under 3 m away, in 5 frames or more) are all measured, and each one's mean measured
  // position, carried to the world, is its surveyed position.
  const auto survey = read_marker_truth(d / "run2" / "markers.csv");
  const PinholeCamera& cam = run2.settings().camera;
  std::set<int> in_view;
  for (const auto& tag : survey) {
    int frames = 0;
    for (const auto& p : truth2) {
      const Eigen::Vector3d pc = p.pose.inverse() * tag.position;
      if (pc.z() < 0.5 || pc.norm() > 3.0) continue;
      const Eigen::Vector2d px = cam.project(pc);
      frames += px.x() > 40 && px.x() < cam.width - 40 && px.y() > 40 && px.y() < cam.height - 40;
    }
    if (frames >= 5) in_view.insert(tag.id);
  }
  ASSERT_GE(in_view.size(), 2u) << "the corridor run should pass floor tags";
  std::map<int, std::pair<Eigen::Vector3d, int>> mean;
  for (const auto& m : read_marker_measurements(d / "measured.csv")) {
    auto& [sum, n] = mean.try_emplace(m.id, Eigen::Vector3d::Zero(), 0).first->second;
    sum += T_tw * m.position;
    ++n;
  }
  for (const int id : in_view) EXPECT_TRUE(mean.count(id)) << "tag " << id << " in view but not measured";
  for (const auto& tag : survey) {
    if (!mean.count(tag.id)) continue;
    const auto& [sum, n] = mean.at(tag.id);
    const Eigen::Vector3d p = sum / n;
    EXPECT_LT((p.head<2>() - tag.position.head<2>()).norm(), 0.05) << "tag " << tag.id << " at " << p.transpose();
  }
  EXPECT_EQ(loc["markers"]["measurements"].get<std::size_t>(), read_marker_measurements(d / "measured.csv").size());
  fs::remove_all(d);
}

}  // namespace
}  // namespace builtscene
