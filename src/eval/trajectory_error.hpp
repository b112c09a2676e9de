#pragma once
// Absolute trajectory error (ATE) and relative pose error (RPE) in the manner of the TUM
// RGB-D benchmark tools: timestamps associated within max_difference, the estimate aligned to
// the ground truth (se3, sim3 or none), statistics of the translational errors.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/sim3.hpp"
#include "io/trajectory.hpp"

namespace builtscene {

enum class Alignment { kNone, kSE3, kSim3 };
Alignment parse_alignment(const std::string& name);  // "none" | "se3" | "sim3"
std::string to_string(Alignment a);

struct ErrorStats {
  double rmse = 0, mean = 0, median = 0, std = 0, min = 0, max = 0;
  std::size_t count = 0;
};
ErrorStats error_stats(const std::vector<double>& errors);

// Index pairs (gt, est) by nearest timestamp, one-to-one, within max_difference seconds.
std::vector<std::pair<std::size_t, std::size_t>> associate_trajectories(const Trajectory& gt, const Trajectory& est,
                                                                        double max_difference);

struct AteResult {
  ErrorStats stats;              // metres
  Alignment alignment = Alignment::kSE3;
  Sim3 est_to_gt;                // applied to the estimate
  std::vector<double> errors;    // per pair, in association order
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
};

// Throws InputError when fewer than 3 pairs (2 with alignment none... 1) are found.
AteResult absolute_trajectory_error(const Trajectory& gt, const Trajectory& est, Alignment alignment,
                                    double max_difference = 0.02);

// Every pose of `est` moved by a fixed transform, e.g. an earlier result's est_to_gt: a second
// run measured in the first run's aligned frame (then with Alignment::kNone), or an estimate
// written out in the ground truth's frame.
Trajectory transformed(const Trajectory& est, const Sim3& transform);

struct RpeResult {
  ErrorStats translation;  // metres per delta
  ErrorStats rotation;     // degrees per delta
  std::size_t delta = 1;
};

// Relative pose error over pose pairs (i, i+delta) of the associated sequence; no alignment
// is needed (relative motions are frame-independent), except a sim3 scale when asked.
RpeResult relative_pose_error(const Trajectory& gt, const Trajectory& est, std::size_t delta,
                              double max_difference = 0.02, bool correct_scale = false);

nlohmann::json to_json(const ErrorStats& s);

}  // namespace builtscene
