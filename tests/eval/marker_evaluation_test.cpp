#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>

#include <nlohmann/json.hpp>

#include "../common/run_cli.hpp"
#include "../common/scratch_dir.hpp"
#include "core/errors.hpp"
#include "eval/marker_evaluation.hpp"

namespace builtscene {
namespace {

namespace fs = std::filesystem;

// 15 floor markers around a 20 m x 10 m rectangle (z = 0).
std::vector<MarkerTruth> loop_markers() {
  std::vector<MarkerTruth> t;
  for (int i = 0; i < 15; ++i) {
    const double s = 60.0 * i / 15.0;  // perimeter position
    Eigen::Vector3d p;
    if (s < 20) p = {s, 0, 0};
    else if (s < 30) p = {20, s - 20, 0};
    else if (s < 50) p = {50 - s, 10, 0};
    else p = {0, 60 - s, 0};
    t.push_back({i + 1, p, 0, 0.2});
  }
  return t;
}

// The map frame: a SLAM world (y down, z forward) rotated and shifted against the markers'.
SE3 truth_to_map() {
  Eigen::Matrix3d to_camera_axes;
  to_camera_axes << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  return SE3(Eigen::Matrix3d(to_camera_axes * Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()).toRotationMatrix()),
             Eigen::Vector3d(3, 1, -2));
}

// Four measurements of every marker, in the map frame T, each `offset(id, k)` off its true
// place (truth frame).
template <typename Offset>
std::vector<MarkerMeasurement> measure(const std::vector<MarkerTruth>& truth, const SE3& T, Offset offset) {
  std::vector<MarkerMeasurement> ms;
  std::size_t frame = 0;
  for (const auto& t : truth)
    for (int k = 0; k < 4; ++k) {
      const Eigen::Vector3d p = t.position + offset(t.id, k);
      ms.push_back({frame++, 0.1 * static_cast<double>(frame), t.id, T * p, 2.0, 10});
    }
  return ms;
}

TEST(MarkerEvaluation, ClosedFormRmseAndDistanceRmseUnderAKnownMapTransform) {
  const auto truth = loop_markers();
  const SE3 T = truth_to_map();
  // Marker 1 is measured at +-5 cm along x (mean exact: RMSE 0.05); the rest exactly.
  const auto ms = measure(truth, T, [](int id, int k) {
    return Eigen::Vector3d(id == 1 ? (k % 2 ? 0.05 : -0.05) : 0.0, 0, 0);
  });
  const auto e = evaluate_markers(ms, truth, MarkerAlignment::k3D);
  ASSERT_EQ(e.markers.size(), 15u);
  EXPECT_NEAR(e.markers[0].rmse, 0.05, 1e-9);
  EXPECT_NEAR(e.markers[0].stddev.x(), 0.05, 1e-9);
  EXPECT_NEAR(e.markers[0].mean_estimate.x(), truth[0].position.x(), 1e-9);
  for (std::size_t i = 1; i < 15; ++i) EXPECT_NEAR(e.markers[i].rmse, 0.0, 1e-9);
  EXPECT_NEAR(e.max_rmse, 0.05, 1e-9);
  // Marker 1 -> 2 lies along x (4 m apart): distances 4 +- 0.05, RMSE 0.05. The closing pair
  // 15 -> 1 lies along y: distances sqrt(4^2 + 0.05^2), RMSE sqrt(16.0025) - 4.
  EXPECT_EQ(e.distances.size(), 15u);
  EXPECT_NEAR(e.distances[0].rmse, 0.05, 1e-9);
  EXPECT_NEAR(e.distances.back().rmse, std::sqrt(16.0025) - 4.0, 1e-9);
  EXPECT_NEAR(e.max_distance_rmse, 0.05, 1e-9);
  // The recovered alignment is the inverse of the map transform.
  EXPECT_LT((e.map_to_truth.matrix() - T.inverse().matrix()).norm(), 1e-9);
}

// The 2D evaluation in a SLAM world (y down, floor in x-z): the up axis comes from the plane
// of the floor markers, so the horizontal errors are the ones put in, and a height error
// (the map's up axis) costs nothing horizontally.
TEST(MarkerEvaluation, TwoDimensionalAlignmentFindsTheFloorOfACameraFrameMap) {
  const auto truth = loop_markers();
  const SE3 T = truth_to_map();
  const auto ms = measure(truth, T, [](int id, int k) {
    const double s = k % 2 ? 1.0 : -1.0;
    return Eigen::Vector3d(id == 1 ? 0.05 * s : 0.0,   // horizontal: RMSE 0.05
                           0, id == 8 ? 0.03 * s : 0.0);  // vertical only: no horizontal error
  });
  const auto e = evaluate_markers(ms, truth, MarkerAlignment::k2D);
  EXPECT_TRUE(e.up_from_markers);
  ASSERT_EQ(e.markers.size(), 15u);
  EXPECT_NEAR(e.markers[0].rmse, 0.05, 1e-9);
  for (std::size_t i = 1; i < 15; ++i) EXPECT_NEAR(e.markers[i].rmse, 0.0, 1e-9) << "marker " << i + 1;
  EXPECT_NEAR(e.markers[7].rmse_3d, 0.03, 1e-9);
  EXPECT_NEAR(e.max_rmse, 0.05, 1e-9);
  EXPECT_LT((e.map_to_truth.matrix() - T.inverse().matrix()).norm(), 1e-9);
  EXPECT_EQ(to_json(e)["map_up"], "markers_plane");

  // Markers on a line leave the plane open: the map's own z is taken as up (z-up map).
  std::vector<MarkerMeasurement> line;
  for (const auto& m : ms)
    if (m.id <= 5) line.push_back({m.frame, m.time, m.id, T.inverse() * m.position + Eigen::Vector3d(1, 2, 0), 2.0, 10});
  const auto l = evaluate_markers(line, truth, MarkerAlignment::k2D);
  EXPECT_FALSE(l.up_from_markers);
  EXPECT_NEAR(l.markers[0].rmse, 0.05, 1e-9);
  for (std::size_t i = 1; i < 5; ++i) EXPECT_NEAR(l.markers[i].rmse, 0.0, 1e-9);
}

TEST(MarkerEvaluation, UnknownUnseenAndTooFewMarkers) {
  const auto truth = loop_markers();
  // Markers 1-3 measured where they are, and an id the survey does not list.
  std::vector<MarkerMeasurement> ms{{0, 0, 1, truth[0].position, 1, 0},
                                    {0, 0, 2, truth[1].position, 1, 0},
                                    {0, 0, 3, truth[2].position, 1, 0},
                                    {0, 0, 99, Eigen::Vector3d(50, 50, 0), 1, 0}};
  const auto e = evaluate_markers(ms, truth, MarkerAlignment::k2D);
  EXPECT_EQ(e.unknown_ids, std::vector<int>{99});
  EXPECT_EQ(e.unseen_ids.size(), 12u);
  EXPECT_EQ(e.markers[5].times, 0u);
  std::vector<MarkerMeasurement> two(ms.begin(), ms.begin() + 2);
  EXPECT_THROW(evaluate_markers(two, truth, MarkerAlignment::k3D), InputError);
}

TEST(MarkerEvaluationCli, WritesTablesAndJsonAndRejectsBadInput) {
  const auto dir = testing::scratch_dir("eval_markers");
  {
    std::ofstream t(dir / "truth.csv");
    t << "id,x,y,z,yaw,size\n";
    for (const auto& m : loop_markers()) t << m.id << ',' << m.position.x() << ',' << m.position.y() << ",0,0,0.2\n";
  }
  std::vector<MarkerMeasurement> ms;
  for (const auto& m : loop_markers()) ms.push_back({0, 0, m.id, truth_to_map() * m.position, 2, 5});
  write_marker_measurements(dir / "measured.csv", ms);
  const auto r = testing::run_cli("eval markers --json --measured " + testing::shell_quote(dir / "measured.csv") +
                                  " --truth " + testing::shell_quote(dir / "truth.csv") + " --out " + testing::shell_quote(dir / "out"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["markers"].size(), 15u);
  EXPECT_LT(j["max_rmse"].get<double>(), 1e-4);  // the CSV keeps 5 decimals (10 um)
  EXPECT_TRUE(j["markers"][0].contains("times"));
  for (const char* f : {"markers.md", "markers_table.csv", "distances_table.csv", "markers.png"}) EXPECT_TRUE(fs::exists(dir / "out" / f)) << f;
  std::ofstream(dir / "two.csv") << "frame,time,id,x,y,z,distance,angle_deg\n0,0,1,0,0,0,1,0\n0,0,2,1,0,0,1,0\n";
  const auto bad = testing::run_cli("eval markers --measured " + testing::shell_quote(dir / "two.csv") + " --truth " + testing::shell_quote(dir / "truth.csv"));
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.err.find("at least 3"), std::string::npos) << bad.err;
}

}  // namespace
}  // namespace builtscene
