// Camera motions stay in free space, look at things and have the advertised character.
#include <gtest/gtest.h>

#include <numbers>

#include "synth/camera_motion.hpp"
#include "synth/rgbd_sequence_writer.hpp"
#include "synth/scene_library.hpp"
#include "synth/truth_map.hpp"

namespace bs = builtscene;
namespace synth = builtscene::synth;

namespace {
double yaw_of(const bs::SE3& p) {
  const Eigen::Vector3d f = p.rotation_matrix().col(2);
  return std::atan2(f.y(), f.x());
}
}  // namespace

TEST(RgbdMotion, RobotDrivesTheLoopInFreeSpaceAtCameraHeight) {
  for (const std::string name : {"corridor-loop", "lab-room", "office", "low-texture"}) {
    const synth::Scene scene = synth::build_scene(name);
    synth::MotionOptions mo;
    mo.kind = synth::MotionKind::Robot;
    mo.loops = 2;
    const auto res = synth::generate_motion(scene, mo);
    ASSERT_GT(res.poses.size(), 100u);
    const auto truth = synth::compute_truth_map(scene, scene.robot_band_min, scene.robot_band_max);
    const cv::Mat clear = synth::clearance_map(truth);
    double min_clear = 1e9, max_step = 0, path = 0;
    for (std::size_t i = 0; i < res.poses.size(); ++i) {
      const Eigen::Vector3d t = res.poses[i].translation();
      EXPECT_NEAR(t.z(), 1.0, 0.02);
      // Facing forward: optical axis close to horizontal, no roll to speak of.
      const Eigen::Matrix3d R = res.poses[i].rotation_matrix();
      EXPECT_NEAR(std::asin(-R(2, 2)), 5.0 * std::numbers::pi / 180, 0.03);
      EXPECT_LT(std::abs(R.col(0).z()), 0.03);
      int c, r;
      ASSERT_TRUE(truth.cell_of(t.x(), t.y(), c, r));
      min_clear = std::min(min_clear, static_cast<double>(clear.at<float>(r, c)));
      if (i > 0) {
        const double step = (t - res.poses[i - 1].translation()).norm();
        max_step = std::max(max_step, step);
        path += step;
      }
    }
    EXPECT_GE(min_clear, 0.3) << name << ": the robot passes too close to an obstacle";
    EXPECT_LE(max_step, 0.75 / 30 + 0.005) << name;  // at most ~0.75 m/s
    // Two loops: about twice the loop's length, ending where it started.
    EXPECT_NEAR(path, 2 * res.loop_length_m, 0.03 * res.loop_length_m) << name;
    EXPECT_LT((res.poses.back().translation() - res.poses.front().translation()).norm(), 0.1) << name;
  }
  // The corridor loop is the source's ~80 m loop.
  synth::MotionOptions mo;
  mo.kind = synth::MotionKind::Robot;
  const auto corridor = synth::generate_motion(synth::build_scene("corridor-loop"), mo);
  EXPECT_GT(corridor.loop_length_m, 75.0);
  EXPECT_LT(corridor.loop_length_m, 82.0);
}

TEST(RgbdMotion, HandheldStaysFreeLooksAtThingsAndTurnsFastSometimes) {
  for (const std::string name : {"lab-room", "office", "demo", "low-texture"}) {
    const synth::Scene scene = synth::build_scene(name);
    synth::MotionOptions mo;
    mo.kind = synth::MotionKind::Handheld;
    mo.frames = 900;
    mo.seed = 3;
    const auto res = synth::generate_motion(scene, mo);
    ASSERT_EQ(res.poses.size(), 900u);
    const auto body = synth::compute_truth_map(scene, 0.05, 1.9);
    const auto surfaces = synth::scene_surfaces(scene);
    double max_rate = 0, max_step = 0;
    std::size_t close_views = 0;
    for (std::size_t i = 0; i < res.poses.size(); ++i) {
      const Eigen::Vector3d t = res.poses[i].translation();
      EXPECT_EQ(body.value_at(t.x(), t.y()), 0) << name << " frame " << i << " is not in free space";
      EXPECT_GT(t.z(), 0.9);
      EXPECT_LT(t.z(), scene.ceiling_height - 0.3);
      const auto hit = synth::raycast(surfaces, t, res.poses[i].rotation_matrix().col(2), 1e-3);
      ASSERT_TRUE(hit.has_value());
      if (*hit < 0.5) ++close_views;
      if (i > 0) {
        max_step = std::max(max_step, (t - res.poses[i - 1].translation()).norm());
        max_rate = std::max(max_rate, std::abs(std::remainder(yaw_of(res.poses[i]) - yaw_of(res.poses[i - 1]), 2 * std::numbers::pi)) * 30);
      }
    }
    EXPECT_LE(close_views, 9u) << name << ": staring at something closer than 0.5 m";
    EXPECT_LT(max_step, 0.05) << name << ": no jumps";
    EXPECT_GT(res.fast_turns, 0) << name;
    EXPECT_GT(max_rate, 1.5) << name << ": a fast turn exceeds ~90 deg/s";
    EXPECT_LT(max_rate, 6.0) << name;
  }
}

// The source's marker experiment measures every floor marker while the robot drives the loop:
// each one must come into the forward camera's view (all four corners in the image, 1-4 m
// away, no wall between: the walls of the 0.5-1.5 m band on the line of sight) on a good
// number of frames. Computed from the path and the scene's geometry, no render.
TEST(RgbdMotion, EveryCorridorMarkerComesIntoTheRobotCamerasView) {
  const synth::Scene scene = synth::build_scene("corridor-loop");
  synth::MotionOptions mo;
  mo.kind = synth::MotionKind::Robot;
  const auto res = synth::generate_motion(scene, mo);
  const auto cam = synth::kinect_settings().camera;
  const auto walls = synth::compute_truth_map(scene, 0.5, 1.5);
  auto wall_between = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    const double len = (b - a).head<2>().norm();
    for (double s = 0; s < len; s += 0.02) {
      const Eigen::Vector3d p = a + (b - a) * (s / len);
      if (walls.value_at(p.x(), p.y()) == 100) return true;
    }
    return false;
  };
  ASSERT_EQ(scene.tags.size(), 15u);
  for (const auto& tag : scene.tags) {
    int frames_in_view = 0;
    for (const auto& T_wc : res.poses) {
      const bs::SE3 T_cw = T_wc.inverse();
      bool in_view = true;
      for (const auto& corner : tag.corners()) {
        const Eigen::Vector3d pc = T_cw * corner;
        const Eigen::Vector2d uv = cam.project(pc);
        if (pc.z() < 1.0 || pc.norm() > 4.0 || uv.x() < 0 || uv.y() < 0 || uv.x() >= cam.width || uv.y() >= cam.height ||
            wall_between(T_wc.translation(), corner)) {
          in_view = false;
          break;
        }
      }
      frames_in_view += in_view;
    }
    std::printf("tag %d: %d frames in view\n", tag.id, frames_in_view);
    EXPECT_GE(frames_in_view, 20) << "tag " << tag.id << " at " << tag.center.transpose();
  }
}
