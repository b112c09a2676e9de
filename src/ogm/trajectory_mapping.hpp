#pragma once
// Builds an occupancy grid from an RGB-D dataset and any trajectory of it (ground truth or a
// SLAM's), so mapping can be used and tested apart from the SLAM: poses are associated with
// frames by timestamp, optionally thinned to keyframes by motion, put in the ground frame,
// and each frame's virtual scan is integrated.
#include <functional>
#include <string>
#include <vector>

#include "core/stage_timer.hpp"
#include "io/trajectory.hpp"
#include "io/tum_dataset.hpp"
#include "ogm/ground_frame.hpp"
#include "ogm/occupancy_grid_mapper.hpp"
#include "ogm/virtual_laser_scanner.hpp"

namespace builtscene {

struct TrajectoryMappingOptions {
  VirtualLaserScanOptions scan;
  OccupancyMapperOptions mapper;
  std::string world = "auto";        // zup | camera | auto (see GroundFrame)
  double camera_height = 1.0;        // for world = camera: first camera above the floor
  bool keyframes_only = false;       // integrate only frames that moved enough since the last one used
  double keyframe_translation = 0.20;  // metres
  double keyframe_rotation_deg = 15.0;
  double max_difference = 0.02;      // seconds, pose-to-frame association
  // Called after each integrated frame with the result so far (e.g. to draw the grid as it grows).
  std::function<void(const struct TrajectoryMappingResult&)> after_frame;
};

struct TrajectoryMappingResult {
  OccupancyGridMapper mapper;
  GroundFrame frame;
  std::vector<Pose2D> poses;         // 2D pose of every integrated frame
  std::vector<std::size_t> frames;   // dataset indices integrated
  LaserScan last_scan;
  std::size_t skipped_frames = 0;    // unreadable depth: counted and logged, not fatal
  StageTimer timer;
};

// Dataset frames paired one-to-one with the trajectory's poses by timestamp.
struct PosedFrames {
  std::vector<std::size_t> frames;  // dataset indices
  std::vector<SE3> poses;           // T_wc in the trajectory's world
};
PosedFrames associate_poses(const TumDataset& dataset, const Trajectory& trajectory, double max_difference);

// The ground frame named by `world` (zup | camera | auto), estimated from up to 20 of the
// posed frames' depth images for auto.
GroundFrame resolve_ground_frame(const TumDataset& dataset, const PosedFrames& posed, const std::string& world,
                                 double camera_height);

// Whether the camera moved at least `translation` metres or turned at least `rotation_deg`
// degrees from `from` to `to`: the rule that thins a trajectory to keyframes.
bool moved_enough(const SE3& from, const SE3& to, double translation, double rotation_deg);
// Frames kept when thinning by motion (the first always).
std::vector<std::size_t> select_by_motion(const std::vector<SE3>& poses, double translation, double rotation_deg);

TrajectoryMappingResult build_map_from_trajectory(const TumDataset& dataset, const Trajectory& trajectory,
                                                  const TrajectoryMappingOptions& options);

}  // namespace builtscene
