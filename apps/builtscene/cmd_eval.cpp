// `builtscene eval ate` and `builtscene eval rpe`: trajectory accuracy against ground truth.
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <optional>

#include "command_registry.hpp"
#include "core/errors.hpp"
#include "core/logging.hpp"
#include "eval/marker_detection_error.hpp"
#include "eval/marker_evaluation.hpp"
#include "eval/trajectory_error.hpp"

namespace builtscene::app {
namespace {

struct TrajectoryPairOptions {
  std::string gt, est, align = "se3";
  double max_diff = 0.02;
  std::size_t delta = 1;
  bool scale = false;
  std::string aligned_out;
  std::vector<std::string> align_from;  // {EST, GT}: fit the alignment on this other pair
};

void add_pair_options(CLI::App& cmd, TrajectoryPairOptions& o) {
  cmd.add_option("--gt", o.gt, "Ground-truth trajectory (TUM format)")->required();
  cmd.add_option("--est", o.est, "Estimated trajectory (TUM format)")->required();
  cmd.add_option("--max-diff", o.max_diff, "Largest timestamp difference for a pair, seconds")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
}

nlohmann::json run_ate(const TrajectoryPairOptions& o) {
  const Alignment align = parse_alignment(o.align);
  const Trajectory gt = read_tum_trajectory(o.gt);
  const Trajectory est = read_tum_trajectory(o.est);
  AteResult r;
  nlohmann::json j;
  if (o.align_from.empty()) {
    r = absolute_trajectory_error(gt, est, align, o.max_diff);
  } else {
    // The source's way to judge a localization run: the map's run is aligned to its ground
    // truth once, and that same transform carries the localization run into the truth's frame.
    const AteResult fit =
        absolute_trajectory_error(read_tum_trajectory(o.align_from[1]), read_tum_trajectory(o.align_from[0]), align, o.max_diff);
    r = absolute_trajectory_error(gt, transformed(est, fit.est_to_gt), Alignment::kNone, o.max_diff);
    r.est_to_gt = fit.est_to_gt;
    j["align_from"] = {{"est", o.align_from[0]}, {"gt", o.align_from[1]}, {"rmse", fit.stats.rmse}, {"pairs", fit.stats.count}};
    spdlog::info("alignment fitted on {} against {} ({} pairs, rmse {:.4f} m) and applied unchanged", o.align_from[0],
                 o.align_from[1], fit.stats.count, fit.stats.rmse);
  }
  spdlog::info("ATE ({} alignment, {} pairs): rmse {:.4f} m, mean {:.4f} m, median {:.4f} m, max {:.4f} m",
               to_string(align), r.stats.count, r.stats.rmse, r.stats.mean, r.stats.median, r.stats.max);
  j.update(to_json(r.stats));
  j["align"] = to_string(align);
  j["scale"] = r.est_to_gt.scale();
  const auto& q = r.est_to_gt.rotation();
  const auto& t = r.est_to_gt.translation();
  j["transform"] = {{"t", {t.x(), t.y(), t.z()}}, {"q_xyzw", {q.x(), q.y(), q.z(), q.w()}}, {"scale", r.est_to_gt.scale()}};
  j["gt_poses"] = gt.size();
  j["est_poses"] = est.size();
  if (!o.aligned_out.empty()) {
    // Every estimated pose (not only the paired ones) in the ground truth's frame, so maps
    // built from the estimate overlay the ground truth's maps.
    write_tum_trajectory(o.aligned_out, transformed(est, r.est_to_gt));
    j["aligned_out"] = o.aligned_out;
  }
  return j;
}

nlohmann::json run_rpe(const TrajectoryPairOptions& o) {
  const Trajectory gt = read_tum_trajectory(o.gt);
  const Trajectory est = read_tum_trajectory(o.est);
  const RpeResult r = relative_pose_error(gt, est, o.delta, o.max_diff, o.scale);
  spdlog::info("RPE (delta {} frames, {} pairs): translation rmse {:.4f} m, rotation rmse {:.3f} deg", r.delta,
               r.translation.count, r.translation.rmse, r.rotation.rmse);
  nlohmann::json j = to_json(r.translation);
  j["rotation_deg"] = to_json(r.rotation);
  j["delta"] = r.delta;
  return j;
}

struct MarkerEvalOptions {
  std::string measured, truth, align = "3d", out;
  std::vector<std::string> camera_truth;  // {LOCALIZED, TRUE}: split off the detection's own error
};

nlohmann::json run_markers(const MarkerEvalOptions& o) {
  const auto measured = read_marker_measurements(o.measured);
  const auto truth = read_marker_truth(o.truth);
  if (measured.empty()) throw InputError(o.measured + ": no marker measurements");
  // --camera-truth: worked out before anything is printed, so its bad input gives one line.
  std::optional<MarkerDetectionErrors> detection;
  if (!o.camera_truth.empty()) {
    const std::string& localized = o.camera_truth[0];
    const std::string& true_poses = o.camera_truth[1];
    const Trajectory localized_poses = read_tum_trajectory(localized), true_camera_poses = read_tum_trajectory(true_poses);
    try {
      detection = marker_detection_errors(measured, truth, localized_poses, true_camera_poses);
    } catch (const InputError& err) {
      throw InputError(o.measured + " with --camera-truth " + localized + " " + true_poses + ": " + err.what());
    }
    if (detection->without_pose > 0)
      spdlog::warn("{}: {} measurements have no pose in {} or {} (within 0.02 s) and are left out of the detection error",
                   o.measured, detection->without_pose, localized, true_poses);
  }
  const MarkerEvaluation e = evaluate_markers(measured, truth, parse_marker_alignment(o.align));
  for (int id : e.unknown_ids) spdlog::warn("{}: marker id {} is not in {}; its measurements are ignored", o.measured, id, o.truth);
  for (int id : e.unseen_ids) spdlog::warn("marker {} of {} was never measured", id, o.truth);
  if (!o.out.empty()) {
    write_marker_tables(e, o.out);
    spdlog::info("tables and plot written to {}", o.out);
  }
  std::cerr << markers_markdown(e);
  spdlog::info("{} measurements of {} markers: max position RMSE {:.3f} m, max distance RMSE {:.3f} m", e.measurements_used,
               e.markers.size() - e.unseen_ids.size(), e.max_rmse, e.max_distance_rmse);
  nlohmann::json j = to_json(e);
  if (detection) {
    std::cerr << "\n" << detection_markdown(*detection);
    spdlog::info("detection alone (true camera poses): max RMSE {:.4f} m over {} measurements", detection->max_rmse, detection->used);
    if (!o.out.empty()) std::ofstream(std::filesystem::path(o.out) / "detection.md") << detection_markdown(*detection);
    j["detection"] = to_json(*detection);
  }
  return j;
}

const bool group_eval = register_group("eval", "Accuracy evaluation against ground truth");

const bool ate = register_command({
    .path = {"eval", "ate"},
    .description = "Absolute trajectory error after alignment (TUM RGB-D benchmark style)",
    .setup = [](CLI::App& cmd) -> Action {
      auto o = std::make_shared<TrajectoryPairOptions>();
      add_pair_options(cmd, *o);
      cmd.add_option("--align", o->align, "Alignment of the estimate: se3, sim3 or none")->capture_default_str();
      cmd.add_option("--aligned-out", o->aligned_out, "Output: the estimate transformed into the ground truth's frame (TUM)");
      cmd.add_option("--align-from", o->align_from,
                     "EST GT: fit the alignment on this other run and its ground truth, and apply it to --est unchanged "
                     "(a localization run judged in its map's aligned frame)")
          ->expected(2);
      return [o] { return run_ate(*o); };
    },
    .order = 60});

const bool rpe = register_command({
    .path = {"eval", "rpe"},
    .description = "Relative pose error over a fixed frame offset",
    .setup = [](CLI::App& cmd) -> Action {
      auto o = std::make_shared<TrajectoryPairOptions>();
      add_pair_options(cmd, *o);
      cmd.add_option("--delta", o->delta, "Frame offset between the two poses of a relative motion")
          ->capture_default_str()
          ->check(CLI::PositiveNumber);
      cmd.add_flag("--correct-scale", o->scale, "Scale the estimate by the sim3 alignment's scale first");
      return [o] { return run_rpe(*o); };
    },
    .order = 61});

const bool markers = register_command({
    .path = {"eval", "markers"},
    .description = "Marker-based accuracy: measured tag positions against surveyed ones (the source's Tables 2.1, 2.2)",
    .setup = [](CLI::App& cmd) -> Action {
      auto o = std::make_shared<MarkerEvalOptions>();
      cmd.add_option("--measured", o->measured, "Measurements: frame,time,id,x,y,z,distance,angle_deg")->required();
      cmd.add_option("--truth", o->truth, "Surveyed markers: id,x,y,z[,yaw,size]")->required();
      cmd.add_option("--align", o->align, "Map-to-marker alignment: 3d, 2d or none")->capture_default_str();
      cmd.add_option("--out", o->out, "Folder for markers.md, the CSV tables and markers.png");
      cmd.add_option("--camera-truth", o->camera_truth,
                     "LOCALIZED TRUE: the trajectory the measurements were made with (localize --trajectory) and the "
                     "camera's true poses in the survey's frame (a generated world's groundtruth.txt): also report each "
                     "marker's error with the true poses, the detection's own")
          ->expected(2);
      return [o] { return run_markers(*o); };
    },
    .order = 62});

}  // namespace
}  // namespace builtscene::app
