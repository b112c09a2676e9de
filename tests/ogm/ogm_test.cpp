#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include <opencv2/imgcodecs.hpp>

#include "../common/scratch_dir.hpp"
#include "analytic_depth.hpp"
#include "core/errors.hpp"
#include "ogm/grid_resampling.hpp"
#include "ogm/ground_frame.hpp"
#include "ogm/map_comparison.hpp"
#include "ogm/map_server_io.hpp"
#include "ogm/occupancy_grid_mapper.hpp"
#include "ogm/virtual_laser_scanner.hpp"

namespace builtscene {
namespace {

using testing::Box;
using testing::kinect_camera;
using testing::level_camera;
using testing::render_depth;

namespace fs = std::filesystem;

TEST(Bresenham, CoversEndpointsAndIsConnected) {
  const auto line = bresenham_line({0, 0}, {7, 3});
  ASSERT_EQ(line.size(), 8u);  // max(|dx|, |dy|) + 1
  EXPECT_EQ(line.front(), (GridIndex{0, 0}));
  EXPECT_EQ(line.back(), (GridIndex{7, 3}));
  for (std::size_t i = 1; i < line.size(); ++i) {
    EXPECT_LE(std::abs(line[i].col - line[i - 1].col), 1);
    EXPECT_LE(std::abs(line[i].row - line[i - 1].row), 1);
    // Each cell within half a cell of the true line y = 3/7 x.
    EXPECT_LE(std::abs(line[i].row - 3.0 / 7.0 * line[i].col), 0.5 + 1e-9);
  }
  EXPECT_EQ(bresenham_line({2, 2}, {2, -3}).size(), 6u);
}

TEST(VirtualLaserScan, WallAheadGivesClosedFormRanges) {
  // A wall 3 m ahead of a level camera 1 m high: at bearing a the range is 3 / cos(a).
  const auto cam = kinect_camera();
  const SE3 T = level_camera(0, 0, 1.0, 0.0);
  const cv::Mat depth = render_depth(cam, T, {{{3.0, -10, 0}, {3.2, 10, 3}}});
  const VirtualLaserScanner scanner(cam, {});
  const LaserScan s = scanner.scan(depth, T);
  int checked = 0;
  for (std::size_t i = 0; i < s.ranges.size(); ++i) {
    if (!std::isfinite(s.ranges[i])) continue;
    const double a = s.beam_angle(i);
    // The bin collects bearings within half an increment: allow that spread.
    const double tol = 3.0 / std::cos(std::abs(a) + s.angle_increment) - 3.0 / std::cos(a) + 0.005;
    EXPECT_NEAR(s.ranges[i], 3.0 / std::cos(a), std::abs(tol)) << a;
    ++checked;
  }
  // Beams across the horizontal field of view: 2 * atan(320/525) / increment.
  EXPECT_GT(checked, static_cast<int>(0.95 * 2 * std::atan(320.0 / 525.0) / s.angle_increment));
}

TEST(VirtualLaserScan, HeightBandCatchesADeskTopThatOneHeightMisses) {
  // A desk: a 4 cm top at 0.72-0.76 m on four thin legs, 1.5 m ahead; camera 1.0 m high,
  // tilted down 20 degrees so that the top is in view.
  const auto cam = kinect_camera();
  std::vector<Box> desk{{{1.5, -0.6, 0.72}, {2.3, 0.6, 0.76}}};
  for (double x : {1.52, 2.26})
    for (double y : {-0.58, 0.54}) desk.push_back({{x, y, 0.0}, {x + 0.03, y + 0.03, 0.72}});
  const Eigen::Matrix3d tilt = Eigen::AngleAxisd(-20.0 * M_PI / 180.0, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const SE3 level = level_camera(0, 0, 1.0, 0.0);
  const SE3 T(level.rotation_matrix() * tilt, level.translation());
  const cv::Mat depth = render_depth(cam, T, desk);
  VirtualLaserScanOptions band;
  band.min_height = 0.05;
  band.max_height = 1.5;
  VirtualLaserScanOptions one_height = band;  // a 2D lidar mounted at 0.30 m
  one_height.min_height = 0.29;
  one_height.max_height = 0.31;
  const LaserScan a = VirtualLaserScanner(cam, band).scan(depth, T);
  const LaserScan b = VirtualLaserScanner(cam, one_height).scan(depth, T);
  // Straight ahead (bearing 0) the band sees the desk edge at 1.5 m; at 0.30 m there is only
  // free space between the legs.
  const auto centre = static_cast<std::size_t>(std::lround(-a.angle_min / a.angle_increment));
  EXPECT_NEAR(a.ranges[centre], 1.5, 0.02);
  EXPECT_FALSE(std::isfinite(b.ranges[centre]) && b.ranges[centre] < 2.25);
}

std::vector<PoseAndScan> corridor_scans() {
  // A robot driving along x in a corridor with walls at y = +-1 (10 cm thick), scanning ahead.
  const auto cam = kinect_camera();
  const std::vector<Box> walls{{{-1, 1.0, 0}, {12, 1.1, 2.5}}, {{-1, -1.1, 0}, {12, -1.0, 2.5}}, {{10, -1.1, 0}, {10.1, 1.1, 2.5}}};
  VirtualLaserScanOptions o;
  o.range_max = 8.0;  // noise-free depth: the whole corridor is in range
  const VirtualLaserScanner scanner(cam, o);
  std::vector<PoseAndScan> out;
  for (int i = 0; i < 16; ++i) {
    const double x = 0.25 * i;
    const double yaw = (i % 2 ? 0.35 : -0.35);
    const SE3 T = level_camera(x, 0.0, 1.0, yaw);
    out.push_back({GroundFrame::z_up().to_2d(T), scanner.scan(render_depth(cam, T, walls), T)});
  }
  return out;
}

OccupancyGrid corridor_truth() {
  OccupancyGrid g(300, 100, 0.05, {-2.5, -2.5}, 0);
  for (int r = 0; r < g.height(); ++r)
    for (int c = 0; c < g.width(); ++c) {
      const Eigen::Vector2d p = g.center_of({c, r});
      const bool wall = (std::abs(p.y()) >= 1.0 && std::abs(p.y()) <= 1.1 && p.x() <= 12) || (p.x() >= 10 && p.x() <= 10.1 && std::abs(p.y()) <= 1.1);
      if (wall) g.at({c, r}) = 100;
      else if (std::abs(p.y()) > 1.1 || p.x() > 10.1) g.at({c, r}) = -1;
    }
  return g;
}

TEST(OccupancyGridMapper, CorridorMatchesTruthForBothModels) {
  for (auto model : {OccupancyMapperOptions::Model::kSource, OccupancyMapperOptions::Model::kInverseSensor}) {
    OccupancyMapperOptions o;
    o.model = model;
    OccupancyGridMapper m(o);
    for (const auto& p : corridor_scans()) m.integrate(p);
    const MapScore s = compare_maps(m.grid(), corridor_truth());
    EXPECT_GE(s.occupied_precision, 0.95);
    EXPECT_GE(s.occupied_recall, 0.90);
    EXPECT_GE(s.free_agreement, 0.98);
    // Both walls over several metres (2 cells thick, 0.05 m cells) and the floor between them.
    EXPECT_GT(s.estimated_occupied, 100u);
    EXPECT_GT(s.estimated_free, 300u);
  }
}

TEST(OccupancyGridMapper, SourceModelFollowsItsIntegerRule) {
  // One beam straight ahead hitting at 1.0 m with 0.1 m cells: cells 0..9 free once, cell 10 hit once.
  LaserScan s;
  s.angle_min = s.angle_max = 0;
  s.angle_increment = 0.01f;
  s.range_min = 0.0f;
  s.range_max = 5.0f;
  s.ranges = {1.0f};
  OccupancyMapperOptions o;
  o.resolution = 0.1;
  OccupancyGridMapper m(o);
  m.integrate({{0.05, 0.05, 0.0}, s});
  OccupancyGrid g = m.grid();
  EXPECT_EQ(g.value_at({0.05, 0.05}), 45);   // 50 - l_free
  EXPECT_EQ(g.value_at({0.55, 0.05}), 45);
  EXPECT_EQ(g.value_at({1.07, 0.05}), 65);   // 50 + l_occ
  EXPECT_EQ(g.value_at({1.25, 0.05}), -1);   // beyond the hit: unknown
  m.integrate({{0.05, 0.05, 0.0}, s});
  g = m.grid();
  EXPECT_EQ(g.value_at({0.05, 0.05}), 40);
  EXPECT_EQ(g.value_at({1.07, 0.05}), 80);
}

TEST(OccupancyGridMapper, MultiPairBatchRebuildsFromScratch) {
  const auto scans = corridor_scans();
  OccupancyGridMapper incremental;
  for (const auto& p : scans) incremental.integrate(p);
  // A wrong pose integrated first (shifted 1 m sideways) leaves a ghost wall...
  OccupancyGridMapper m;
  auto wrong = scans[0];
  wrong.pose.y += 1.0;
  m.integrate(wrong);
  // ...and a batch of all corrected poses erases it.
  m.integrate_batch(scans);
  EXPECT_EQ(m.grid().data(), incremental.grid().data());
  EXPECT_EQ(m.scans_integrated(), scans.size());
}

// A fresh folder bs_ogm_<name>_<pid>, removed when the test process exits.
fs::path temp_dir(const std::string& name) { return testing::scratch_dir("ogm_" + name); }

TEST(MapServerIo, RoundTripKeepsClassesAndFlipsRows) {
  OccupancyGrid g(40, 30, 0.05, {-1.0, 2.0}, -1);
  g.at({0, 0}) = 100;    // bottom-left: must be the PGM's last row, first column
  g.at({39, 29}) = 0;    // top-right: the PGM's first row, last column
  g.at({10, 5}) = 30;    // between the thresholds: unknown in trinary
  const auto d = temp_dir("io");
  save_map_server(g, d / "map.yaml");
  const cv::Mat pgm = cv::imread((d / "map.pgm").string(), cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(pgm.empty());
  EXPECT_EQ(pgm.at<std::uint8_t>(29, 0), 0);
  EXPECT_EQ(pgm.at<std::uint8_t>(0, 39), 254);
  EXPECT_EQ(pgm.at<std::uint8_t>(15, 15), 205);
  const OccupancyGrid r = load_map_server(d / "map.yaml");
  EXPECT_EQ(r.width(), 40);
  EXPECT_DOUBLE_EQ(r.origin().y(), 2.0);
  EXPECT_EQ(r.value_at({-0.99, 2.01}), 100);
  EXPECT_EQ(r.value_at({0.98, 3.48}), 0);
  EXPECT_EQ(r.at({10, 5}), -1);
}

TEST(MapServerIo, GroundFrameRidesInTheYamlAndStillLoads) {
  OccupancyGrid g(10, 10, 0.05, {0.0, 0.0}, 0);
  const auto d = temp_dir("ground");
  save_map_server(g, d / "map.yaml");
  EXPECT_FALSE(read_ground_frame(d / "map.yaml").has_value());
  const SE3 T(Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, -2, 0.5).normalized())),
              Eigen::Vector3d(0.25, -3.5, 1.125));
  append_ground_frame(d / "map.yaml", T);
  EXPECT_EQ(load_map_server(d / "map.yaml").width(), 10);  // map_server's keys untouched
  const auto back = read_ground_frame(d / "map.yaml");
  ASSERT_TRUE(back.has_value());
  EXPECT_LT((back->translation() - T.translation()).norm(), 1e-12);
  EXPECT_LT(back->rotation().angularDistance(T.rotation()), 1e-12);
  std::ofstream(d / "short.yaml") << "image: map.pgm\nground_frame_T_gw: [1, 2, 3]\n";
  EXPECT_THROW(read_ground_frame(d / "short.yaml"), InputError);
  std::ofstream(d / "bad.yaml") << "image: map.pgm\nground_frame_T_gw: [0, 0, 0, 0, 0, 0, 2]\n";
  try {
    read_ground_frame(d / "bad.yaml");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("ground_frame_T_gw"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("bad.yaml"), std::string::npos) << e.what();
  }
}

TEST(MapServerIo, BadYamlNamesFileAndField) {
  const auto d = temp_dir("bad");
  std::ofstream(d / "a.yaml") << "image: missing.pgm\nresolution: 0.05\norigin: [0, 0, 0]\noccupied_thresh: 0.65\nfree_thresh: 0.2\n";
  try {
    load_map_server(d / "a.yaml");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("missing.pgm"), std::string::npos) << e.what();
  }
  std::ofstream(d / "b.yaml") << "image: x.pgm\nresolution: fine\norigin: [0, 0, 0]\noccupied_thresh: 0.65\nfree_thresh: 0.2\n";
  try {
    load_map_server(d / "b.yaml");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("resolution"), std::string::npos) << e.what();
  }
  std::ofstream(d / "c.yaml") << "image: x.pgm\nresolution: 0.05\noccupied_thresh: 0.65\nfree_thresh: 0.2\n";
  EXPECT_THROW(load_map_server(d / "c.yaml"), InputError);
}

