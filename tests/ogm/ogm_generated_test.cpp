// The occupancy grid on a generated world against the world's own geometry (label: slow).
#include <gtest/gtest.h>

#include <algorithm>

#include <cmath>

#include <fstream>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "../common/run_cli.hpp"
#include "../common/scratch_dir.hpp"
#include "io/trajectory.hpp"
#include "ogm/map_server_io.hpp"

namespace builtscene {
namespace {

namespace fs = std::filesystem;
using testing::run_cli;
using testing::shell_quote;

// The generated room and the maps the tests build, one folder per process (ctest runs tests in
// parallel processes), removed when the process exits.
const fs::path& work() {
  static const fs::path d = testing::scratch_dir("ogm_lab");
  return d;
}

const fs::path& lab_room() {
  static const fs::path dir = [] {
    const auto d = work() / "room";
    const auto r = run_cli("synth rgbd --scene lab-room --motion robot --frames 450 --seed 3 --out " + shell_quote(d));
    EXPECT_EQ(r.exit_code, 0) << r.err;
    return d;
  }();
  return dir;
}

nlohmann::json build(const fs::path& out, const std::string& extra) {
  const auto r = run_cli("ogm build --json --keyframes-only --dataset " + shell_quote(lab_room()) + " --poses " +
                         shell_quote(lab_room() / "groundtruth.txt") + " --out " + shell_quote(out) + " " + extra);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return r.exit_code == 0 ? nlohmann::json::parse(r.out) : nlohmann::json();
}

