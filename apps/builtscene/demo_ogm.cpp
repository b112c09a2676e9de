// Demo part "ogm": a generated lab room driven by a robot; from its ground-truth poses an
// occupancy grid (scored against the room's true map), an A* path across it, and the floor
// markers measured and evaluated. Ground-truth poses on purpose: this part shows the mapping,
// planning and marker chains' own error; the "slam" part builds a grid from the SLAM's poses.
#include <fstream>
#include <iomanip>
#include <sstream>

#include <opencv2/imgcodecs.hpp>

#include "core/errors.hpp"
#include "core/logging.hpp"
#include "demo_registry.hpp"
#include "eval/marker_evaluation.hpp"
#include "nav/astar_planner.hpp"
#include "ogm/map_comparison.hpp"
#include "ogm/map_drawing.hpp"
#include "ogm/map_server_io.hpp"
#include "ogm/trajectory_mapping.hpp"
#include "synth/rgbd_sequence_writer.hpp"

namespace builtscene::app {
namespace {

std::string fmt3(double v) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(3) << v;
  return o.str();
}

DemoSection run_ogm_demo(const std::filesystem::path& dir) {
  synth::RgbdSequenceOptions so;
  so.scene = "lab-room";
  so.motion = synth::MotionKind::Robot;
  so.frames = 450;
  so.out = dir / "lab-room";
  synth::generate_rgbd_sequence(so);

  const TumDataset ds = TumDataset::open(so.out);
  TrajectoryMappingOptions mo;
  mo.world = "auto";  // estimated from the depth images, not told
  const TrajectoryMappingResult r = build_map_from_trajectory(ds, ds.groundtruth(), mo);
  const OccupancyGrid grid = r.mapper.grid();
  save_map_server(grid, dir / "map.yaml");
  const MapScore score = compare_maps(grid, load_map_server(so.out / "truth_map.yaml"));

  // A path from the robot's start to the far corner of the room's free space.
  const Costmap costmap(grid, {});
  const AStarPlanner planner(costmap);
  // Start from the first pose of the drive whose cell the costmap lets the robot stand on
  // (the very first cells may still be unknown: the camera looks ahead, not down).
  Eigen::Vector2d start(r.poses.front().x, r.poses.front().y);
  for (const auto& p : r.poses)
    if (costmap.traversable(grid.cell_of({p.x, p.y}), false)) {
      start = {p.x, p.y};
      break;
    }
  PlanResult plan;
  Eigen::Vector2d goal = start;
  for (int row = grid.height() - 1; row >= 0 && !plan.found; --row)
    for (int col = grid.width() - 1; col >= 0 && !plan.found; col -= 7)
      if (costmap.traversable({col, row}, false) && (grid.center_of({col, row}) - start).norm() > 3.0) {
        goal = grid.center_of({col, row});
        try {
          plan = planner.plan(start, goal);
        } catch (const InputError&) {
          break;  // no traversable start: report "none found"
        }
      }
  MapDrawing d(grid, 3);
  d.trajectory(r.poses);
  if (plan.found) d.path(plan.points);
  d.robot(r.poses.back());
  d.scan(r.poses.back(), r.last_scan);
  cv::imwrite((dir / "map.png").string(), d.image());

  // Floor markers measured along the ground-truth trajectory.
  std::map<int, double> sizes;
  const auto truth = read_marker_truth(so.out / "markers.csv");
  for (const auto& t : truth) sizes[t.id] = t.size;
  const MarkerObserver observer(ds.settings().camera, 0.0, sizes);
  std::vector<MarkerMeasurement> ms;
  const PosedFrames posed = associate_poses(ds, ds.groundtruth(), 0.02);
  for (std::size_t k = 0; k < posed.frames.size(); k += 3) {
    const auto m = observer.observe(posed.frames[k], ds.entry(posed.frames[k]).timestamp, ds.load_rgb(posed.frames[k]),
                                    ds.load_depth(posed.frames[k]), posed.poses[k]);
    ms.insert(ms.end(), m.begin(), m.end());
  }
  nlohmann::json markers_json;
  std::string markers_html = "<p>No floor marker was in view.</p>";
  if (!ms.empty()) {
    const MarkerEvaluation e = evaluate_markers(ms, truth, MarkerAlignment::kNone);
    markers_json = to_json(e);
    markers_html = "<p>" + std::to_string(ms.size()) + " marker measurements (ground-truth poses, so this is the "
                   "measurement chain's own error): largest position RMSE " + fmt3(e.max_rmse) + " m.</p>";
  }

  DemoSection s;
  s.title = "Occupancy grid, path planning and floor markers (generated lab room)";
  s.summary = {{"frames", ds.size()}, {"scans", r.frames.size()}, {"score", to_json(score)},
               {"plan", {{"found", plan.found}, {"length_m", plan.length_m}, {"cells_expanded", plan.cells_expanded}}},
               {"markers", markers_json}, {"stage_ms", r.timer.summary()}};
  s.html = "<p>A robot drove " + std::to_string(ds.size()) +
           " frames through a generated 6 x 8 m lab room (Kinect-like noise). From its poses and virtual "
           "laser scans (height band 0.05-1.3 m, so desk tops count) the occupancy grid below was built; the "
           "floor plane and up axis were estimated from the depth images. Against the room's true map "
           "(1-cell tolerance): occupied precision <b>" + fmt3(score.occupied_precision) + "</b>, recall <b>" +
           fmt3(score.occupied_recall) + "</b>, free agreement <b>" + fmt3(score.free_agreement) + "</b>.</p>" +
           "<p>A* path (orange, robot radius 0.3 m): " + (plan.found ? fmt3(plan.length_m) + " m, " +
           std::to_string(plan.cells_expanded) + " cells expanded" : std::string("none found")) + ".</p>" +
           markers_html + "<img src=\"ogm/map.png\" alt=\"occupancy grid\">";
  return s;
}

const bool registered_demo_ogm = register_demo_part({.name = "ogm", .order = 20, .run = run_ogm_demo});

}  // namespace
}  // namespace builtscene::app