TEST(MapperState, RoundTripContinuesMappingAndRejectsCorruption) {
  const auto scans = corridor_scans();
  OccupancyGridMapper full;
  for (const auto& p : scans) full.integrate(p);
  OccupancyGridMapper half;
  for (std::size_t i = 0; i < scans.size() / 2; ++i) half.integrate(scans[i]);
  const auto d = temp_dir("state");
  half.save_state(d / "m.state");
  OccupancyGridMapper resumed = OccupancyGridMapper::load_state(d / "m.state");
  for (std::size_t i = scans.size() / 2; i < scans.size(); ++i) resumed.integrate(scans[i]);
  EXPECT_EQ(resumed.grid().data(), full.grid().data());

  std::ifstream in(d / "m.state", std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::ofstream(d / "trunc.state", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  EXPECT_THROW(OccupancyGridMapper::load_state(d / "trunc.state"), InputError);
  std::string flipped = bytes;
  flipped[flipped.size() - 10] ^= 0x40;
  std::ofstream(d / "flip.state", std::ios::binary) << flipped;
  EXPECT_THROW(OccupancyGridMapper::load_state(d / "flip.state"), InputError);
  std::string version = bytes;
  version[8] = 9;
  std::ofstream(d / "ver.state", std::ios::binary) << version;
  EXPECT_THROW(OccupancyGridMapper::load_state(d / "ver.state"), InputError);
}

TEST(GroundFrame, FirstCameraConventionAndEstimation) {
  // A SLAM world = the first camera (level, 1.0 m above the floor). A camera 2 m forward and
  // 1 m to the right, turned 90 degrees left, is at ground (1, 2) heading +90 degrees... in
  // the source's mapping x <- camera x, y <- camera z.
  const GroundFrame g = GroundFrame::first_camera(1.0);
  const SE3 T(Eigen::Quaterniond(Eigen::AngleAxisd(-M_PI / 2, Eigen::Vector3d::UnitY())), Eigen::Vector3d(1, 0, 2));
  const Pose2D p = g.to_2d(T);
  EXPECT_NEAR(p.x, 1.0, 1e-12);
  EXPECT_NEAR(p.y, 2.0, 1e-12);
  EXPECT_NEAR(std::abs(p.theta), M_PI, 1e-9);  // camera z turned to -x in camera-0 = ground -x
  EXPECT_NEAR(g.camera_in_ground(SE3()).translation().z(), 1.0, 1e-12);

  // Estimated from level cameras 1.2 m above a floor in a z-up world: up = z, floor at 0.
  const auto cam = kinect_camera();
  std::vector<SE3> poses{level_camera(0, 0, 1.2, 0.3), level_camera(0.5, 0.2, 1.2, -0.4)};
  const Eigen::Matrix3d tilt = Eigen::AngleAxisd(-0.5, Eigen::Vector3d::UnitX()).toRotationMatrix();
  std::vector<cv::Mat> depths;
  for (auto& T0 : poses) {
    T0 = SE3(T0.rotation_matrix() * tilt, T0.translation());  // look down at the floor
    depths.push_back(render_depth(cam, T0, {{{-20, -20, -1}, {20, 20, 0}}, {{4, -5, 0}, {4.2, 5, 2.5}}}));
  }
  const GroundFrame e = GroundFrame::estimate(poses, depths, cam);
  EXPECT_NEAR(e.camera_in_ground(poses[0]).translation().z(), 1.2, 0.02);
  EXPECT_GT((e.T_gw().rotation().conjugate() * Eigen::Vector3d::UnitZ()).z(), std::cos(M_PI / 180.0));  // up within 1 degree
}

// A grid moved by a known planar motion: every occupied source cell lands on the cell the
// closed-form motion gives, free and unknown cells keep their class, and the result scores
// perfectly against the same layout drawn directly in the destination frame.
TEST(GridResampling, KnownPlanarMotionMovesEveryCellWhereTheFormulaSays) {
  OccupancyGrid src(40, 20, 0.05, {-1.0, 0.5}, 0);
  for (int col = 0; col < 40; ++col) src.at({col, 19}) = 100;  // a wall along the top
  for (int row = 0; row < 5; ++row)
    for (int col = 0; col < 5; ++col) src.at({col, row}) = -1;  // an unseen corner
  const Pose2D T{2.0, -3.0, M_PI / 2};                           // 90 degrees, then shifted
  const OccupancyGrid lattice(1, 1, 0.05, {0.0, 0.0});
  const OccupancyGrid out = resample_grid(src, T, lattice);
  // Cells line up with the lattice: the origin is a whole number of cells from (0, 0).
  EXPECT_NEAR(std::remainder(out.origin().x(), 0.05), 0.0, 1e-9);
  EXPECT_NEAR(std::remainder(out.origin().y(), 0.05), 0.0, 1e-9);
  int moved = 0;
  for (int row = 0; row < src.height(); ++row)
    for (int col = 0; col < src.width(); ++col) {
      const Eigen::Vector2d p = src.center_of({col, row});
      const Eigen::Vector2d q(-p.y() + 2.0, p.x() - 3.0);  // R(90) p + t
      ASSERT_EQ(out.value_at(q), src.at({col, row})) << col << "," << row;
      ++moved;
    }
  EXPECT_EQ(moved, 800);
  // The same wall drawn directly in the destination frame: x = -(0.5 + 19.5 * 0.05) + 2.
  const double wall_x = -(0.5 + 19.5 * 0.05) + 2.0;
  OccupancyGrid truth(60, 80, 0.05, {-2.0, -5.0}, 0);
  for (int row = 0; row < truth.height(); ++row) {
    const Eigen::Vector2d c = truth.center_of({0, row});
    if (c.y() > -4.0 && c.y() < -2.0) truth.at(truth.cell_of({wall_x, c.y()})) = 100;
  }
  const MapScore s = compare_maps(out, truth, 0);
  EXPECT_EQ(s.estimated_occupied, 40u);
  EXPECT_DOUBLE_EQ(s.occupied_precision, 1.0);
  EXPECT_DOUBLE_EQ(s.occupied_recall, 1.0);
  // Planar part of a z-up motion.
  const SE3 T3(Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ())), Eigen::Vector3d(1, 2, 3));
  const Pose2D p2 = planar_part(T3);
  EXPECT_NEAR(p2.x, 1, 1e-12);
  EXPECT_NEAR(p2.y, 2, 1e-12);
  EXPECT_NEAR(p2.theta, 0.3, 1e-12);
}

}  // namespace
}  // namespace builtscene
