// `builtscene localize`: localization mode in a saved map. Each frame is relocalized until
// tracking finds the map, then tracked against it; the map does not change. Writes the
// trajectory of the tracked frames.
//
// Per-frame consumers (occupancy-grid display, 2D poses, points of interest, marker
// measurements) hook in as FrameObservers: each gets every processed frame with its index,
// timestamp, tracked flag, camera-to-world pose and depth image, in frame order.
#include <chrono>
#include <fstream>
#include <functional>
#include <memory>
#include <optional>

#include "cli_parsing.hpp"
#include "command_registry.hpp"
#include "descriptor_options.hpp"
#include "core/errors.hpp"
#include "core/logging.hpp"
#include "core/progress.hpp"
#include "core/settings_file.hpp"
#include "io/trajectory.hpp"
#include "io/tum_dataset.hpp"
#include "localize_outputs.hpp"
#include "rgbd_frame_reader.hpp"
#include "localized_frame.hpp"
#include "slam/system.hpp"

namespace builtscene::app {
namespace {

struct LocalizeOptions {
  std::filesystem::path dataset, camera, map, trajectory, vocabulary;
  long max_frames = 0;
  std::optional<double> planar_pitch_deg;  // --planar-motion
  LocalizeOutputOptions outputs;
  DescriptorOptions features;
};

nlohmann::json run_localize(const LocalizeOptions& opt) {
  const TumDataset data = TumDataset::open(opt.dataset, opt.camera);
  const auto camera_file = opt.camera.empty() ? opt.dataset / "camera.yaml" : opt.camera;
  slam::SystemOptions so;
  so.orb = OrbExtractorOptions::from_settings(SettingsFile::load(camera_file));
  so.vocabulary = opt.vocabulary;
  if (opt.planar_pitch_deg) so.planar = slam::PlanarMotion::from_pitch(*opt.planar_pitch_deg);
  opt.features.apply(so);
  opt.features.check_outputs();
  check_output_file(opt.trajectory);
  slam::System system(data.settings(), so);
  const auto load_start = std::chrono::steady_clock::now();
  const auto info = system.load_map(opt.map);
  system.timer().add("map_load", ms_since(load_start));
  spdlog::info("map {}: {} keyframes, {} map points", opt.map.string(), info.keyframes, info.points);
  system.set_mode(slam::Mode::kLocalization, "start");

  // Consumers of the per-frame results; commands built on localization add theirs here.
  // The outputs open their files now, so a bad path fails before the run.
  LocalizeOutputs outputs(opt.outputs, data.settings().camera);
  std::vector<FrameObserver> observers{[&outputs](const LocalizedFrame& f) { outputs.observe(f); }};

  const std::size_t n = opt.max_frames > 0 ? std::min<std::size_t>(data.size(), static_cast<std::size_t>(opt.max_frames))
                                           : data.size();
  long tracked = 0, lost = 0;
  TrackingDiagnostics diagnostics;
  RgbdFrameReader frames(data, n);
  Progress progress("localize", n);
  const auto start = std::chrono::steady_clock::now();
  while (const auto f = frames.next()) {
    progress.update(f->index);
    const std::size_t i = f->index;
    const auto out = system.track_rgbd(f->rgb, f->depth, f->timestamp);
    const bool ok = out.state == slam::TrackingState::kOk;
    diagnostics.add(static_cast<long>(i), f->timestamp, out, system.saft_learning() ? system.saft_learning()->stats().weight_updates : 0);
    if (ok) ++tracked;
    else ++lost;
    if (!observers.empty()) {
      const LocalizedFrame frame{i, f->timestamp, ok, ok ? system.last_pose() : std::nullopt, f->rgb, f->depth};
      for (const auto& observe : observers) observe(frame);
    }
  }
  progress.finish();
  const double wall_s = ms_since(start) / 1000.0;
  system.shutdown();

  const Trajectory traj = system.trajectory();
  if (!opt.trajectory.empty()) write_tum_trajectory(opt.trajectory, traj);
  const long processed = frames.delivered();
  diagnostics.write_csv(opt.features.inliers_out);
  nlohmann::json switches = nlohmann::json::array();
  for (const auto& sw : system.mode_switches())
    switches.push_back({{"frame", sw.frame}, {"from", slam::to_string(sw.from)}, {"to", slam::to_string(sw.to)},
                        {"reason", sw.reason}});
  nlohmann::json j = {
      {"frames", n},
      {"processed_frames", processed},
      {"tracked_frames", tracked},
      {"lost_frames", lost},
      {"relocalizations",
       {{"count", system.relocalized_frames().size()},
        {"frames", system.relocalized_frames()},
        {"while_on_odometry", system.odometry_relocalizations()},
        {"attempts", system.relocalization_attempts()}}},
      {"first_relocalized_frame", system.first_relocalized_frame() >= 0 ? nlohmann::json(system.first_relocalized_frame())
                                                                         : nlohmann::json(nullptr)},
      {"bad_input", frames.bad_input()},
      {"map", {{"path", opt.map.string()}, {"keyframes", info.keyframes}, {"map_points", info.points}}},
      {"keyframes_after", system.keyframe_count()},
      {"map_points_after", system.map_point_count()},
      {"mode_switches", switches},
      {"fps", wall_s > 0 ? static_cast<double>(processed) / wall_s : 0.0},
      {"wall_seconds", wall_s},
      {"stage_ms", system.timer().summary()},
      {"trajectory", opt.trajectory.string()},
      {"trajectory_poses", traj.size()},
      {"features", diagnostics.summary(system, opt.features)},
  };
  // The outputs' summaries (ogm, poi_events, markers) join the run's.
  const auto output_summary = outputs.finish();
  for (const auto& [key, value] : output_summary.items()) j[key] = value;
  spdlog::info("localize: {} frames, {} tracked, {} lost, {} relocalizations, {:.1f} fps", n, tracked, lost,
               system.relocalized_frames().size(), j["fps"].get<double>());
  return j;
}

const bool registered_localize = register_command({
    .path = {"localize"},
    .description = "Localization mode in a saved map: relocalize, then track every frame; the map is not changed",
    .setup = [](CLI::App& cmd) -> Action {
      auto opt = std::make_shared<LocalizeOptions>();
      cmd.add_option("--dataset", opt->dataset, "TUM RGB-D layout folder")->required();
      cmd.add_option("--map", opt->map, "Saved map (builtscene slam --map-out)")->required();
      cmd.add_option("--camera", opt->camera, "Camera settings (default DATASET/camera.yaml)");
      cmd.add_option("--trajectory", opt->trajectory, "Output: TUM trajectory of the tracked frames");
      cmd.add_option("--max-frames", opt->max_frames, "Only the first N frames (0 = all)");
      cmd.add_option("--planar-motion", opt->planar_pitch_deg,
                     "Ground robot: the camera keeps its height and tilt over a flat floor; its pitch below the "
                     "horizontal in degrees (as the map was built with)")
          ->check(CLI::Range(-89.0, 89.0));
      cmd.add_option("--vocabulary", opt->vocabulary,
                     "Bag-of-words vocabulary (default: the shipped one; must be the map's)");
      opt->outputs.add_to(cmd);
      opt->features.add_to(cmd);
      return [opt] { return run_localize(*opt); };
    },
    .order = 41});

}  // namespace
}  // namespace builtscene::app
