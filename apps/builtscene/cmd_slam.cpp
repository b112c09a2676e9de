// `builtscene slam`: RGB-D SLAM over a TUM-layout sequence; writes the trajectory of every
// tracked frame and the keyframe trajectory (TUM format); optionally starts from a saved map
// (--map-in), saves the map (--map-out), and switches between SLAM and localization mode by
// frame range (--mode-schedule) or by region on the ground plane (--slam-region).
#include <optional>
#include <chrono>
#include <cmath>
#include <fstream>
#include <memory>

#include "cli_parsing.hpp"
#include "command_registry.hpp"
#include "descriptor_options.hpp"
#include "rgbd_frame_reader.hpp"
#include "core/errors.hpp"
#include "core/logging.hpp"
#include "core/progress.hpp"
#include "core/settings_file.hpp"
#include "io/trajectory.hpp"
#include "io/tum_dataset.hpp"
#include "nav/region.hpp"
#include "ogm/ground_frame.hpp"
#include "slam/map.hpp"
#include "slam/map_points_csv.hpp"
#include "slam/system.hpp"
#include "slam_ogm_output.hpp"

namespace builtscene::app {
namespace {

struct SlamOptions {
  std::filesystem::path dataset;
  std::filesystem::path camera;
  std::filesystem::path trajectory;
  std::filesystem::path keyframes;
  long max_frames = 0;
  bool sync_mapping = false;
  std::filesystem::path map_in, map_out, map_points_out;
  std::string mode = "slam", mode_schedule, slam_region, world = "camera";
  double camera_height = 1.0;
  std::filesystem::path vocabulary;
  bool no_relocalization = false;
  bool no_loop_closing = false;
  bool depth_links = false;
  double depth_link_weight = 1.0;
  bool depth_planes = slam::PlaneLandmarkOptions{}.enabled;
  double depth_plane_weight = 1.0;
  double motion_prior_cm = 0, motion_prior_deg = 0.3;
  double depth_prior = slam::TrackingOptions{}.depth_prior_weight;
  int depth_prior_below = slam::TrackingOptions{}.depth_prior_below_inliers;
  int bridge_local_map = -1;  // --bridge-local-map
  int global_ba_iterations = slam::LoopClosingOptions{}.global_ba_iterations;
  bool no_final_ba = false;
  bool no_close_at_end = false;
  bool adaptive_ba_disparity = false;
  double bridge_link_cm = slam::BridgeLinkOptions{}.sigma_m * 100.0;
  double bridge_link_deg = slam::BridgeLinkOptions{}.sigma_deg;
  double min_parallax_sigmas = slam::LocalMappingOptions{}.min_parallax_sigmas;
  std::optional<double> planar_pitch_deg;  // --planar-motion
  SlamOgmOptions ogm;
  DescriptorOptions features;
};

// The mode plan from the command line; the region is on the ground plane of the map's world.
slam::ModePlan make_mode_plan(const SlamOptions& opt) {
  slam::ModePlan plan;
  if (!opt.mode_schedule.empty()) plan.set_schedule(slam::ModeSchedule::parse(opt.mode_schedule));
  if (!opt.slam_region.empty()) {
    const Region region = Region::parse(opt.slam_region, "--slam-region");
    GroundFrame ground;
    if (!parse_ground_frame(opt.world, opt.camera_height, ground) || opt.world == "auto")
      throw InputError("--world: '" + opt.world + "' must be zup, camera or a grid's .yaml for --slam-region");
    plan.set_region([region, ground](const SE3& T_wc) {
      const Pose2D p = ground.to_2d(T_wc);
      return region.contains({p.x, p.y});
    });
  }
  return plan;
}

nlohmann::json run_slam(const SlamOptions& opt) {
  for (const auto& [flag, value] : {std::pair{"--motion-prior", opt.motion_prior_cm},
                                     std::pair{"--motion-prior-deg", opt.motion_prior_deg},
                                     std::pair{"--depth-link-weight", opt.depth_link_weight},
                                     std::pair{"--depth-plane-weight", opt.depth_plane_weight},
                                     std::pair{"--depth-prior", opt.depth_prior},
                                     std::pair{"--min-parallax-sigmas", opt.min_parallax_sigmas},
                                     std::pair{"--bridge-link-cm", opt.bridge_link_cm},
                                     std::pair{"--bridge-link-deg", opt.bridge_link_deg}})
    if (!std::isfinite(value)) throw InputError(std::string(flag) + ": not a number");
  slam::SystemOptions so;
  opt.features.apply(so);  // the descriptor flags, checked before the dataset is read
  const TumDataset data = TumDataset::open(opt.dataset, opt.camera);
  const auto camera_file = opt.camera.empty() ? opt.dataset / "camera.yaml" : opt.camera;
  so.orb = OrbExtractorOptions::from_settings(SettingsFile::load(camera_file));
  so.mapping_thread = !opt.sync_mapping;
  so.vocabulary = opt.vocabulary;
  so.relocalization = !opt.no_relocalization;
  so.loop_closing = !opt.no_loop_closing;
  so.tracking.depth_links = opt.depth_links;
  so.tracking.depth_link_weight = opt.depth_link_weight;
  so.planes.enabled = opt.depth_planes;
  so.planes.sigma_rad /= std::sqrt(opt.depth_plane_weight);
  so.planes.sigma_m /= std::sqrt(opt.depth_plane_weight);
  so.tracking.depth_prior_weight = opt.depth_prior;
  so.tracking.depth_prior_below_inliers = opt.depth_prior_below;
  so.tracking.bridge_local_map_inliers = opt.bridge_local_map;
  so.loop.global_ba_iterations = opt.global_ba_iterations;
  so.loop.final_bundle_adjustment = !opt.no_final_ba;
  so.loop.close_at_end = !opt.no_close_at_end;
  so.mapping.ba_disparity.adaptive = opt.adaptive_ba_disparity;
  so.loop.bridge_links.sigma_m = opt.bridge_link_cm / 100.0;
  so.loop.bridge_links.sigma_deg = opt.bridge_link_deg;
  so.mapping.min_parallax_sigmas = opt.min_parallax_sigmas;
  if (opt.planar_pitch_deg) so.planar = slam::PlanarMotion::from_pitch(*opt.planar_pitch_deg);
  if (opt.motion_prior_cm > 0) {
    so.tracking.motion_prior = true;
    so.tracking.motion_prior_sigma_m = opt.motion_prior_cm / 100.0;
    so.tracking.motion_prior_sigma_rad = opt.motion_prior_deg * M_PI / 180.0;
  }
  so.saft_learning.synchronous = opt.sync_mapping;  // reproducible: learning inline too
  opt.features.check_outputs();
  // Fail on an unwritable output before spending minutes on the sequence.
  const auto start_mode = slam::parse_mode(opt.mode);
  if (!start_mode) throw InputError("--mode: '" + opt.mode + "' must be slam or localize");
  const slam::ModePlan plan = make_mode_plan(opt);
  for (const auto& out : {opt.trajectory, opt.keyframes, opt.map_out, opt.map_points_out}) check_output_file(out);

  std::optional<SlamOgmOutput> ogm;
  if (opt.ogm.enabled()) {
    SlamOgmOptions ogm_options = opt.ogm;
    ogm_options.camera_height = opt.camera_height;  // one --camera-height for the region and the grid
    ogm.emplace(ogm_options, data.settings().camera);
  }
  slam::System system(data.settings(), so);
  if (ogm) ogm->subscribe(system);
  nlohmann::json map_in_json = nullptr;
  if (!opt.map_in.empty()) {
    const auto t0 = std::chrono::steady_clock::now();
    const auto info = system.load_map(opt.map_in);
    system.timer().add("map_load", ms_since(t0));
    spdlog::info("map {}: {} keyframes, {} map points loaded", opt.map_in.string(), info.keyframes, info.points);
    map_in_json = {{"path", opt.map_in.string()}, {"keyframes", info.keyframes}, {"map_points", info.points}};
  }
  system.set_mode(*start_mode, "start");
  const std::size_t n = opt.max_frames > 0 ? std::min<std::size_t>(data.size(), static_cast<std::size_t>(opt.max_frames))
                                           : data.size();
  long tracked = 0, lost = 0, lost_events = 0, not_initialized = 0, no_features = 0;
  bool was_ok = false;
  TrackingDiagnostics diagnostics;
  RgbdFrameReader frames(data, n);
  Progress progress("slam", n);
  const auto start = std::chrono::steady_clock::now();
  while (const auto f = frames.next()) {
    progress.update(f->index);
    const std::size_t i = f->index;
    if (const auto d = plan.decide(static_cast<long>(i), system.last_pose())) system.set_mode(d->mode, d->reason);
    const auto out = system.track_rgbd(f->rgb, f->depth, f->timestamp);
    if (ogm) ogm->after_frame(system, out, f->timestamp, f->depth);
    diagnostics.add(static_cast<long>(i), f->timestamp, out, system.saft_learning() ? system.saft_learning()->stats().weight_updates : 0);
    if (out.keypoints < 20) ++no_features;
    if (out.state == slam::TrackingState::kOk) {
      ++tracked;
      was_ok = true;
    } else if (out.state == slam::TrackingState::kLost) {
      ++lost;
      if (was_ok) {
        ++lost_events;
        spdlog::warn("frame {} ({:.6f}): tracking lost", i, f->timestamp);
      }
      was_ok = false;
    } else {
      ++not_initialized;
    }
  }
  progress.finish();
  const double wall_s = ms_since(start) / 1000.0;
  system.shutdown();

  const Trajectory traj = system.trajectory();
  write_tum_trajectory(opt.trajectory, traj);
  if (!opt.keyframes.empty()) write_tum_trajectory(opt.keyframes, system.keyframe_trajectory());
  nlohmann::json map_out_json = nullptr;
  if (!opt.map_out.empty()) {
    const auto t0 = std::chrono::steady_clock::now();
    const auto info = system.save_map(opt.map_out);
    system.timer().add("map_save", ms_since(t0));
    spdlog::info("map {}: {} keyframes, {} map points, {} bytes saved", opt.map_out.string(), info.keyframes,
                 info.points, info.bytes);
    map_out_json = {{"path", opt.map_out.string()}, {"keyframes", info.keyframes}, {"map_points", info.points},
                    {"bytes", info.bytes}};
  }
  nlohmann::json map_points_json = nullptr;
  if (!opt.map_points_out.empty()) {
    const auto info = slam::write_map_points_csv(system.map(), opt.map_points_out);
    map_points_json = {{"path", opt.map_points_out.string()}, {"points", info.points}, {"rows", info.rows}};
  }
  nlohmann::json switches = nlohmann::json::array();
  for (const auto& sw : system.mode_switches())
    switches.push_back({{"frame", sw.frame}, {"timestamp", sw.timestamp}, {"from", slam::to_string(sw.from)},
                        {"to", slam::to_string(sw.to)}, {"reason", sw.reason}});

  const nlohmann::json ogm_summary = ogm ? ogm->finish(system) : nlohmann::json();
  diagnostics.write_csv(opt.features.inliers_out);
  const nlohmann::json features_summary = diagnostics.summary(system, opt.features);
  const auto stats = system.mapping_stats();
  const auto relocalized = system.relocalized_frames();
  const long processed = frames.delivered();
  nlohmann::json bad_input = frames.bad_input();
  bad_input["no_features"] = no_features;
  const double frame_median = system.timer().median_ms("frame");
  nlohmann::json loop_frames = nlohmann::json::array(), loop_list = nlohmann::json::array();
  for (const auto& e : system.loop_events()) {
    if (e.stage != slam::LoopEvent::Stage::kPoseGraph) continue;
    loop_frames.push_back(e.frame);
    const double angle = Eigen::AngleAxisd(e.correction.rotation()).angle();
    nlohmann::json matched_timestamp = nullptr;
    for (const auto& k : e.keyframes)
      if (k.id == e.matched_keyframe) matched_timestamp = k.timestamp;
    loop_list.push_back({{"frame", e.frame},
                         {"timestamp", e.timestamp},
                         {"keyframe", e.keyframe},
                         {"matched_keyframe", e.matched_keyframe},
                         {"matched_timestamp", matched_timestamp},
                         {"inliers", e.inliers},
                         {"correction_m", e.correction.translation().norm()},
                         {"correction_deg", angle * 180.0 / M_PI}});
  }
  const auto lc = system.loop_closing_stats();
  nlohmann::json j = {
      {"frames", n},
      {"processed_frames", processed},
      {"tracked_frames", tracked},
      {"lost_frames", lost + not_initialized},
      {"not_initialized_frames", not_initialized},
      {"lost_events", lost_events},
      {"bad_input", bad_input},
      {"keyframes", system.keyframe_count()},
      {"map_points", system.map_point_count()},
      {"fps", wall_s > 0 ? static_cast<double>(processed) / wall_s : 0.0},
      {"tracking_fps_median", frame_median > 0 ? 1000.0 / frame_median : 0.0},
      {"wall_seconds", wall_s},
      {"local_mapping",
       {{"keyframes_processed", stats.keyframes_processed},
        {"keyframes_culled", stats.keyframes_culled},
        {"points_culled", stats.points_culled},
        {"points_fused", stats.points_fused},
        {"points_triangulated", stats.points_triangulated},
        {"bundle_adjustments", stats.bundle_adjustments},
        {"bundle_adjustments_aborted", stats.bundle_adjustments_aborted},
        {"bundle_adjustments_measured_disparity", stats.bundle_adjustments_measured_disparity},
        {"bundle_adjustments_not_held", stats.bundle_adjustments_not_held},
        {"ba_disparity_sigma_mean", stats.bundle_adjustments_measured_disparity > 0
                                        ? stats.ba_disparity_sigma_sum /
                                              static_cast<double>(stats.bundle_adjustments_measured_disparity)
                                        : 0.0},
        {"max_queue", stats.max_queue}}},
      {"relocalizations",
       {{"count", relocalized.size()}, {"frames", relocalized}, {"attempts", system.relocalization_attempts()}}},
      {"depth_odometry_frames", system.depth_odometry_frames()},
      {"depth_odometry_prior_frames", system.depth_odometry_prior_frames()},
      {"loops", {{"count", loop_frames.size()}, {"frames", loop_frames}, {"events", loop_list}}},
      {"loop_closing",
       {{"enabled", system.loop_closing_enabled()},
        {"keyframes_checked", lc.keyframes_checked},
        {"consistent_candidates", lc.consistent_candidates},
        {"end_candidates", lc.end_candidates},
        {"loops_closed_at_end", lc.loops_closed_at_end},
        {"rejected", lc.rejected},
        {"rejected_anchored", lc.rejected_anchored},
        {"rejected_implausible", lc.rejected_implausible},
        {"points_fused", lc.points_fused},
        {"planes_merged", lc.planes_merged},
        {"global_ba_runs", lc.global_ba_runs},
        {"final_ba_runs", lc.final_ba_runs},
        {"final_ba_aborted", lc.final_ba_aborted},
        {"final_ba_disparity_sigma", lc.final_ba_disparity_sigma},
        {"final_ba_measured_disparity_sigma", lc.final_ba_measured_disparity_sigma},
        {"global_ba_aborted", lc.global_ba_aborted},
        {"global_ba_merged", lc.global_ba_merged},
        {"max_pose_graph_parts", lc.max_pose_graph_parts}}},
      {"vocabulary", system.vocabulary() ? so.vocabulary.empty() ? slam::default_vocabulary_path(so.descriptor).string() : so.vocabulary.string() : ""},
      {"features", features_summary},
      {"mode_switches", switches},
      {"map_in", map_in_json},
      {"map_out", map_out_json},
      {"map_points_out", map_points_json},
      {"stage_ms", system.timer().summary()},
      {"trajectory", opt.trajectory.string()},
      {"trajectory_poses", traj.size()},
  };
  if (ogm) j["ogm"] = ogm_summary;
  if (system.planar().enabled) {
    const auto& up = system.planar().up_c;
    const auto& floor = system.floor_plane();
    j["planar_motion"] = {{"up_c", {up.x(), up.y(), up.z()}},
                          {"from", floor ? "floor" : "pitch"},
                          {"floor_height_m", floor ? nlohmann::json(floor->height_m) : nlohmann::json(nullptr)}};
  }
  if (opt.depth_planes) {
    std::lock_guard lock(system.map().mutex());
    std::size_t measured = 0, associated = 0, observers = 0;
    for (const auto& kf : system.map().keyframes()) {
      measured += kf->planes.size();
      for (const auto& p : kf->planes) associated += p.landmark != nullptr;
    }
    for (const auto& p : system.map().planes()) observers += p->observers.size();
    j["plane_landmarks"] = {{"planes", system.map().planes().size()},
                            {"keyframe_planes", measured},
                            {"associated", associated},
                            {"observations_per_plane", system.map().planes().empty() ? 0.0
                                                       : static_cast<double>(observers) / static_cast<double>(system.map().planes().size())}};
  }
  spdlog::info("slam: {} frames, {} tracked, {} lost, {} keyframes, {} map points, {:.1f} fps", n, tracked,
               lost + not_initialized, system.keyframe_count(), system.map_point_count(), j["fps"].get<double>());
  return j;
}

const bool registered_slam = register_command({
    .path = {"slam"},
    .description = "RGB-D SLAM on a TUM-layout sequence: trajectory of every tracked frame and keyframes",
    .setup = [](CLI::App& cmd) -> Action {
      auto opt = std::make_shared<SlamOptions>();
      cmd.add_option("--dataset", opt->dataset, "TUM RGB-D layout folder")->required();
      cmd.add_option("--camera", opt->camera, "Camera settings (default DATASET/camera.yaml)");
      cmd.add_option("--trajectory", opt->trajectory, "Output: TUM trajectory of tracked frames")->required();
      cmd.add_option("--keyframes", opt->keyframes, "Output: TUM trajectory of the keyframes");
      cmd.add_option("--max-frames", opt->max_frames, "Only the first N frames (0 = all)");
      cmd.add_flag("--sync-mapping", opt->sync_mapping,
                   "Run local mapping (and SAFT online learning) inline instead of in their threads (deterministic, slower)");
      cmd.add_option("--map-in", opt->map_in, "Saved map to start from (tracking relocalizes in it, then extends it)");
      cmd.add_option("--map-out", opt->map_out, "Output: the map at the end (binary, see docs/slam.md)");
      cmd.add_option("--map-points-out", opt->map_points_out,
                     "Output: CSV of the map's points at the end, one row per keyframe observing each (position, "
                     "keypoint, pyramid level, depth reading; see docs/slam.md)");
      cmd.add_option("--mode", opt->mode, "Mode at the start: slam or localize")->capture_default_str();
      cmd.add_option("--mode-schedule", opt->mode_schedule,
                     "Modes by frame range, e.g. 0-199:slam,200-399:localize (open end: 400-:slam)");
      cmd.add_option("--slam-region", opt->slam_region,
                     "SLAM mode while the camera is inside x0,y0,x1,y1 (or a polygon) on the ground plane, "
                     "localization outside");
      cmd.add_option("--world", opt->world,
                     "Ground plane of --slam-region: camera (first camera, --camera-height), zup, "
                     "or a grid's MAP.yaml (regions on that grid)")
          ->capture_default_str();
      cmd.add_option("--camera-height", opt->camera_height,
                     "With --world camera or --ogm-world camera: first camera above the floor, m")
          ->capture_default_str();
      cmd.add_option("--vocabulary", opt->vocabulary,
                     "Bag-of-words vocabulary for relocalization (default: the shipped data/vocab/orb_k10_L4.bsvoc, "
                     "saft_k10_L4.bsvoc with --descriptor saft)");
      opt->features.add_to(cmd);
      cmd.add_flag("--no-relocalization", opt->no_relocalization,
                   "When lost, only match the last reference keyframe (no place recognition)");
      cmd.add_flag("--no-loop-closing", opt->no_loop_closing,
                   "No loop detection and correction (the map drifts freely; for comparison)");
      cmd.add_flag("--depth-links", opt->depth_links,
                   "Experimental: align consecutive keyframes' depth images (ICP) and add the relative poses "
                   "to bundle adjustment (off by default: better on the corridor and lab room, worse on the office and the real kitchen; docs/slam.md)");
      cmd.add_option("--depth-link-weight", opt->depth_link_weight,
                     "With --depth-links: scale of the links' information (1 = independent 1 cm depth noise)")
          ->capture_default_str()
          ->check(CLI::Range(1e-6, 1e6));
      cmd.add_flag("--depth-planes,!--no-depth-planes", opt->depth_planes,
                   "The walls, floor and ceiling in each keyframe's depth become plane landmarks shared by the "
                   "keyframes that see them, held in bundle adjustment (on by default; docs/slam.md, \"Plane landmarks\")");
      cmd.add_option("--depth-plane-weight", opt->depth_plane_weight,
                     "Scale of the plane landmarks' information (1 = 0.29 degrees and 1 cm per keyframe)")
          ->capture_default_str()
          ->check(CLI::Range(1e-6, 1e6));
      cmd.add_option("--motion-prior", opt->motion_prior_cm,
                     "Experimental: hold each frame's pose to the motion model's prediction with this standard "
                     "deviation in cm (0 = off; docs/slam.md)")
          ->check(CLI::Range(0.0, 100.0));
      cmd.add_option("--motion-prior-deg", opt->motion_prior_deg, "... and this one in degrees")
          ->capture_default_str()
          ->check(CLI::Range(0.001, 45.0));
      cmd.add_option("--depth-prior", opt->depth_prior,
                     "Align the frame's depth to the newest keyframe's (ICP) and hold the pose to it with the ICP's "
                     "information times this weight, where features are few (0 = off; docs/slam.md)")
          ->capture_default_str()
          ->check(CLI::Range(0.0, 1e6));
      cmd.add_option("--planar-motion", opt->planar_pitch_deg,
                     "Ground robot: the camera keeps its height and tilt over a flat floor; its pitch below the "
                     "horizontal in degrees (docs/slam.md, \"Planar motion\")")
          ->check(CLI::Range(-89.0, 89.0));
      cmd.add_option("--bridge-local-map", opt->bridge_local_map,
                     "After a frame the depth odometry carried, search the local map from its pose and keep the "
                     "result when it has this many map inliers (0 = off; default: 10 with --planar-motion, else off; "
                     "docs/slam.md)")
          ->check(CLI::Range(0, 1000));
      cmd.add_option("--global-ba-iterations", opt->global_ba_iterations,
                     "Solver iterations of the global bundle adjustment after each loop closure, in each of its "
                     "two phases (robust, then after removing outliers)")
          ->capture_default_str()
          ->check(CLI::Range(1, 1000));
      cmd.add_flag("--no-final-ba", opt->no_final_ba,
                   "Skip the final bundle adjustment a run that closed a loop ends with (the depth readings weighed "
                   "by the disparity noise the map shows; docs/slam.md, \"The final bundle adjustment\")");
      cmd.add_flag("--no-close-at-end", opt->no_close_at_end,
                   "Do not close a loop at the end of the run whose place was recognised on every keyframe but one "
                   "too few to be confirmed (it still passes every geometric check; docs/slam.md, \"The loop at "
                   "the end of a run\")");
      cmd.add_flag("--adaptive-ba-disparity", opt->adaptive_ba_disparity,
                   "Local bundle adjustment weighs the depth readings at 1.6 times the noise its window's readings "
                   "show (0.1 px to DisparitySigma) where every free keyframe is held through shared points "
                   "(docs/slam.md, \"Local bundle adjustment at the noise its window shows\")");
      cmd.add_option("--bridge-link-cm", opt->bridge_link_cm,
                     "Global BA holds the pose between the keyframes either side of a stretch the depth odometry "
                     "carried (a featureless turn) to its value after the pose graph, with this standard deviation "
                     "in cm (0 = off; docs/slam.md, \"Bridge links\")")
          ->capture_default_str()
          ->check(CLI::Range(0.0, 1e4));
      cmd.add_option("--bridge-link-deg", opt->bridge_link_deg, "... and this one in degrees")
          ->capture_default_str()
          ->check(CLI::Range(0.001, 180.0));
      cmd.add_option("--min-parallax-sigmas", opt->min_parallax_sigmas,
                     "Triangulate two rays only when their parallax is at least this many times its own standard "
                     "error (0 = ORB-SLAM's 1.15 degrees alone; 12 removes a 1 % range bias but can starve "
                     "weakly textured stretches; docs/slam.md)")
          ->capture_default_str()
          ->check(CLI::Range(0.0, 100.0));
      cmd.add_option("--depth-prior-below", opt->depth_prior_below,
                     "... only after a frame with fewer map inliers than this (0 = every frame)")
          ->capture_default_str()
          ->check(CLI::NonNegativeNumber);
      cmd.add_option("--ogm-out", opt->ogm.out,
                     "Output: occupancy grid built live from keyframes (MAP.yaml, .pgm, .state, .png)");
      cmd.add_option("--ogm-world", opt->ogm.world,
                     "Ground plane of the grid: auto (floor in the first keyframe's depth) or camera (first camera level)")
          ->capture_default_str();
      cmd.add_option("--ogm-frames", opt->ogm.frames,
                     "Output folder: a picture of the grid after each keyframe (keyframe_NNNNN.png)");
      cmd.add_option("--ogm-loop-snapshots", opt->ogm.loop_snapshots,
                     "Output folder: the grid just before and just after each loop-closure rebuild "
                     "(loop_N_before/after.yaml with the keyframe poses it was built from, loop_N_*_keyframes.txt)");
      cmd.add_option("--ogm-every", opt->ogm.batches.full_batch_every,
                     "Rebuild the grid from all keyframes every N keyframes (0 = only after loops and at the end)")
          ->capture_default_str()
          ->check(CLI::NonNegativeNumber);
      cmd.add_option("--lcm", opt->ogm.lcm_url,
                     "Publish PosesAndLaserScans on POSES_AND_LASER_SCANS and loop closures on LOOP_EVENTS over this LCM URL (udpm://..., file://LOG?mode=w)");
      return [opt] { return run_slam(*opt); };
    },
    .order = 40});

}  // namespace
}  // namespace builtscene::app
