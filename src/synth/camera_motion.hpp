#pragma once
// Camera trajectories through a scene, one pose T_wc per frame at a fixed rate.
//   robot:    planar wheelchair driving the scene's loop (corners rounded, slower in turns),
//             camera ~1 m high facing forward (pitched 5 degrees down), small vibration.
//   handheld: a person walking between random free-space waypoints while looking at things
//             (posters, shelves, desks, tags), smooth 6-DoF with hand tremor and a walking
//             bob, and occasional fast turns.
// Both keep the camera in free space (checked against the truth map of the band the person
// or robot occupies) and are deterministic for a seed.
#include <cstdint>
#include <string>
#include <vector>

#include "core/se3.hpp"
#include "synth/scene.hpp"

namespace builtscene::synth {

enum class MotionKind { Handheld, Robot };

struct MotionOptions {
  MotionKind kind = MotionKind::Handheld;
  int frames = 0;           // 0: handheld 300, robot exactly `loops` loops
  int loops = 1;
  std::uint64_t seed = 1;
  double fps = 30.0;
  double robot_camera_height = 1.0;
  double robot_pitch_deg = 5.0;   // downwards
  double robot_speed = 0.7;       // m/s on straights
};

struct MotionResult {
  std::vector<SE3> poses;   // T_wc per frame
  double loop_length_m = 0; // robot: the rounded loop's length
  int fast_turns = 0;       // handheld: number of fast-turn segments
};

MotionResult generate_motion(const Scene& scene, const MotionOptions& options);

// Rotation of a camera (x right, y down, z forward) looking along `forward` in a z-up world,
// rolled by `roll` radians about its optical axis.
Eigen::Matrix3d look_rotation(const Eigen::Vector3d& forward, double roll);

}  // namespace builtscene::synth
