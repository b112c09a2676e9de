// `builtscene cloud`: a coloured point cloud from posed RGB-D frames, optionally updated only
// inside a region of the map (location-aware point-cloud update).
#include <memory>
#include <optional>

#include "command_registry.hpp"
#include "core/errors.hpp"
#include "core/logging.hpp"
#include "nav/region_cloud_update.hpp"
#include "ogm/trajectory_mapping.hpp"

namespace builtscene::app {
namespace {

struct CloudOptions {
  std::string dataset, camera, poses, region, cloud_in, out, world = "auto";
  double camera_height = 1.0;
  CloudBuildOptions build;
};

nlohmann::json run_cloud(const CloudOptions& o) {
  std::optional<Region> region;
  if (!o.region.empty()) region = Region::parse(o.region);
  PointCloud existing;
  if (!o.cloud_in.empty()) existing = read_ply(o.cloud_in);
  const TumDataset ds = TumDataset::open(o.dataset, o.camera);
  const PosedFrames posed = associate_poses(ds, read_tum_trajectory(o.poses), 0.02);
  const GroundFrame ground = resolve_ground_frame(ds, posed, o.world, o.camera_height);
  std::vector<PosedFrame> frames;
  for (std::size_t i = 0; i < posed.frames.size(); ++i)
    frames.push_back({posed.frames[i], ground.camera_in_ground(posed.poses[i])});
  const CloudUpdateResult r =
      update_cloud_in_region(ds, frames, region, o.cloud_in.empty() ? nullptr : &existing, o.build);
  write_ply(o.out, r.cloud);
  spdlog::info("{} points written to {} ({} frames integrated, {} outside the region; {} old points replaced)",
               r.cloud.size(), o.out, r.frames_integrated, r.frames_outside_region, r.points_removed);
  return {{"points", r.cloud.size()},
          {"points_added", r.points_added},
          {"points_removed", r.points_removed},
          {"points_kept", r.points_kept},
          {"frames_integrated", r.frames_integrated},
          {"frames_outside_region", r.frames_outside_region},
          {"frames_skipped", r.frames_skipped},
          {"out", o.out},
          {"stage_ms", r.timer.summary()}};
}

const bool registered_cloud = register_command({
    .path = {"cloud"},
    .description = "Coloured point cloud (binary PLY) from posed frames, optionally updated only inside a region",
    .setup = [](CLI::App& cmd) -> Action {
      auto o = std::make_shared<CloudOptions>();
      cmd.add_option("--dataset", o->dataset, "TUM-layout RGB-D folder")->required();
      cmd.add_option("--camera", o->camera, "Camera settings (default DATASET/camera.yaml)");
      cmd.add_option("--poses", o->poses, "Trajectory (TUM format) of the dataset's frames")->required();
      cmd.add_option("--world", o->world,
                     "Ground frame of the trajectory's world: zup, camera, auto, or a grid's MAP.yaml (the grid's frame)")
          ->capture_default_str();
      cmd.add_option("--camera-height", o->camera_height, "With --world camera: first camera above the floor, m");
      cmd.add_option("--region", o->region, "x0,y0,x1,y1 or a polygon x0,y0,x1,y1,x2,y2,... on the map");
      cmd.add_option("--cloud-in", o->cloud_in, "Existing cloud whose points inside the region are replaced");
      cmd.add_option("--voxel", o->build.voxel, "Voxel size, m")->capture_default_str()->check(CLI::PositiveNumber);
      cmd.add_option("--max-depth", o->build.max_depth, "Ignore depth beyond this, m")->capture_default_str()->check(CLI::PositiveNumber);
      cmd.add_option("--out", o->out, "Output cloud (binary PLY)")->required();
      return [o] { return run_cloud(*o); };
    },
    .order = 45});

}  // namespace
}  // namespace builtscene::app
