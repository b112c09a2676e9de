// Demo part "slam": the locating system on a generated lab room. The RGB-D SLAM maps one
// handheld run (accuracy against ground truth, frame rate), its keyframes build the occupancy
// grid (scored against the room's true map), the map is saved, and a second run of another
// seed and path is localized in it without changing it.
#include <chrono>
#include <iomanip>
#include <sstream>

#include <opencv2/imgcodecs.hpp>

#include "core/logging.hpp"
#include "core/settings_file.hpp"
#include "core/stage_timer.hpp"
#include "demo_registry.hpp"
#include "eval/trajectory_error.hpp"
#include "io/trajectory.hpp"
#include "io/tum_dataset.hpp"
#include "ogm/map_comparison.hpp"
#include "ogm/map_drawing.hpp"
#include "ogm/map_server_io.hpp"
#include "ogm/trajectory_mapping.hpp"
#include "slam/system.hpp"
#include "synth/rgbd_sequence_writer.hpp"

namespace builtscene::app {
namespace {

std::string fixed(double v, int digits) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(digits) << v;
  return o.str();
}

struct RunResult {
  long frames = 0, tracked = 0;
  double fps = 0;
};

// Feeds every frame of `ds` to the system; frames that cannot be read are skipped.
RunResult run_frames(slam::System& system, const TumDataset& ds) {
  RunResult r;
  const auto start = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < ds.size(); ++i) {
    const auto out = system.track_rgbd(ds.load_rgb(i), ds.load_depth(i), ds.entry(i).timestamp);
    ++r.frames;
    r.tracked += out.state == slam::TrackingState::kOk;
  }
  const double s = ms_since(start) / 1000.0;
  r.fps = s > 0 ? static_cast<double>(r.frames) / s : 0;
  system.shutdown();
  return r;
}

slam::SystemOptions options_for(const std::filesystem::path& dataset) {
  slam::SystemOptions so;
  so.orb = OrbExtractorOptions::from_settings(SettingsFile::load(dataset / "camera.yaml"));
  return so;
}

DemoSection run_slam_demo(const std::filesystem::path& dir) {
  synth::RgbdSequenceOptions a;
  a.scene = "lab-room";
  a.frames = 300;
  a.seed = 1;
  a.out = dir / "map-run";
  synth::generate_rgbd_sequence(a);
  synth::RgbdSequenceOptions b = a;
  b.frames = 200;
  b.seed = 2;
  b.out = dir / "localize-run";
  synth::generate_rgbd_sequence(b);

  // SLAM on the first run, with the saved map.
  const TumDataset run_a = TumDataset::open(a.out);
  slam::System mapper(run_a.settings(), options_for(a.out));
  const RunResult ra = run_frames(mapper, run_a);
  const Trajectory traj_a = mapper.trajectory(), keyframes = mapper.keyframe_trajectory();
  write_tum_trajectory(dir / "map-run-trajectory.txt", traj_a);
  const auto map_info = mapper.save_map(dir / "lab-room.bsmap");
  const AteResult ate_a = absolute_trajectory_error(run_a.groundtruth(), traj_a, Alignment::kSE3);

  // The occupancy grid from the SLAM's keyframes, carried into the room's frame with the
  // trajectory's alignment so that it can be scored against the true map.
  Trajectory keyframes_in_room;
  for (const auto& k : keyframes) keyframes_in_room.push_back({k.timestamp, ate_a.est_to_gt.transform_pose(k.pose)});
  TrajectoryMappingOptions mo;
  mo.world = "zup";
  const TrajectoryMappingResult grid = build_map_from_trajectory(run_a, keyframes_in_room, mo);
  save_map_server(grid.mapper.grid(), dir / "grid.yaml");
  const MapScore score = compare_maps(grid.mapper.grid(), load_map_server(a.out / "truth_map.yaml"));

  // Localization of the second run in the saved map; its error is measured in the first run's
  // alignment (the map's frame is fixed, so no new alignment is allowed).
  const TumDataset run_b = TumDataset::open(b.out);
  slam::System localizer(run_b.settings(), options_for(b.out));
  const auto loaded = localizer.load_map(dir / "lab-room.bsmap");
  localizer.set_mode(slam::Mode::kLocalization, "start");
  const RunResult rb = run_frames(localizer, run_b);
  const Trajectory traj_b_in_room = transformed(localizer.trajectory(), ate_a.est_to_gt);
  write_tum_trajectory(dir / "localize-run-trajectory.txt", localizer.trajectory());
  const AteResult ate_b = absolute_trajectory_error(run_b.groundtruth(), traj_b_in_room, Alignment::kNone);

  MapDrawing d(grid.mapper.grid(), 3);
  d.trajectory(grid.poses);
  std::vector<Pose2D> b_track;
  for (const auto& p : traj_b_in_room) b_track.push_back(grid.frame.to_2d(p.pose));
  if (!b_track.empty()) d.robot(b_track.back());
  cv::imwrite((dir / "grid.png").string(), d.image());

  DemoSection s;
  s.title = "RGB-D SLAM, live occupancy grid and localization in a saved map (generated lab room)";
  s.summary = {{"slam",
                {{"frames", ra.frames},
                 {"tracked_frames", ra.tracked},
                 {"fps", ra.fps},
                 {"keyframes", keyframes.size()},
                 {"map_points", map_info.points},
                 {"ate_rmse_m", ate_a.stats.rmse}}},
               {"grid", {{"keyframes", keyframes.size()}, {"score", to_json(score)}}},
               {"localize",
                {{"frames", rb.frames},
                 {"tracked_frames", rb.tracked},
                 {"fps", rb.fps},
                 {"map_keyframes", loaded.keyframes},
                 {"keyframes_after", localizer.keyframe_count()},
                 {"ate_rmse_m", ate_b.stats.rmse}}}};
  s.html = "<p>The SLAM (ORB features, local bundle adjustment, 1000 features at 640 x 480) mapped a handheld run of " +
           std::to_string(ra.frames) + " frames through the lab room: " + std::to_string(ra.tracked) + " tracked at " +
           fixed(ra.fps, 1) + " frames/s, " + std::to_string(keyframes.size()) + " keyframes, " +
           std::to_string(map_info.points) + " map points; trajectory error against ground truth (ATE RMSE, se3 "
           "alignment) <b>" + fixed(100 * ate_a.stats.rmse, 2) + " cm</b>.</p>" +
           "<p>Occupancy grid from the keyframes' virtual scans only (" + std::to_string(keyframes.size()) +
           " scans), against the room's true map: occupied precision <b>" + fixed(score.occupied_precision, 3) +
           "</b>, recall <b>" + fixed(score.occupied_recall, 3) + "</b>, free agreement <b>" +
           fixed(score.free_agreement, 3) + "</b>. Map saved as <code>slam/lab-room.bsmap</code>.</p>" +
           "<p>A second run (another seed and path, " + std::to_string(rb.frames) + " frames) localized in the saved map: " +
           std::to_string(rb.tracked) + " tracked at " + fixed(rb.fps, 1) + " frames/s, the map unchanged (" +
           std::to_string(loaded.keyframes) + " keyframes loaded, " + std::to_string(localizer.keyframe_count()) +
           " after), error in the map's frame <b>" +
           fixed(100 * ate_b.stats.rmse, 2) + " cm</b> RMSE.</p>" + "<img src=\"slam/grid.png\" alt=\"occupancy grid\">";
  return s;
}

const bool registered_demo_slam = register_demo_part({.name = "slam", .order = 15, .run = run_slam_demo});

}  // namespace
}  // namespace builtscene::app