 void check_map_scores() {
  const auto j = build(work() / "map", "--truth " + shell_quote(lab_room() / "truth_map.yaml"));
  ASSERT_TRUE(j.contains("score"));
  EXPECT_GE(j["score"]["occupied_precision"].get<double>(), 0.90);
  EXPECT_GE(j["score"]["occupied_recall"].get<double>(), 0.85);
  EXPECT_GE(j["score"]["free_agreement"].get<double>(), 0.95);
  EXPECT_GT(j["score"]["estimated_occupied"].get<int>(), 300);
}

// Inside a rotated box's footprint, at least `margin` from its edges.
bool in_footprint(const nlohmann::json& box, const Eigen::Vector2d& p, double margin) {
  const double yaw = box["yaw"].get<double>();
  const Eigen::Vector2d c(box["center"][0].get<double>(), box["center"][1].get<double>());
  const Eigen::Vector2d d = p - c;
  const double u = std::cos(yaw) * d.x() + std::sin(yaw) * d.y(), v = -std::sin(yaw) * d.x() + std::cos(yaw) * d.y();
  return std::abs(u) <= box["size"][0].get<double>() / 2 - margin && std::abs(v) <= box["size"][1].get<double>() / 2 - margin;
}

void check_desk_tops() {
  const auto band = work() / "band";
  const auto one = work() / "one_height";
  build(band, "--world zup");
  build(one, "--world zup --min-height 0.29 --max-height 0.31");  // a 2D lidar at 0.30 m
  const OccupancyGrid a = load_map_server(fs::path(band.string() + ".yaml"));
  const OccupancyGrid b = load_map_server(fs::path(one.string() + ".yaml"));
  std::ifstream in(lab_room() / "scene.json");
  const auto scene = nlohmann::json::parse(in);
  std::vector<nlohmann::json> tops, legs;
  for (const auto& box : scene["boxes"]) {
    if (box["name"] == "desk_top") tops.push_back(box);
    if (box["name"] == "desk_leg") legs.push_back(box);
  }
  ASSERT_FALSE(tops.empty());
  // Cells under desk tops, 10 cm away from every leg: only the top can make them occupied.
  int band_hits = 0, one_hits = 0, cells = 0;
  for (int r = 0; r < a.height(); ++r)
    for (int c = 0; c < a.width(); ++c) {
      const Eigen::Vector2d p = a.center_of({c, r});
      bool under_top = false, near_leg = false;
      for (const auto& t : tops) under_top |= in_footprint(t, p, 0.0);
      for (const auto& l : legs) near_leg |= in_footprint(l, p, -0.10);
      if (!under_top || near_leg) continue;
      ++cells;
      band_hits += occupancy_class(a.at({c, r})) == 1;
      one_hits += occupancy_class(b.value_at(p)) == 1;
    }
  ASSERT_GT(cells, 100);
  EXPECT_GE(band_hits, 20) << "of " << cells << " cells under desk tops";
  EXPECT_LE(one_hits, 2) << "of " << cells << " cells under desk tops";
}

// --frame-images: one picture per integrated frame, named by its dataset frame; the last one
// shows the final grid, so it equals the map's own picture pixel for pixel.
void check_frame_images() {
  const auto out = work() / "frames";
  const auto dir = work() / "frames_dir";
  const auto j = build(out, "--frame-images " + shell_quote(dir));
  ASSERT_TRUE(j.contains("scans"));
  std::vector<fs::path> pictures;
  for (const auto& e : fs::directory_iterator(dir)) pictures.push_back(e.path());
  std::sort(pictures.begin(), pictures.end());
  ASSERT_EQ(pictures.size(), j["scans"].get<std::size_t>());
  EXPECT_EQ(pictures.front().filename(), "frame_000000.png");  // the first frame is always used
  const cv::Mat last = cv::imread(pictures.back().string()), final_map = cv::imread(j["png"].get<std::string>());
  ASSERT_FALSE(last.empty());
  ASSERT_EQ(last.size(), final_map.size());
  EXPECT_EQ(cv::norm(last, final_map, cv::NORM_INF), 0.0);
  const cv::Mat first = cv::imread(pictures.front().string());
  EXPECT_LT(first.total(), last.total()) << "the grid grows as frames arrive";
}

// `ogm compare --est --gt`: a map built in another world (the ground truth moved by a known
// rigid motion that also tilts it, y down like a SLAM's first camera), its floor found from
// the data, carried back into the truth's frame, scores like the map built there directly.
void check_carried_comparison() {
  const SE3 T_moved_world(Eigen::Quaterniond(Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitX()) *
                                             Eigen::AngleAxisd(0.6, Eigen::Vector3d::UnitZ())),
                          Eigen::Vector3d(1.5, -0.7, 2.0));
  Trajectory moved = read_tum_trajectory(lab_room() / "groundtruth.txt");
  for (auto& p : moved) p.pose = T_moved_world * p.pose;
  const auto moved_path = work() / "moved.txt";
  write_tum_trajectory(moved_path, moved);
  const auto out = work() / "moved_map";
  const auto r0 = run_cli("ogm build --json --keyframes-only --world auto --dataset " + shell_quote(lab_room()) +
                          " --poses " + shell_quote(moved_path) + " --out " + shell_quote(out));
  ASSERT_EQ(r0.exit_code, 0) << r0.err;
  const std::string truth = shell_quote(lab_room() / "truth_map.yaml"), gt = shell_quote(lab_room() / "groundtruth.txt");
  const auto r = run_cli("ogm compare --json --map " + shell_quote(out.string() + ".yaml") + " --truth " + truth +
                         " --est " + shell_quote(moved_path) + " --gt " + gt);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_GE(j["occupied_precision"].get<double>(), 0.90) << r.out;
  EXPECT_GE(j["occupied_recall"].get<double>(), 0.85) << r.out;
  EXPECT_GE(j["free_agreement"].get<double>(), 0.95) << r.out;
  EXPECT_LT(j["aligned"]["ate_rmse"].get<double>(), 1e-6);
  // Without the carry the same map does not land on the truth.
  const auto raw = run_cli("ogm compare --json --map " + shell_quote(out.string() + ".yaml") + " --truth " + truth);
  ASSERT_EQ(raw.exit_code, 0) << raw.err;
  EXPECT_LT(nlohmann::json::parse(raw.out)["occupied_precision"].get<double>(), 0.5) << raw.out;
  // Bad input: --est alone, and a map with no ground frame to carry.
  auto bad = run_cli("ogm compare --map " + shell_quote(out.string() + ".yaml") + " --truth " + truth + " --est " + gt);
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("--gt"), std::string::npos) << bad.err;
  bad = run_cli("ogm compare --map " + truth + " --truth " + truth + " --est " + gt + " --gt " + gt);
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("ground_frame_T_gw"), std::string::npos) << bad.err;
  EXPECT_NE(bad.err.find("truth_map.yaml"), std::string::npos) << bad.err;
}

// One test: the checks share one generated lab room (generating it takes most of the time).
TEST(OgmGenerated, LabRoomMapMatchesTheTrueMapAndSeesDeskTopsThatOneHeightMisses) {
  check_map_scores();
  check_desk_tops();
  check_frame_images();
  check_carried_comparison();
}

}  // namespace
}  // namespace builtscene
