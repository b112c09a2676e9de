#pragma once
// Marker-based accuracy evaluation (the source's section 2.5): the map frame is aligned to the
// surveyed markers' frame by the best rigid transform over all markers' mean positions (3D, or
// 2D on the floor plane: the map's up axis from the plane through the measured floor markers,
// the truth's up axis z), then per marker: times measured, mean estimated and true X and Y,
// the position RMSE over all measurements (horizontal, as the source's Table 2.1) and the
// spread (repeatability); and for consecutive markers (and the closing pair) the distance
// RMSE over all pairs of their measurements (Table 2.2).
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/sim3.hpp"
#include "markers/marker_measurements.hpp"

namespace builtscene {

enum class MarkerAlignment { k3D, k2D, kNone };
MarkerAlignment parse_marker_alignment(const std::string& name);  // 3d | 2d | none

struct MarkerResult {
  int id = -1;
  std::size_t times = 0;
  Eigen::Vector3d mean_estimate = Eigen::Vector3d::Zero();  // aligned, truth frame
  Eigen::Vector3d truth = Eigen::Vector3d::Zero();
  Eigen::Vector3d stddev = Eigen::Vector3d::Zero();         // of the aligned measurements
  double rmse = 0;                                          // horizontal, metres
  double rmse_3d = 0;
};

struct MarkerDistanceResult {
  int from = -1, to = -1;
  double estimated = 0, truth = 0, rmse = 0;  // horizontal distances
  std::size_t pairs = 0;
};

struct MarkerEvaluation {
  std::vector<MarkerResult> markers;          // every true marker, in the truth file's order
  std::vector<MarkerDistanceResult> distances;
  std::vector<int> unknown_ids;               // measured ids the truth lacks (ignored)
  std::vector<int> unseen_ids;                // true markers never measured
  MarkerAlignment alignment = MarkerAlignment::k3D;
  Sim3 map_to_truth;
  bool up_from_markers = false;               // 2d: the map's up axis is the markers' plane (else its z)
  std::size_t measurements_used = 0;
  double max_rmse = 0, max_distance_rmse = 0;
};

// Throws InputError when alignment needs more measured markers than there are (3 for 3d,
// 2 for 2d); `evaluate_markers_unaligned` still gives the repeatability then.
MarkerEvaluation evaluate_markers(const std::vector<MarkerMeasurement>& measured, const std::vector<MarkerTruth>& truth,
                                  MarkerAlignment alignment);

std::string markers_markdown(const MarkerEvaluation& e);
nlohmann::json to_json(const MarkerEvaluation& e);
void write_marker_tables(const MarkerEvaluation& e, const std::filesystem::path& dir);  // CSV, Markdown, PNG

}  // namespace builtscene
