#include "ogm/trajectory_mapping.hpp"

#include <chrono>
#include <cmath>
#include <numbers>

#include "core/errors.hpp"
#include "core/logging.hpp"
#include "core/progress.hpp"

namespace builtscene {

bool moved_enough(const SE3& from, const SE3& to, double translation, double rotation_deg) {
  const SE3 d = from.inverse() * to;
  const double angle = Eigen::AngleAxisd(d.rotation()).angle() * 180.0 / std::numbers::pi;
  return d.translation().norm() >= translation || angle >= rotation_deg;
}

std::vector<std::size_t> select_by_motion(const std::vector<SE3>& poses, double translation, double rotation_deg) {
  std::vector<std::size_t> keep;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    if (keep.empty()) {
      keep.push_back(i);
      continue;
    }
    if (moved_enough(poses[keep.back()], poses[i], translation, rotation_deg)) keep.push_back(i);
  }
  return keep;
}

PosedFrames associate_poses(const TumDataset& ds, const Trajectory& traj, double max_difference) {
  std::vector<double> frame_times, pose_times;
  for (const auto& e : ds.entries()) frame_times.push_back(e.timestamp);
  for (const auto& p : traj) pose_times.push_back(p.timestamp);
  const auto pairs = associate_timestamps(frame_times, pose_times, max_difference);
  if (pairs.empty())
    throw InputError("no pose of the trajectory lies within " + std::to_string(max_difference) +
                     " s of a frame of " + ds.root().string());
  PosedFrames out;
  for (const auto& [fi, ti] : pairs) {
    out.frames.push_back(fi);
    out.poses.push_back(traj[ti].pose);
  }
  return out;
}

GroundFrame resolve_ground_frame(const TumDataset& ds, const PosedFrames& posed, const std::string& world,
                                 double camera_height) {
  GroundFrame frame;
  if (parse_ground_frame(world, camera_height, frame)) return frame;
  std::vector<SE3> sample_poses;
  std::vector<cv::Mat> sample_depths;
  const std::size_t step = std::max<std::size_t>(1, posed.frames.size() / 20);
  for (std::size_t k = 0; k < posed.frames.size(); k += step) {
    try {
      sample_depths.push_back(ds.load_depth(posed.frames[k]));
      sample_poses.push_back(posed.poses[k]);
    } catch (const InputError&) {
      // an unreadable frame is skipped here; the mapping loop reports it
    }
  }
  return GroundFrame::estimate(sample_poses, sample_depths, ds.settings().camera);
}

TrajectoryMappingResult build_map_from_trajectory(const TumDataset& ds, const Trajectory& traj,
                                                  const TrajectoryMappingOptions& o) {
  TrajectoryMappingResult r{OccupancyGridMapper(o.mapper), GroundFrame(), {}, {}, {}, 0, {}};
  const PosedFrames posed = associate_poses(ds, traj, o.max_difference);
  const auto& frame_idx = posed.frames;
  const auto& poses = posed.poses;
  std::vector<std::size_t> use(poses.size());
  for (std::size_t i = 0; i < use.size(); ++i) use[i] = i;
  if (o.keyframes_only) use = select_by_motion(poses, o.keyframe_translation, o.keyframe_rotation_deg);
  r.frame = resolve_ground_frame(ds, posed, o.world, o.camera_height);
  const VirtualLaserScanner scanner(ds.settings().camera, o.scan);
  Progress progress("ogm", use.size());
  for (std::size_t k = 0; k < use.size(); ++k) {
    const std::size_t fi = frame_idx[use[k]];
    cv::Mat depth;
    {
      auto t = r.timer.scope("load_depth");
      try {
        depth = ds.load_depth(fi);
      } catch (const InputError& e) {
        ++r.skipped_frames;
        spdlog::warn("skipping frame {}: {}", fi, e.what());
        continue;
      }
    }
    const SE3 T_gc = r.frame.camera_in_ground(poses[use[k]]);
    LaserScan scan;
    {
      auto t = r.timer.scope("scan");
      scan = scanner.scan(depth, T_gc, ds.entry(fi).timestamp);
    }
    const Pose2D p = r.frame.to_2d(poses[use[k]]);
    {
      auto t = r.timer.scope("integrate");
      r.mapper.integrate({p, scan});
    }
    r.poses.push_back(p);
    r.frames.push_back(fi);
    r.last_scan = std::move(scan);
    if (o.after_frame) o.after_frame(r);
    progress.update(k + 1);
  }
  return r;
}

}  // namespace builtscene
