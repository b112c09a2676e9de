// `builtscene ogm build`: an occupancy grid map from a dataset and a trajectory;
// `builtscene ogm compare`: score a map against a ground-truth map.
#include <cstdio>
#include <memory>

#include "command_registry.hpp"
#include "core/errors.hpp"
#include "core/logging.hpp"
#include "eval/trajectory_error.hpp"
#include "ogm/grid_resampling.hpp"
#include "ogm/map_comparison.hpp"
#include "ogm/map_drawing.hpp"
#include "ogm/map_server_io.hpp"
#include "ogm/trajectory_mapping.hpp"

namespace builtscene::app {
namespace {

struct BuildOptions {
  std::string dataset, camera, poses, out, truth, png, model = "source";
  std::filesystem::path frame_images;
  TrajectoryMappingOptions mapping;
};

std::filesystem::path yaml_path(const std::string& out) {
  std::filesystem::path p = out;
  if (p.extension() != ".yaml") p += ".yaml";
  return p;
}

nlohmann::json run_build(BuildOptions o) {
  if (o.model == "source") o.mapping.mapper.model = OccupancyMapperOptions::Model::kSource;
  else if (o.model == "inverse-sensor") o.mapping.mapper.model = OccupancyMapperOptions::Model::kInverseSensor;
  else throw InputError("--model: unknown model '" + o.model + "' (expected source or inverse-sensor)");
  const TumDataset ds = TumDataset::open(o.dataset, o.camera);
  const Trajectory traj = read_tum_trajectory(o.poses);
  if (!o.frame_images.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(o.frame_images, ec);
    if (ec) throw InputError(located(o.frame_images, 0, "cannot create the folder: " + ec.message()));
    // The grid as it grows, one picture per integrated frame (the source's per-keyframe figures).
    o.mapping.after_frame = [dir = o.frame_images](const TrajectoryMappingResult& so_far) {
      char name[32];
      std::snprintf(name, sizeof name, "frame_%06zu.png", so_far.frames.back());
      write_track_picture(dir / name, so_far.mapper.grid(), so_far.poses, &so_far.last_scan);
    };
  }
  const TrajectoryMappingResult r = build_map_from_trajectory(ds, traj, o.mapping);
  const OccupancyGrid grid = r.mapper.grid();
  const auto yaml = yaml_path(o.out);
  save_map_server(grid, yaml);
  append_ground_frame(yaml, r.frame.T_gw());
  auto state = yaml;
  state.replace_extension(".state");
  r.mapper.save_state(state);
  const std::string png = o.png.empty() ? (std::filesystem::path(yaml).replace_extension(".png")).string() : o.png;
  write_track_picture(png, grid, r.poses, &r.last_scan);
  const auto& Tg = r.frame.T_gw();
  nlohmann::json j = {{"map", yaml.string()},
                      {"state", state.string()},
                      {"png", png},
                      {"frames", ds.size()},
                      {"scans", r.frames.size()},
                      {"skipped_frames", r.skipped_frames},
                      {"width", grid.width()},
                      {"height", grid.height()},
                      {"resolution", grid.resolution()},
                      {"origin", {grid.origin().x(), grid.origin().y()}},
                      {"world", o.mapping.world},
                      {"ground_from_world",
                       {{"t", {Tg.translation().x(), Tg.translation().y(), Tg.translation().z()}},
                        {"q_xyzw", {Tg.rotation().x(), Tg.rotation().y(), Tg.rotation().z(), Tg.rotation().w()}}}},
                      {"stage_ms", r.timer.summary()}};
  if (!o.truth.empty()) {
    const MapScore s = compare_maps(grid, load_map_server(o.truth));
    j["score"] = to_json(s);
    spdlog::info("against {}: occupied precision {:.3f}, recall {:.3f}, free agreement {:.3f}", o.truth,
                 s.occupied_precision, s.occupied_recall, s.free_agreement);
  }
  spdlog::info("map {} ({} x {} cells) from {} scans; picture {}", yaml.string(), grid.width(), grid.height(),
               r.frames.size(), png);
  return j;
}

struct CompareOptions {
  std::string map, truth, est, gt;
  int tolerance = 1;
};

// A grid built beside a SLAM lies in a ground frame of the SLAM's world; the truth map in the
// ground truth's z-up world. With --est/--gt the grid is carried over: ground -> SLAM world
// (the grid's ground_frame_T_gw) -> ground-truth world (the SE3 alignment of the estimated
// trajectory to the ground truth), in the floor plane, before it is scored.
nlohmann::json run_compare(const CompareOptions& o) {
  if (o.est.empty() != o.gt.empty()) throw InputError("--est and --gt go together (the grid's trajectory and its ground truth)");
  OccupancyGrid map = load_map_server(o.map);
  const OccupancyGrid truth = load_map_server(o.truth);
  nlohmann::json aligned;
  if (!o.est.empty()) {
    const auto T_gw = read_ground_frame(o.map);
    if (!T_gw)
      throw InputError(located(o.map, 0, "ground_frame_T_gw: missing (needed with --est/--gt to carry the grid into the ground truth's world)"));
    const AteResult ate = absolute_trajectory_error(read_tum_trajectory(o.gt), read_tum_trajectory(o.est), Alignment::kSE3);
    const SE3 T_tw(ate.est_to_gt.rotation(), ate.est_to_gt.translation());
    const Pose2D T = planar_part(T_tw * T_gw->inverse());
    map = resample_grid(map, T, truth);
    aligned = {{"pairs", ate.stats.count}, {"ate_rmse", ate.stats.rmse}, {"x", T.x}, {"y", T.y}, {"theta", T.theta}};
  }
  const MapScore s = compare_maps(map, truth, o.tolerance);
  spdlog::info("occupied precision {:.3f}, recall {:.3f}, free agreement {:.3f}", s.occupied_precision,
               s.occupied_recall, s.free_agreement);
  nlohmann::json j = to_json(s);
  j["tolerance_cells"] = o.tolerance;
  if (!aligned.is_null()) j["aligned"] = aligned;
  return j;
}

const bool group_ogm = register_group("ogm", "Occupancy grid maps from virtual laser scans");

const bool build = register_command({
    .path = {"ogm", "build"},
    .description = "Build an occupancy grid map from a dataset and a trajectory (ground truth or SLAM)",
    .setup = [](CLI::App& cmd) -> Action {
      auto o = std::make_shared<BuildOptions>();
      auto& m = o->mapping;
      cmd.add_option("--dataset", o->dataset, "TUM-layout RGB-D folder")->required();
      cmd.add_option("--camera", o->camera, "Camera settings (default DATASET/camera.yaml)");
      cmd.add_option("--poses", o->poses, "Trajectory, TUM format, camera in world")->required();
      cmd.add_option("--out", o->out, "Output map (MAP.yaml + MAP.pgm + MAP.state + MAP.png)")->required();
      cmd.add_flag("--keyframes-only", m.keyframes_only, "Integrate only frames that moved enough (0.2 m / 15 deg)");
      cmd.add_option("--world", m.world,
                     "Ground frame of the trajectory's world: zup, camera, auto, or a grid's MAP.yaml (the grid's frame)")
          ->capture_default_str();
      cmd.add_option("--camera-height", m.camera_height, "With --world camera: first camera above the floor, m")->capture_default_str();
      cmd.add_option("--min-height", m.scan.min_height, "Scan band bottom above the floor, m")->capture_default_str();
      cmd.add_option("--max-height", m.scan.max_height, "Scan band top above the floor, m")->capture_default_str();
      cmd.add_option("--range-max", m.scan.range_max, "Largest scan range, m")->capture_default_str();
      cmd.add_option("--resolution", m.mapper.resolution, "Cell size, m")->capture_default_str()->check(CLI::PositiveNumber);
      cmd.add_option("--model", o->model, "Update model: source or inverse-sensor")->capture_default_str();
      cmd.add_option("--truth", o->truth, "Ground-truth map_server YAML to score against");
      cmd.add_option("--png", o->png, "Picture (default MAP.png)");
      cmd.add_option("--frame-images", o->frame_images,
                     "Output folder: a picture of the grid after each integrated frame (frame_NNNNNN.png)");
      return [o] { return run_build(*o); };
    },
    .order = 30});

const bool compare = register_command({
    .path = {"ogm", "compare"},
    .description = "Score an occupancy grid map against a ground-truth map",
    .setup = [](CLI::App& cmd) -> Action {
      auto o = std::make_shared<CompareOptions>();
      cmd.add_option("--map", o->map, "Estimated map_server YAML")->required();
      cmd.add_option("--truth", o->truth, "Ground-truth map_server YAML")->required();
      cmd.add_option("--tolerance", o->tolerance, "Tolerance in cells")->capture_default_str()->check(CLI::NonNegativeNumber);
      cmd.add_option("--est", o->est,
                     "The trajectory of the grid's world (TUM; e.g. the SLAM's keyframes): with --gt, the grid is "
                     "carried into the ground truth's world before scoring");
      cmd.add_option("--gt", o->gt, "Ground-truth trajectory (TUM) in the truth map's z-up world");
      return [o] { return run_compare(*o); };
    },
    .order = 31});

}  // namespace
}  // namespace builtscene::app
