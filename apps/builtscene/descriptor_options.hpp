#pragma once
// The descriptor options `slam` and `localize` share (--descriptor, --saft-weights,
// --saft-mode, ...) and the per-frame tracking diagnostics both report: the inlier ratios
// after the initial pose and after local-map tracking (the source's Figure 3.13), and for
// SAFT the online learning's statistics.
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "slam/system.hpp"

namespace builtscene::app {

struct DescriptorOptions {
  std::string descriptor = "orb";
  std::filesystem::path saft_weights;
  std::string saft_mode = "offline";
  double saft_learning_rate = 1e-4;
  double saft_target_accuracy = 0.98;
  double saft_anchor = 1.0;
  bool saft_handover_check = false;
  bool saft_calibrate_decision = false;
  std::filesystem::path saft_weights_out;
  std::filesystem::path inliers_out;

  void add_to(CLI::App& cmd);
  // Fills the descriptor fields of `so`; InputError on a bad value.
  void apply(slam::SystemOptions& so) const;
  // Probes the output files (fail before the run, not after it).
  void check_outputs() const;
};

// One row per frame; written as CSV and summarized in JSON.
class TrackingDiagnostics {
 public:
  void add(long frame, double timestamp, const slam::TrackingOutcome& out, long weight_updates);
  void write_csv(const std::filesystem::path& path) const;  // no-op for an empty path
  // Medians of the two inlier ratios, and with SAFT the learning statistics and the
  // frames per weight update; the final weights go to `weights_out` when given.
  nlohmann::json summary(slam::System& system, const DescriptorOptions& opt) const;

 private:
  struct Row {
    long frame;
    double timestamp;
    int initial_matches, initial_inliers, local_matches, local_inliers;
    long weight_updates;
  };
  std::vector<Row> rows_;
};

}  // namespace builtscene::app
