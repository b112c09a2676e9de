#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include <nlohmann/json.hpp>

#include "../common/run_cli.hpp"
#include "../common/scratch_dir.hpp"
#include "core/errors.hpp"
#include "eval/marker_detection_error.hpp"

namespace builtscene {
namespace {

namespace fs = std::filesystem;

SE3 pose(double yaw, double pitch, const Eigen::Vector3d& t) {
  return SE3(Eigen::Matrix3d(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitX())), t);
}

// A survey of 5 floor markers; each is measured 4 times from its own true camera pose, with a
// known detection error e = bias(id) +- spread(id) along y. The localization's poses are wrong
// by a different transform in every frame (a distorted map in another frame), so the markers'
// map-frame positions are far off; only the detection error may come back.
struct World {
  std::vector<MarkerTruth> survey;
  std::vector<MarkerMeasurement> measured;
  Trajectory localized, truth;
  static Eigen::Vector3d bias(int id) { return {0.001 * id, -0.002, 0.0005 * id}; }
  static double spread(int id) { return 0.003 * id; }
  World() {
    for (int id = 1; id <= 5; ++id) survey.push_back({id, Eigen::Vector3d(4.0 * id, 1.0 + 0.3 * id * id, 0.0015), 0, 0.2});
    std::size_t frame = 0;
    for (const auto& s : survey)
      for (int k = 0; k < 4; ++k, ++frame) {
        const double t = 1.0 + frame / 30.0;
        const SE3 T_true = pose(0.3 * k - 0.5, -1.9, s.position + Eigen::Vector3d(-2.0 + 0.2 * k, 0.3, 0.5));
        const SE3 map_error = pose(0.02 * static_cast<double>(frame), 0.7, Eigen::Vector3d(3.0, -1.0 + 0.05 * static_cast<double>(frame), 2.0));
        const SE3 T_loc = map_error * T_true;
        const Eigen::Vector3d e = bias(s.id) + Eigen::Vector3d(0, (k % 2 ? 1.0 : -1.0) * spread(s.id), 0);
        const Eigen::Vector3d p_camera = T_true.inverse() * (s.position + e);  // what the detector saw
        measured.push_back({frame, t, s.id, T_loc * p_camera, p_camera.norm(), 30});
        truth.push_back({t, T_true});
        localized.push_back({t, T_loc});
      }
  }
};

TEST(MarkerDetectionError, TrueCameraPosesLeaveExactlyTheDetectionsOwnError) {
  const World w;
  const auto d = marker_detection_errors(w.measured, w.survey, w.localized, w.truth);
  ASSERT_EQ(d.markers.size(), 5u);
  EXPECT_EQ(d.used, 20u);
  EXPECT_EQ(d.without_pose, 0u);
  double max_rmse = 0;
  for (const auto& m : d.markers) {
    EXPECT_EQ(m.times, 4u);
    EXPECT_LT((m.bias - World::bias(m.id)).norm(), 1e-9) << m.id;
    const double rmse = std::sqrt(World::bias(m.id).squaredNorm() + World::spread(m.id) * World::spread(m.id));  // closed form
    EXPECT_NEAR(m.rmse, rmse, 1e-9) << m.id;
    max_rmse = std::max(max_rmse, rmse);
  }
  EXPECT_NEAR(d.max_rmse, max_rmse, 1e-9);
}

TEST(MarkerDetectionError, MeasurementsWithoutAPoseOrASurveyedIdAreLeftOut) {
  World w;
  w.localized.erase(w.localized.begin());       // frame 0 (marker 1) has no localized pose
  w.truth.erase(w.truth.begin() + 5);           // frame 5 (marker 2) has no true pose
  w.measured.push_back({99, 50.0, 42, Eigen::Vector3d::Zero(), 1, 0});  // an id the survey lacks
  const auto d = marker_detection_errors(w.measured, w.survey, w.localized, w.truth);
  EXPECT_EQ(d.used, 18u);
  EXPECT_EQ(d.without_pose, 2u);
  EXPECT_EQ(d.markers[0].times, 3u);
  EXPECT_EQ(d.markers[1].times, 3u);
  // Times 1 ms off still find their frame; none within 0.02 s is an error, not an empty table.
  Trajectory shifted = w.truth;
  for (auto& p : shifted) p.timestamp += 0.001;
  EXPECT_EQ(marker_detection_errors(w.measured, w.survey, w.localized, shifted).used, 18u);
  for (auto& p : shifted) p.timestamp += 1.0;
  EXPECT_THROW(marker_detection_errors(w.measured, w.survey, w.localized, shifted), InputError);
}

TEST(MarkerDetectionError, CommandLineReportsItBesideTheMarkerTables) {
  const World w;
  const fs::path dir = testing::scratch_dir("marker_detection");
  write_marker_measurements(dir / "measured.csv", w.measured);
  {
    std::ofstream s(dir / "survey.csv");
    s << "id,x,y,z,yaw,size\n";
    for (const auto& m : w.survey) s << m.id << "," << m.position.x() << "," << m.position.y() << "," << m.position.z() << ",0,0.2\n";
  }
  write_tum_trajectory(dir / "loc.txt", w.localized);
  write_tum_trajectory(dir / "gt.txt", w.truth);
  const auto q = [](const fs::path& p) { return testing::shell_quote(p.string()); };
  const std::string base = "eval markers --json --measured " + q(dir / "measured.csv") + " --truth " + q(dir / "survey.csv");
  const auto r = testing::run_cli(base + " --out " + q(dir / "out") + " --camera-truth " + q(dir / "loc.txt") + " " + q(dir / "gt.txt"));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto j = nlohmann::json::parse(r.out);
  ASSERT_TRUE(j.contains("detection"));
  // The CSV and TUM files keep 5 and 6 decimals: the error comes back to a few hundredths of a mm.
  EXPECT_NEAR(j["detection"]["max_rmse"].get<double>(), std::sqrt(World::bias(5).squaredNorm() + 0.015 * 0.015), 5e-5);
  EXPECT_GT(j["max_rmse"].get<double>(), 0.5);  // the map-frame positions are far off
  EXPECT_TRUE(fs::exists(dir / "out" / "detection.md"));
  std::ofstream(dir / "bad.txt") << "1.0 0 0 0 0 0 0\n";
  const auto bad = testing::run_cli(base + " --camera-truth " + q(dir / "bad.txt") + " " + q(dir / "gt.txt"));
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_NE(bad.err.find("bad.txt"), std::string::npos) << bad.err;
  EXPECT_EQ(testing::line_count(bad.err), 1) << bad.err;
  Trajectory later = w.truth;  // no true pose within 0.02 s of any measurement
  for (auto& p : later) p.timestamp += 5.0;
  write_tum_trajectory(dir / "later.txt", later);
  const auto apart = testing::run_cli(base + " --camera-truth " + q(dir / "loc.txt") + " " + q(dir / "later.txt"));
  EXPECT_NE(apart.exit_code, 0);
  EXPECT_NE(apart.err.find("measured.csv with --camera-truth"), std::string::npos) << apart.err;
  EXPECT_EQ(testing::line_count(apart.err), 1) << apart.err;
}

}  // namespace
}  // namespace builtscene
