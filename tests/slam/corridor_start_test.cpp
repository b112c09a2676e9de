// The generated corridor's plain start (label: slow): the robot drives 14 m down a corridor
// whose walls give 20-40 feature inliers per frame. SLAM with and without planar motion.
//
// With planar motion the frame at 28 matched 24 map points instead of 31, tracking fell onto
// the depth-odometry bridge, and never came back: each bridge keyframe held only the 3-10
// keypoints with depth of a plain corridor, so the motion model never found its 20 matches,
// and the start ended 2 m off along the corridor (docs/slam.md, "Planar motion"). The local
// map searched from the depth odometry's pose finds the far map points again (tracking.cpp,
// refine_depth_odometry_with_local_map).
//
// The floor's normal for planar motion is measured in the first keyframe's depth (frame 0 here); checked
// here against the generated camera's true tilt.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "../common/run_cli.hpp"
#include "eval/trajectory_error.hpp"
#include "io/tum_dataset.hpp"
#include "slam/system.hpp"
#include "../common/scratch_dir.hpp"

namespace builtscene::slam {
namespace {

namespace fs = std::filesystem;

struct Result {
  double rmse = 0, max = 0;
  long tracked = 0;
  std::optional<FloorPlane> floor;
  // Straight-line distance covered between the first associated frame and frame `chord_end`,
  // estimated over true (alignment-free: a scale error along the corridor shows here).
  double chord_ratio = 0;
};

constexpr std::size_t chord_end = 200;

Result run(const TumDataset& data, const SystemOptions& options) {
  System system(data.settings(), options);
  Result r;
  for (std::size_t i = 0; i < data.size(); ++i)
    r.tracked += system.track_rgbd(data.load_rgb(i), data.load_depth(i), data.entry(i).timestamp).state ==
                 TrackingState::kOk;
  system.shutdown();
  const auto est = system.trajectory();
  const auto& gt = data.groundtruth();
  const auto ate = absolute_trajectory_error(gt, est, Alignment::kSE3);
  r.rmse = ate.stats.rmse;
  r.max = ate.stats.max;
  if (ate.pairs.size() > chord_end) {
    const auto [g0, e0] = ate.pairs.front();
    const auto [g1, e1] = ate.pairs[chord_end];
    const double true_m = (gt[g1].pose.translation() - gt[g0].pose.translation()).norm();
    r.chord_ratio = (est[e1].pose.translation() - est[e0].pose.translation()).norm() / true_m;
  }
  r.floor = system.floor_plane();
  return r;
}

// The first `frames` frames of the generated corridor world `seed` (robot), in a fresh folder.
fs::path generate_corridor_start(int seed, const std::string& name, int frames = 600) {
  const fs::path dir = testing::scratch_dir(name);
  const auto r = testing::run_cli("synth rgbd --scene corridor-loop --motion robot --seed " + std::to_string(seed) +
                                  " --frames " + std::to_string(frames) +
                                  " --out " + testing::shell_quote(dir / "seq"));
  EXPECT_EQ(r.exit_code, 0) << r.err;
  return dir;
}

SystemOptions deterministic_options() {
  SystemOptions options;
  options.mapping_thread = false;
  return options;
}

TEST(CorridorStart, PlainStartHoldsWithAndWithoutPlanarMotion) {
  const fs::path dir = generate_corridor_start(1, "corridor_start");
  const auto data = TumDataset::open(dir / "seq");
  SystemOptions options = deterministic_options();
  const Result plain = run(data, options);
  options.planar = PlanarMotion::from_pitch(5.0);  // the generator's nominal pitch
  const Result planar = run(data, options);
  std::printf("corridor start, 600 frames: default %ld tracked, ATE %.2f cm (max %.2f); planar %ld tracked, ATE %.2f cm (max %.2f)\n",
              plain.tracked, 100 * plain.rmse, 100 * plain.max, planar.tracked, 100 * planar.rmse, 100 * planar.max);
  EXPECT_EQ(plain.tracked, 600);
  EXPECT_EQ(planar.tracked, 600);
  // Measured 8.3 / 6.3 cm (the same with the bridge's turn window, 2026-12-05); the start 2 m
  // off gave 0.8 m RMSE.
  EXPECT_LT(plain.rmse, 0.15);
  EXPECT_LT(planar.rmse, 0.15);
  EXPECT_LT(planar.max, 0.40);

  // The floor: the world's up (z) seen from the first camera, from the ground truth.
  ASSERT_TRUE(planar.floor.has_value());
  const Eigen::Vector3d up_true = data.groundtruth().front().pose.rotation_matrix().transpose() * Eigen::Vector3d::UnitZ();
  const double angle = std::acos(std::clamp(planar.floor->up_c.dot(up_true), -1.0, 1.0)) * 180 / M_PI;
  std::printf("floor normal %.3f degrees from the truth, camera %.3f m above the floor (truth %.3f)\n", angle,
              planar.floor->height_m, data.groundtruth().front().pose.translation().z());
  EXPECT_LT(angle, 0.1);  // the nominal pitch is 0.27 degrees off here
  EXPECT_NEAR(planar.floor->height_m, data.groundtruth().front().pose.translation().z(), 0.01);
  fs::remove_all(dir);
}

// The second generated corridor (seed 2) starts plainer: from frame 23 to 180 the depth
// odometry carries every frame. Along a plain corridor the depth leaves the slide free and
// returns its prediction there plus noise; when that prediction was the last frame's velocity,
// the speed did a random walk under its cap and stalled at a quarter of the true speed, and
// the first feature frame's 16 cm snap back to the map was then taken for a velocity and
// held: the start ended 1.9 m off (0.92 m RMSE over 600 frames). The prediction on the bridge
// is now, while driving straight, the last feature-tracked velocity at the median
// feature-tracked speed (measured: 0.42 m RMSE, max 0.88 m; with straight judged over 10
// frames, 0.34 m and 0.74 m; tracking.cpp, odometry_prediction).
TEST(CorridorStart, DepthOdometryBridgeKeepsTheSpeedAlongAPlainCorridor) {
  const fs::path dir = generate_corridor_start(2, "corridor_bridge");
  const auto data = TumDataset::open(dir / "seq");
  const Result result = run(data, deterministic_options());
  std::printf("corridor seed 2, 600 frames: %ld tracked, ATE %.2f cm (max %.2f)\n", result.tracked, 100 * result.rmse,
              100 * result.max);
  EXPECT_EQ(result.tracked, 600);
  EXPECT_LT(result.rmse, 0.6);
  EXPECT_LT(result.max, 1.2);
  fs::remove_all(dir);
}

// The fourth generated corridor: features give out from frame ~20 to ~180 as well (5 of 500
// keypoints with depth), and the bridge's prediction holds the feature-tracked speed only while
// driving straight. Straight was judged on the last frame's rotation alone; a bridge frame
// jitters by 0.1-0.3 degrees (ICP noise), the hold dropped out every few frames and fed the
// bridge's own speed back: frames 80-200 covered 0.84 of the true distance (frames 0-200:
// 0.90), the 400 frames 19.3 cm RMSE. Judged on the net turn over 10 frames (tracking.cpp,
// recent_turn_rate): 0.97 and 9.9 cm (13.6 cm with plane landmarks on). The held speed was
// the features' last, 1.8 cm per frame while the robot still sped up to its 2.34; from frame
// 36 to 80 a cabinet's end in the depth measures the true speed, and such bridge frames now
// feed the held speed (depth_odometry.hpp, last_slide_measured): 5.2 cm, distance 1.02.
TEST(CorridorStart, BridgeHoldsTheSpeedThroughRotationJitter) {
  const fs::path dir = generate_corridor_start(4, "corridor_jitter", 400);
  const auto data = TumDataset::open(dir / "seq");
  const Result result = run(data, deterministic_options());
  std::printf("corridor seed 4, 400 frames: %ld tracked, ATE %.2f cm (max %.2f), distance to frame %zu: %.3f of the truth\n",
              result.tracked, 100 * result.rmse, 100 * result.max, chord_end, result.chord_ratio);
  EXPECT_EQ(result.tracked, 400);
  EXPECT_GT(result.chord_ratio, 0.95);
  EXPECT_LT(result.chord_ratio, 1.05);
  EXPECT_LT(result.rmse, 0.08);
  fs::remove_all(dir);
}

}  // namespace
}  // namespace builtscene::slam
