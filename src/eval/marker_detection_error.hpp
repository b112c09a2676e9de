#pragma once
// How much of a marker's error is the detection's own, on a world whose camera poses are known
// (a generated one). Each map-frame measurement p was made as T_wc * p_c with the pose the
// localization gave its frame; taken back into the camera with that pose (p_c = T_wc^-1 p) and
// out again with the frame's true pose (T_true * p_c), it is where the detection and the tag
// pose alone put the tag in the survey's frame. What is left of the marker's error
// (evaluate_markers) is the camera pose's: the map's and the localization's.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "io/trajectory.hpp"
#include "markers/marker_measurements.hpp"

namespace builtscene {

struct MarkerDetectionError {
  int id = -1;
  std::size_t times = 0;                             // measurements whose frame both trajectories have
  Eigen::Vector3d bias = Eigen::Vector3d::Zero();    // mean error, survey frame, metres
  double rmse = 0;                                   // 3D, metres
};

struct MarkerDetectionErrors {
  std::vector<MarkerDetectionError> markers;  // surveyed markers with at least one usable measurement, by id
  std::size_t used = 0;
  std::size_t without_pose = 0;               // measurements whose time neither trajectory (or one) has
  double max_rmse = 0;
};

// `localized`: the trajectory the measurements were made with (localize --trajectory, map
// frame); `truth`: the true camera poses in the survey's frame. The two are associated as for
// `eval ate` (associate_trajectories), and a measurement takes the associated frame nearest its
// time, within max_difference seconds. Measurements of ids the survey lacks are skipped. Throws
// InputError when no measurement has a pose in both trajectories.
MarkerDetectionErrors marker_detection_errors(const std::vector<MarkerMeasurement>& measured,
                                              const std::vector<MarkerTruth>& survey, const Trajectory& localized,
                                              const Trajectory& truth, double max_difference = 0.02);

std::string detection_markdown(const MarkerDetectionErrors& d);
nlohmann::json to_json(const MarkerDetectionErrors& d);

}  // namespace builtscene
