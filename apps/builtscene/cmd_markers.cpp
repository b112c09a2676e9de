// `builtscene markers measure`: AprilTag positions in the map frame from a dataset and a
// trajectory (any locating system's, or ground truth), as `localize --markers-out` logs them.
#include <memory>

#include "command_registry.hpp"
#include "core/errors.hpp"
#include "core/logging.hpp"
#include "core/progress.hpp"
#include "core/stage_timer.hpp"
#include "markers/marker_measurements.hpp"
#include "ogm/trajectory_mapping.hpp"

namespace builtscene::app {
namespace {

struct MeasureOptions {
  std::string dataset, camera, poses, out, sizes_from, family = "tag36h11";
  double tag_size = 0, max_distance = 4.0;
  int upsample = 1, stride = 1;
};

nlohmann::json run_measure(const MeasureOptions& o) {
  std::map<int, double> sizes;
  if (!o.sizes_from.empty())
    for (const auto& t : read_marker_truth(o.sizes_from))
      if (t.size > 0) sizes[t.id] = t.size;
  const TumDataset ds = TumDataset::open(o.dataset, o.camera);
  const PosedFrames posed = associate_poses(ds, read_tum_trajectory(o.poses), 0.02);
  AprilTagOptions ao;
  ao.family = o.family;
  ao.upsample = o.upsample;
  const MarkerObserver observer(ds.settings().camera, o.tag_size, sizes, ao, o.max_distance);
  std::vector<MarkerMeasurement> all;
  StageTimer timer;
  std::size_t skipped = 0;
  Progress progress("markers", posed.frames.size());
  for (std::size_t k = 0; k < posed.frames.size(); k += static_cast<std::size_t>(std::max(1, o.stride))) {
    const std::size_t f = posed.frames[k];
    cv::Mat rgb, depth;
    try {
      auto t = timer.scope("load");
      rgb = ds.load_rgb(f);
      depth = ds.load_depth(f);
    } catch (const InputError& e) {
      ++skipped;
      spdlog::warn("skipping frame {}: {}", f, e.what());
      continue;
    }
    auto t = timer.scope("detect_and_pose");
    const auto ms = observer.observe(f, ds.entry(f).timestamp, rgb, depth, posed.poses[k]);
    all.insert(all.end(), ms.begin(), ms.end());
    progress.update(k + 1);
  }
  write_marker_measurements(o.out, all);
  std::map<int, int> per_id;
  for (const auto& m : all) ++per_id[m.id];
  spdlog::info("{} measurements of {} markers written to {}", all.size(), per_id.size(), o.out);
  nlohmann::json ids = nlohmann::json::object();
  for (const auto& [id, n] : per_id) ids[std::to_string(id)] = n;
  return {{"measurements", all.size()}, {"markers", per_id.size()}, {"per_marker", ids},
          {"frames", posed.frames.size()}, {"skipped_frames", skipped}, {"stage_ms", timer.summary()}};
}

const bool group_markers = register_group("markers", "AprilTag markers: measurement for accuracy evaluation");

const bool measure = register_command({
    .path = {"markers", "measure"},
    .description = "Measure AprilTag positions in the map frame from a dataset and its trajectory",
    .setup = [](CLI::App& cmd) -> Action {
      auto o = std::make_shared<MeasureOptions>();
      cmd.add_option("--dataset", o->dataset, "TUM-layout RGB-D folder")->required();
      cmd.add_option("--camera", o->camera, "Camera settings (default DATASET/camera.yaml)");
      cmd.add_option("--poses", o->poses, "Trajectory of the camera in the map (TUM format)")->required();
      cmd.add_option("--tag-size", o->tag_size, "Edge of the tags' black square, metres");
      cmd.add_option("--sizes-from", o->sizes_from, "Survey CSV (id,x,y,z,yaw,size) giving each tag's size");
      cmd.add_option("--tag-family", o->family, "AprilTag family")->capture_default_str();
      cmd.add_option("--tag-upsample", o->upsample, "Detect on an upsampled image (2 finds smaller tags)")->capture_default_str()->check(CLI::Range(1, 3));
      cmd.add_option("--max-distance", o->max_distance, "Ignore tags farther than this, metres")->capture_default_str();
      cmd.add_option("--stride", o->stride, "Use every n-th frame")->capture_default_str()->check(CLI::PositiveNumber);
      cmd.add_option("--out", o->out, "Measurements CSV")->required();
      return [o] { return run_measure(*o); };
    },
    .order = 50});

}  // namespace
}  // namespace builtscene::app
